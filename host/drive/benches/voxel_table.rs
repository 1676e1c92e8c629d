//! The local map's voxel table: our own open addressing (linear probing, backward-shift
//! deletion, as in `core/src/local_map/`) against hashbrown's `HashTable` living in a
//! fixed arena (a bump allocator over one `Vec<u8>`, through allocator-api2, sized once for
//! the capacity and never grown).
//!
//! Both tables replay the same workload, recorded from a real odometry run: per frame, the
//! find-or-insert of the voxel of every merge-cloud point (in the world frame, in the map
//! update's order), the 27-neighbour lookups of every registration point at its registered
//! pose, and the pruning of voxels beyond `r_max` from the sensor. Values are what the map
//! keeps per voxel (first block, point count). Both use the same key hash.
//!
//! Data: `KISS_ODOM_BENCH_SEQ` (a generated sequence, e.g. `kiss-odom simulate --profile urban`;
//! long enough for pruning to happen), else kitti-mini sequence 05; `KISS_ODOM_BENCH_FRAMES`
//! frames at most (default 300). Besides criterion's times (throughput in table operations),
//! it prints bytes per voxel, drops, in-place rehashes, the slowest frame and whether the
//! iteration order is reproducible.

mod common;

use allocator_api2::alloc::{AllocError, Allocator};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use hashbrown::HashTable;
use kiss_odom_core::stages::{
    point_to_voxel, scratch_words_for, table_hash, voxel_downsample, VoxelKey, NEIGHBOUR_SHIFTS,
};
use kiss_odom_core::{Capacities, Point};
use std::alloc::Layout;
use std::cell::Cell;
use std::hint::black_box;
use std::ptr::NonNull;
use std::time::{Duration, Instant};

/// Voxel capacity of both tables (full scale).
const CAPACITY: usize = Capacities::FULL_SCALE.map_voxels;
const N_MAX: u8 = 20;
const R_MAX: f64 = 100.0;

/// One frame of recorded table operations.
struct FrameOps {
    inserts: Vec<VoxelKey>,
    lookups: Vec<VoxelKey>,
    origin: [f64; 3],
}

fn record_workload() -> Option<Vec<FrameOps>> {
    let max: usize = std::env::var("KISS_ODOM_BENCH_FRAMES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(300);
    let path = std::env::var_os("KISS_ODOM_BENCH_SEQ")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| common::kitti_mini().join("sequences/05"));
    eprintln!("voxel_table: recording from {}", path.display());
    let scans = common::load(&path, max)?;
    let rec = common::record(&scans);
    let mut source = vec![[0.0f64; 3]; Capacities::FULL_SCALE.source_points];
    let mut scratch = vec![0u64; scratch_words_for(source.len())];
    let frames = rec
        .merge
        .iter()
        .zip(&rec.poses)
        .map(|(merge, pose)| {
            let s = voxel_downsample(merge, 1.5, &mut source, &mut scratch)
                .unwrap()
                .kept;
            let key = |p: &[f64; 3]| point_to_voxel(&(pose * Point::from(*p)), 1.0);
            FrameOps {
                inserts: merge.iter().map(key).collect(),
                lookups: source[..s].iter().map(key).collect(),
                origin: pose.translation.vector.into(),
            }
        })
        .collect();
    Some(frames)
}

/// Whether a voxel stays in the map: its centre within `r_max` of the sensor.
fn keep(k: &VoxelKey, o: &[f64; 3]) -> bool {
    let d2: f64 = (0..3)
        .map(|a| {
            let c = k[a] as f64 + 0.5 - o[a];
            c * c
        })
        .sum();
    d2 < R_MAX * R_MAX
}

/// What a table must do for the map.
trait VoxelTable {
    /// Finds `k` (counting one more point, up to `N_MAX`) or inserts it with `head`; false if
    /// the table is full.
    fn upsert(&mut self, k: VoxelKey, head: u32) -> bool;
    /// The voxel's (first block, count).
    fn get(&self, k: &VoxelKey) -> Option<(u32, u8)>;
    /// Removes voxels far from `o`; returns how many.
    fn prune(&mut self, o: &[f64; 3]) -> usize;
    /// Voxels held.
    fn len(&self) -> usize;
    /// Keys in iteration order.
    fn keys(&self, f: &mut dyn FnMut(&VoxelKey));
}

// ------------------------------------------------------------------------------------------
// Our table: a line-for-line replica of the voxel table in core/src/local_map/ (`view.rs`
// finds a key, `update.rs` inserts and removes).

struct Own {
    keys: Vec<VoxelKey>,
    heads: Vec<u32>,
    counts: Vec<u8>,
    mask: usize,
    len: usize,
    max: usize,
}

impl Own {
    fn new(capacity: usize) -> Self {
        let slots = ((capacity * 4).div_ceil(3)).next_power_of_two();
        Self {
            keys: vec![[0; 3]; slots],
            heads: vec![0; slots],
            counts: vec![0; slots],
            mask: slots - 1,
            len: 0,
            max: capacity.min(slots / 4 * 3),
        }
    }
    fn bytes(&self) -> usize {
        self.keys.len() * (12 + 4 + 1)
    }
    fn find(&self, k: &VoxelKey) -> Option<usize> {
        let mut i = table_hash(k) as usize & self.mask;
        loop {
            if self.counts[i] == 0 {
                return None;
            }
            if self.keys[i] == *k {
                return Some(i);
            }
            i = (i + 1) & self.mask;
        }
    }
    fn remove_slot(&mut self, mut hole: usize) {
        self.len -= 1;
        self.counts[hole] = 0;
        let mut j = hole;
        loop {
            j = (j + 1) & self.mask;
            if self.counts[j] == 0 {
                return;
            }
            let home = table_hash(&self.keys[j]) as usize & self.mask;
            let stays = if hole <= j {
                hole < home && home <= j
            } else {
                hole < home || home <= j
            };
            if !stays {
                self.keys[hole] = self.keys[j];
                self.heads[hole] = self.heads[j];
                self.counts[hole] = self.counts[j];
                self.counts[j] = 0;
                hole = j;
            }
        }
    }
}

impl VoxelTable for Own {
    fn upsert(&mut self, k: VoxelKey, head: u32) -> bool {
        let mut i = table_hash(&k) as usize & self.mask;
        loop {
            if self.counts[i] == 0 {
                break;
            }
            if self.keys[i] == k {
                self.counts[i] = (self.counts[i] + 1).min(N_MAX);
                return true;
            }
            i = (i + 1) & self.mask;
        }
        if self.len >= self.max {
            return false;
        }
        self.keys[i] = k;
        self.heads[i] = head;
        self.counts[i] = 1;
        self.len += 1;
        true
    }
    fn get(&self, k: &VoxelKey) -> Option<(u32, u8)> {
        self.find(k).map(|i| (self.heads[i], self.counts[i]))
    }
    fn prune(&mut self, o: &[f64; 3]) -> usize {
        let mut removed = 0;
        let mut i = 0;
        while i <= self.mask {
            while self.counts[i] != 0 && !keep(&self.keys[i], o) {
                self.remove_slot(i);
                removed += 1;
            }
            i += 1;
        }
        removed
    }
    fn len(&self) -> usize {
        self.len
    }
    fn keys(&self, f: &mut dyn FnMut(&VoxelKey)) {
        for i in 0..=self.mask {
            if self.counts[i] != 0 {
                f(&self.keys[i]);
            }
        }
    }
}

// ------------------------------------------------------------------------------------------
// hashbrown's HashTable over a fixed arena.

/// A bump allocator over one caller-provided buffer: allocation moves a cursor, freeing does
/// nothing, and running out is an `AllocError` (never a call to the global allocator).
struct Bump {
    base: NonNull<u8>,
    size: usize,
    used: Cell<usize>,
    _buf: Vec<u8>,
}

impl Bump {
    fn new(size: usize) -> Self {
        let mut buf = vec![0u8; size.max(1)];
        let base = NonNull::new(buf.as_mut_ptr()).unwrap();
        Self {
            base,
            size,
            used: Cell::new(0),
            _buf: buf,
        }
    }
}

// SAFETY: every block handed out lies inside `_buf`, which lives as long as `Bump` and is never
// touched otherwise; blocks never overlap because the cursor only moves forward.
unsafe impl Allocator for &Bump {
    fn allocate(&self, layout: Layout) -> Result<NonNull<[u8]>, AllocError> {
        let addr = self.base.as_ptr() as usize + self.used.get();
        let start = addr.next_multiple_of(layout.align()) - self.base.as_ptr() as usize;
        let end = start.checked_add(layout.size()).ok_or(AllocError)?;
        if end > self.size {
            return Err(AllocError);
        }
        self.used.set(end);
        // SAFETY: start <= end <= size, inside the buffer.
        let ptr = unsafe { self.base.as_ptr().add(start) };
        Ok(NonNull::slice_from_raw_parts(
            NonNull::new(ptr).ok_or(AllocError)?,
            layout.size(),
        ))
    }
    unsafe fn deallocate(&self, _ptr: NonNull<u8>, _layout: Layout) {}
}

#[derive(Clone, Copy)]
struct Entry {
    key: VoxelKey,
    head: u32,
    count: u8,
}

/// hashbrown takes its 7-bit tags from the top of a 64-bit hash: spread our 32-bit hash there.
fn hash64(k: &VoxelKey) -> u64 {
    u64::from(table_hash(k)).wrapping_mul(0x9E37_79B9_7F4A_7C15)
}

struct Brown<'a> {
    table: HashTable<Entry, &'a Bump>,
    rehashes: usize,
}

/// Bytes hashbrown's `HashTable::with_capacity_in(capacity)` takes (measured on a probe arena).
fn hashbrown_bytes(capacity: usize) -> usize {
    let probe = Bump::new(capacity * 64 + 4096);
    let t: HashTable<Entry, &Bump> = HashTable::with_capacity_in(capacity, &probe);
    drop(t);
    probe.used.get()
}

impl<'a> Brown<'a> {
    fn new(capacity: usize, arena: &'a Bump) -> Self {
        Self {
            table: HashTable::with_capacity_in(capacity, arena),
            rehashes: 0,
        }
    }
}

impl VoxelTable for Brown<'_> {
    fn upsert(&mut self, k: VoxelKey, head: u32) -> bool {
        let h = hash64(&k);
        if let Some(e) = self.table.find_mut(h, |e| e.key == k) {
            e.count = (e.count + 1).min(N_MAX);
            return true;
        }
        if self.table.len() >= self.table.capacity() {
            // No growth left: tombstones may be reclaimed by an in-place rehash (no allocation);
            // a real resize needs memory the arena does not have, so the voxel is dropped.
            if self.table.try_reserve(1, |e| hash64(&e.key)).is_err() {
                return false;
            }
            self.rehashes += 1;
        }
        self.table.insert_unique(
            h,
            Entry {
                key: k,
                head,
                count: 1,
            },
            |e| hash64(&e.key),
        );
        true
    }
    fn get(&self, k: &VoxelKey) -> Option<(u32, u8)> {
        self.table
            .find(hash64(k), |e| e.key == *k)
            .map(|e| (e.head, e.count))
    }
    fn prune(&mut self, o: &[f64; 3]) -> usize {
        let before = self.table.len();
        self.table.retain(|e| keep(&e.key, o));
        before - self.table.len()
    }
    fn len(&self) -> usize {
        self.table.len()
    }
    fn keys(&self, f: &mut dyn FnMut(&VoxelKey)) {
        for e in self.table.iter() {
            f(&e.key);
        }
    }
}

// ------------------------------------------------------------------------------------------
// Replay.

#[derive(Clone, Copy, Debug, Default)]
struct Phases {
    insert: Duration,
    lookup: Duration,
    prune: Duration,
    worst_frame: Duration,
    dropped: usize,
    found: u64,
    order: u64,
}

fn fnv(h: &mut u64, k: &VoxelKey) {
    for c in k {
        for b in c.to_le_bytes() {
            *h = (*h ^ b as u64).wrapping_mul(0x100_0000_01b3);
        }
    }
}

/// Replays the workload; with `order`, fingerprints the iteration order after every frame.
fn replay(t: &mut dyn VoxelTable, ops: &[FrameOps], order: bool) -> Phases {
    let mut ph = Phases {
        order: 0xcbf2_9ce4_8422_2325,
        ..Phases::default()
    };
    let mut head = 0u32;
    for f in ops {
        let t0 = Instant::now();
        for k in &f.inserts {
            head = head.wrapping_add(1);
            if !t.upsert(*k, head) {
                ph.dropped += 1;
            }
        }
        let t1 = Instant::now();
        let mut found = 0u64;
        for k in &f.lookups {
            for s in NEIGHBOUR_SHIFTS.iter() {
                if let Some((h, c)) = t.get(&[k[0] + s[0], k[1] + s[1], k[2] + s[2]]) {
                    found += u64::from(h) + u64::from(c);
                }
            }
        }
        let t2 = Instant::now();
        t.prune(&f.origin);
        let t3 = Instant::now();
        ph.insert += t1 - t0;
        ph.lookup += t2 - t1;
        ph.prune += t3 - t2;
        ph.worst_frame = ph.worst_frame.max(t3 - t0);
        ph.found = ph.found.wrapping_add(black_box(found));
        if order {
            let mut h = ph.order;
            t.keys(&mut |k| fnv(&mut h, k));
            ph.order = h;
        }
    }
    ph
}

fn voxel_table(c: &mut Criterion) {
    let Some(ops) = record_workload() else {
        return;
    };
    let inserts: usize = ops.iter().map(|f| f.inserts.len()).sum();
    let lookups: usize = ops.iter().map(|f| f.lookups.len() * 27).sum();
    let frames = ops.len();
    let arena_bytes = hashbrown_bytes(CAPACITY);

    // Correctness, memory and determinism, outside criterion.
    let own_a = replay(&mut Own::new(CAPACITY), &ops, true);
    let own_b = replay(&mut Own::new(CAPACITY), &ops, true);
    let arena = Bump::new(arena_bytes);
    let mut brown = Brown::new(CAPACITY, &arena);
    let br_a = replay(&mut brown, &ops, true);
    let (rehashes, brown_cap) = (brown.rehashes, brown.table.capacity());
    drop(brown);
    let arena2 = Bump::new(arena_bytes);
    let br_b = replay(&mut Brown::new(CAPACITY, &arena2), &ops, true);
    assert_eq!(
        own_a.found, br_a.found,
        "both tables answer the lookups alike"
    );
    let mut peak = Own::new(CAPACITY);
    let mut most = 0;
    for f in &ops {
        for k in &f.inserts {
            peak.upsert(*k, 0);
        }
        most = most.max(peak.len());
        peak.prune(&f.origin);
    }
    let own_bytes = Own::new(CAPACITY).bytes();
    println!(
        "voxel_table: {frames} frames, {inserts} find-or-inserts, {lookups} lookups, at most \
         {most} voxels; capacity {CAPACITY} voxels"
    );
    for (name, bytes, a, b, extra) in [
        (
            "own",
            own_bytes,
            own_a,
            own_b,
            String::from("no rehash ever"),
        ),
        (
            "hashbrown",
            arena_bytes,
            br_a,
            br_b,
            format!("{rehashes} in-place rehashes; capacity() {brown_cap} after the run"),
        ),
    ] {
        println!(
            "voxel_table/{name}: {bytes} B ({:.1} B per voxel of capacity); dropped {}; \
             slowest frame {:.3} ms; iteration order reproducible: {} (fingerprint {:016x}); {extra}",
            bytes as f64 / CAPACITY as f64,
            a.dropped,
            a.worst_frame.as_secs_f64() * 1e3,
            a.order == b.order,
            a.order,
        );
    }
    println!(
        "voxel_table: the two tables iterate in {} order",
        if own_a.order == br_a.order {
            "the same"
        } else {
            "different"
        }
    );

    let mut g = c.benchmark_group("voxel_table");
    g.sample_size(10).measurement_time(Duration::from_secs(8));
    for (phase, n) in [("insert", inserts), ("lookup", lookups), ("prune", frames)] {
        g.throughput(Throughput::Elements(n as u64));
        let pick = |p: &Phases| match phase {
            "insert" => p.insert,
            "lookup" => p.lookup,
            _ => p.prune,
        };
        g.bench_function(format!("own/{phase}"), |b| {
            b.iter_custom(|iters| {
                (0..iters)
                    .map(|_| pick(&replay(&mut Own::new(CAPACITY), &ops, false)))
                    .sum()
            })
        });
        g.bench_function(format!("hashbrown/{phase}"), |b| {
            b.iter_custom(|iters| {
                (0..iters)
                    .map(|_| {
                        let arena = Bump::new(arena_bytes);
                        let mut t = Brown::new(CAPACITY, &arena);
                        pick(&replay(&mut t, &ops, false))
                    })
                    .sum()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, voxel_table);
criterion_main!(benches);
