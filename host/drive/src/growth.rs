//! A host's storage grows instead of dropping: the bound belongs to the board.
//!
//! With capacities sized from the configuration (none named), the core refuses a frame that
//! would drop or evict anything (`WhenFull::Refuse`), and the driver moves it into storage
//! whose short capacities are doubled (or raised to what the frame needs, if more), then
//! registers the frame again: the poses are those of a run that had the larger storage from
//! the start. Growth stops at a memory limit on the core's state (`[runtime] memory_limit`,
//! `runtime.memory_limit`; by default [`DEFAULT_SHARE`] of the machine's memory); past it the core's
//! fixed-storage rule acts (a full map evicts its farthest voxels) and the run warns once.
//! Named or explicit capacities never grow.

use kiss_odom_core::Capacities;

/// The share of the machine's memory (`MemTotal`) the core's state may grow to by default.
pub const DEFAULT_SHARE: (u64, u64) = (1, 4);

/// The default limit where the machine does not say how much memory it has.
pub const FALLBACK_LIMIT: u64 = 4 << 30;

/// The default memory limit: [`DEFAULT_SHARE`] of the machine's memory.
pub fn default_limit() -> u64 {
    let total = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| mem_total(&s));
    total.map_or(FALLBACK_LIMIT, |t| t / DEFAULT_SHARE.1 * DEFAULT_SHARE.0)
}

/// `MemTotal` of a `/proc/meminfo` text, in bytes.
fn mem_total(meminfo: &str) -> Option<u64> {
    let line = meminfo.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kb.checked_mul(1024)
}

/// Empties a frame buffer whose capacity passed `keep` entries and gives that memory back:
/// one huge frame does not hold its memory for the rest of the run, and frames up to `keep`
/// points reuse theirs (a fresh buffer costs page faults on every frame).
pub fn trim_buffer<U>(v: &mut Vec<U>, keep: usize) {
    if v.capacity() > keep {
        v.clear();
        v.shrink_to(keep);
    }
}

/// What the core's state used over a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StateMemory {
    /// Bytes of state at the start.
    pub start_bytes: usize,
    /// Bytes of state now.
    pub bytes: usize,
    /// The most bytes of state held (during a move the old state is held beside the new one
    /// for as long as the copy takes; that is not counted).
    pub peak_bytes: usize,
    /// Moves into larger storage so far.
    pub moves: u64,
    /// The capacities in use now.
    pub capacities: Capacities,
    /// The limit growth stops at; `None` for fixed capacities, which never grow.
    pub limit: Option<u64>,
    /// The frame (its index) at which growth hit the limit, if it did.
    pub capped_at: Option<usize>,
}

/// When and how far the state grows.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Growth {
    pub(crate) memory: StateMemory,
    /// The frame (its index) being registered, for [`StateMemory::capped_at`].
    pub(crate) frame: usize,
    /// Whether the limit's warning was given.
    warned: bool,
}

impl Growth {
    /// A run starting with `caps` in `bytes` of state, growing up to `limit` (`None`: fixed).
    pub(crate) fn new(caps: Capacities, bytes: usize, limit: Option<u64>) -> Self {
        Self {
            memory: StateMemory {
                start_bytes: bytes,
                bytes,
                peak_bytes: bytes,
                moves: 0,
                capacities: caps,
                limit,
                capped_at: None,
            },
            frame: 0,
            warned: false,
        }
    }

    /// The capacities to move into when `caps` are short of `needed`: each short one doubled,
    /// or raised to what is needed if that is more; or exactly what is needed when doubling
    /// would pass the limit. `None` when even that passes it (`bytes` gives the state's size
    /// for capacities).
    pub(crate) fn next(
        &self,
        caps: &Capacities,
        needed: &Capacities,
        bytes: impl Fn(&Capacities) -> usize,
    ) -> Option<Capacities> {
        let limit = self.memory.limit?;
        let within = |c: &Capacities| (bytes(c) as u64) <= limit;
        [grown(caps, needed, 2), grown(caps, needed, 1)]
            .into_iter()
            .find(within)
    }

    /// Growth stops here: past the limit (or the allocator's end) the fixed-storage rule acts.
    pub(crate) fn cap(&mut self) {
        self.memory.capped_at.get_or_insert(self.frame);
    }

    /// The warning that growth reached its limit, once.
    pub(crate) fn warning(&mut self) -> Option<String> {
        let m = &self.memory;
        let (frame, limit) = (m.capped_at?, m.limit?);
        if std::mem::replace(&mut self.warned, true) {
            return None;
        }
        let mib = |b: u64| b as f64 / (1 << 20) as f64;
        Some(format!(
            "frame {frame}: the core's state ({:.1} MiB) cannot grow past the memory limit \
             ({:.1} MiB): from here its buffers keep their size and a full map gives up its \
             farthest voxels, as on a board; raise runtime.memory_limit to keep kiss-icp's map",
            mib(m.bytes as u64),
            mib(limit)
        ))
    }

    /// Notes a move into `caps` of `bytes`.
    pub(crate) fn moved(&mut self, caps: Capacities, bytes: usize) {
        let m = &mut self.memory;
        m.moves += 1;
        m.capacities = caps;
        m.bytes = bytes;
        m.peak_bytes = m.peak_bytes.max(bytes);
    }
}

/// `caps` with each capacity short of `needed` raised to `factor` times itself, or to the
/// need if that is more.
fn grown(caps: &Capacities, needed: &Capacities, factor: usize) -> Capacities {
    let up = |have: usize, need: usize| {
        if need > have {
            need.max(have.saturating_mul(factor))
        } else {
            have
        }
    };
    Capacities {
        scan_points: up(caps.scan_points, needed.scan_points),
        merge_points: up(caps.merge_points, needed.merge_points),
        source_points: up(caps.source_points, needed.source_points),
        map_voxels: up(caps.map_voxels, needed.map_voxels),
        map_points: up(caps.map_points, needed.map_points),
        plane_terms: caps.plane_terms,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CAPS: Capacities = Capacities::SMALL;

    #[test]
    fn only_the_short_capacities_grow_doubled_or_to_the_need() {
        let needed = Capacities {
            map_voxels: CAPS.map_voxels + 1,
            source_points: 5 * CAPS.source_points,
            ..CAPS
        };
        let g = Growth::new(CAPS, 0, Some(u64::MAX));
        let next = g.next(&CAPS, &needed, |_| 0).unwrap();
        assert_eq!(next.map_voxels, 2 * CAPS.map_voxels);
        assert_eq!(next.source_points, 5 * CAPS.source_points);
        assert_eq!(
            (next.scan_points, next.merge_points, next.map_points),
            (CAPS.scan_points, CAPS.merge_points, CAPS.map_points)
        );
    }

    #[test]
    fn near_the_limit_it_grows_only_to_the_need_and_past_it_not_at_all() {
        let needed = Capacities {
            map_voxels: CAPS.map_voxels + 10,
            ..CAPS
        };
        let bytes = |c: &Capacities| c.map_voxels;
        let limit = (CAPS.map_voxels + 10) as u64;
        let g = Growth::new(CAPS, 0, Some(limit));
        assert_eq!(g.next(&CAPS, &needed, bytes).unwrap(), needed);
        let g = Growth::new(CAPS, 0, Some(limit - 1));
        assert_eq!(g.next(&CAPS, &needed, bytes), None);
        let fixed = Growth::new(CAPS, 0, None);
        assert_eq!(fixed.next(&CAPS, &needed, bytes), None);
    }

    #[test]
    fn reaching_the_limit_warns_once_naming_the_frame() {
        let mut g = Growth::new(CAPS, 3 << 20, Some(4 << 20));
        assert_eq!(g.warning(), None);
        g.frame = 17;
        g.cap();
        g.frame = 18;
        g.cap();
        let w = g.warning().unwrap();
        assert!(w.starts_with("frame 17:") && w.contains("4.0 MiB"), "{w}");
        assert_eq!(g.warning(), None);
    }

    #[test]
    fn moves_are_counted_and_the_peak_kept() {
        let mut g = Growth::new(CAPS, 100, Some(1000));
        g.moved(Capacities::FULL_SCALE, 400);
        g.moved(Capacities::FULL_SCALE, 300);
        let m = g.memory;
        assert_eq!(
            (m.start_bytes, m.bytes, m.peak_bytes, m.moves),
            (100, 300, 400, 2)
        );
        assert_eq!(m.capacities, Capacities::FULL_SCALE);
    }

    #[test]
    fn a_buffer_past_its_size_is_emptied_and_one_within_it_kept() {
        let mut v: Vec<u8> = vec![1; 1000];
        trim_buffer(&mut v, 10);
        assert!(v.is_empty() && v.capacity() <= 10 && v.capacity() < 1000);
        let mut steady: Vec<u8> = vec![1; 10];
        trim_buffer(&mut steady, 10);
        assert_eq!(steady.len(), 10, "within its size: kept as it is");
    }

    #[test]
    fn the_machines_memory_is_read_from_meminfo() {
        let text = "MemTotal:       24576000 kB\nMemFree:         1000 kB\n";
        assert_eq!(mem_total(text), Some(24_576_000 * 1024));
        assert_eq!(mem_total("MemFree: 10 kB\n"), None);
        assert!(default_limit() > 0);
    }
}
