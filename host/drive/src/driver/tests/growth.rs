//! A host's storage grows instead of dropping: on a scene that fills every voxel of the range
//! ball (a forest's depth), the default run moves its state into larger storage and gives the
//! poses of a run that had room from the start, in every build; fixed capacities and a memory
//! limit keep the board's rule.

use super::*;
use kiss_odom_core::Flag;

/// A cloud filling a 60 x 24 x 12 m box at random, about 6 points a cubic metre (seeded).
fn forest() -> Vec<[f64; 3]> {
    let mut x = 0x9e37_79b9_7f4a_7c15u64;
    let mut uniform = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..100_000)
        .map(|_| {
            [
                -10.0 + 60.0 * uniform(),
                -12.0 + 24.0 * uniform(),
                -6.0 + 12.0 * uniform(),
            ]
        })
        .collect()
}

/// Scans of `forest` within `range` of a sensor moving 0.8 m a frame along x.
fn drive(frames: usize, range: f64) -> Vec<Frame> {
    let world = forest();
    (0..frames)
        .map(|k| {
            let at = 0.8 * k as f64;
            let points = world
                .iter()
                .map(|p| [p[0] - at, p[1], p[2]])
                .filter(|p| p.iter().map(|c| c * c).sum::<f64>() < range * range)
                .collect();
            Frame {
                index: k,
                name: format!("forest-{k}"),
                points,
                ..Frame::default()
            }
        })
        .collect()
}

/// Settings at `range` with 1 m voxels and one thread: sized capacities hold 3 discs of voxels
/// (943 at 10 m), far less than the ball of filled voxels (about 4,200).
fn settings_at(range: f64, scalar: Scalar, storage: Storage) -> Settings {
    let mut s = settings(scalar, storage);
    s.data.max_range = range;
    s.mapping.voxel_size = Some(1.0);
    s
}

/// Capacities that hold everything this drive gives.
fn roomy(s: &Settings) -> Settings {
    let mut s = s.clone();
    s.capacities = kiss_odom_core::Capacities {
        scan_points: 100_000,
        merge_points: 100_000,
        source_points: 100_000,
        map_voxels: 100_000,
        map_points: 1_000_000,
        plane_terms: false,
    }
    .into();
    s
}

#[test]
fn a_default_host_run_grows_and_gives_the_poses_of_a_run_with_room_from_the_start() {
    let frames = drive(8, 10.0);
    for (scalar, storage) in [
        (Scalar::F64, Storage::Exact),
        (Scalar::F64, Storage::Quantized),
        (Scalar::F32, Storage::Exact),
        (Scalar::F32, Storage::Quantized),
    ] {
        let s = settings_at(10.0, scalar, storage);
        assert!(s.grows());
        let mut growing = Driver::new(&s).unwrap();
        let got = register_all(&mut growing, &frames);
        let mut fixed = Driver::new(&roomy(&s)).unwrap();
        let want = register_all(&mut fixed, &frames);
        let m = growing.memory();
        println!(
            "{scalar:?} {storage:?}: {} moves, state {} -> {} bytes, map {} of {} voxels",
            m.moves,
            m.start_bytes,
            m.bytes,
            growing.high_water().map_voxels,
            s.capacities().unwrap().map_voxels
        );
        assert!(m.moves >= 2 && m.bytes > m.start_bytes && m.peak_bytes == m.bytes);
        assert!(growing.high_water().map_voxels > s.capacities().unwrap().map_voxels);
        assert_eq!(got.iter().map(|o| o.moves as u64).sum::<u64>(), m.moves);
        for (a, b) in got.iter().zip(&want) {
            let r = a.report().unwrap();
            assert!(!r.status.contains(Flag::Evicted) && !r.status.contains(Flag::Capacity));
            assert_eq!(
                a.pose, b.pose,
                "{scalar:?} {storage:?} frame {}",
                a.meta.index
            );
        }
        assert_eq!(growing.high_water(), fixed.high_water());
    }
}

#[test]
fn fixed_capacities_and_a_reached_limit_keep_the_boards_rule_and_say_so() {
    let frames = drive(8, 10.0);
    let s = settings_at(10.0, Scalar::F64, Storage::Exact);
    let sized = s.capacities().unwrap();
    // The same sizes given explicitly: fixed, so the map evicts (the board's rule).
    let mut fixed = s.clone();
    fixed.capacities = sized.into();
    assert_eq!(fixed.memory_limit(), None);
    let mut driver = Driver::new(&fixed).unwrap();
    let out = register_all(&mut driver, &frames);
    let evicted = |o: &[Outcome]| {
        o.iter()
            .filter(|o| o.report().unwrap().status.contains(Flag::Evicted))
            .count()
    };
    assert!(evicted(&out) > 0);
    assert_eq!(driver.memory().moves, 0);
    assert_eq!(driver.growth_warning(), None);
    // A limit just above the start: one move at most, then the board's rule, warned once.
    let mut limited = s.clone();
    limited.runtime.memory_limit = Some(Driver::new(&s).unwrap().build().state_bytes as u64 + 1);
    let mut driver = Driver::new(&limited).unwrap();
    let mut warnings = Vec::new();
    let mut out = Vec::new();
    for f in &frames {
        out.push(driver.register(f).unwrap());
        warnings.extend(driver.growth_warning());
    }
    let m = driver.memory();
    println!(
        "limited: {} moves, capped at {:?}: {warnings:?}",
        m.moves, m.capped_at
    );
    assert_eq!(warnings.len(), 1);
    assert!(m.capped_at.is_some() && m.bytes as u64 <= m.limit.unwrap());
    assert!(evicted(&out) > 0);
}
