//! The core's frame entry point: bytes become a configuration, small capacities and a few
//! scans (with or without stamps, some of them the previous scan moved a little so that ICP
//! has work), fed to `Odometry::register_frame` and `skip_frame`. Asserts that nothing panics,
//! that every pose is finite, that errors leave the pose alone, and that no buffer grows past
//! its capacity.
#![no_main]

use arbitrary::{Result, Unstructured};
use kiss_odom_core::stages::BLOCK;
use kiss_odom_core::{
    Capacities, Config, ConfigError, Degeneracy, Exact, FrameError, Odometry, PointCodec, Pose,
    Quantized, Real,
};
use libfuzzer_sys::fuzz_target;
use nalgebra::{Point3, Translation3, UnitQuaternion, Vector3};

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let _ = match u.arbitrary::<u8>().unwrap_or(0) % 3 {
        0 => run::<f64, Exact>(&mut u),
        1 => run::<f64, Quantized>(&mut u),
        _ => run::<f32, Quantized>(&mut u),
    };
});

const SPECIAL: [f64; 12] = [
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    0.0,
    -0.0,
    1e300,
    -1e300,
    f64::MAX,
    f64::MIN_POSITIVE,
    5e-324,
    1e15,
    -3e38,
];

fn pick<T: Copy>(u: &mut Unstructured, table: &[T]) -> Result<T> {
    Ok(table[u.arbitrary::<u8>()? as usize % table.len()])
}

/// A value: mostly a multiple of `unit / 256` within +-128 units, sometimes special or raw.
fn value(u: &mut Unstructured, unit: f64) -> Result<f64> {
    Ok(match u.arbitrary::<u8>()? {
        0..=223 => f64::from(u.arbitrary::<i16>()?) * unit / 256.0,
        224..=239 => pick(u, &SPECIAL)?,
        _ => f64::from_bits(u.arbitrary()?),
    })
}

fn config<T: Real>(u: &mut Unstructured) -> Result<Config<T>> {
    let max_range = pick(
        u,
        &[100.0, 50.0, 1.0, 10.0, 1e3, 1e6, 1e30, 1e200, f64::MAX],
    )?;
    let mut c = Config::new(T::of(max_range));
    c.voxel_size = T::of(max_range / pick(u, &[100.0, 10.0, 1.0, 1000.0, 1e6])?);
    c.min_range = T::of(max_range * pick(u, &[0.0, 0.0, 0.01, 0.5])?);
    c.max_points_per_voxel = u32::from(u.arbitrary::<u8>()?.max(1));
    c.deskew = u.arbitrary()?;
    c.max_iterations = u32::from(u.arbitrary::<u8>()? % 32 + 1);
    c.convergence_criterion = T::of(pick(u, &[1e-4, 0.0, 1e-2])?);
    c.initial_threshold = T::of(pick(u, &[2.0, 0.1, 50.0, 1e-6])?);
    c.kernel_scale = T::of(pick(u, &[1.0, 1.0 / 3.0, 10.0])?);
    c.degeneracy = *u.choose(&[Degeneracy::Reference, Degeneracy::Robust])?;
    c.robust.plane_gate = T::of(pick(u, &[0.015, 0.0, 1.0, 0.5])?);
    c.robust.prediction_prior = T::of(pick(u, &[0.0, 0.01, 1e3])?);
    c.robust.lateral_prior = T::of(pick(u, &[0.0, 1.0, 1e-3])?);
    c.robust.cycle_stop = u.arbitrary()?;
    c.desired_source_points = usize::from(u.arbitrary::<u8>()? % 128);
    Ok(c)
}

fn caps(u: &mut Unstructured) -> Result<Capacities> {
    Ok(Capacities {
        scan_points: usize::from(u.arbitrary::<u16>()? % 512 + 1),
        merge_points: usize::from(u.arbitrary::<u16>()? % 256 + 1),
        source_points: usize::from(u.arbitrary::<u16>()? % 128 + 1),
        map_voxels: usize::from(u.arbitrary::<u16>()? % 256 + 1),
        map_points: usize::from(u.arbitrary::<u16>()? % 1024 + 1),
        plane_terms: u.arbitrary()?,
    })
}

fn stamps(u: &mut Unstructured, n: usize) -> Result<Option<Vec<f64>>> {
    Ok(match u.arbitrary::<u8>()? % 5 {
        0 | 1 => None,
        2 => {
            let (a, b) = (value(u, 1.0)?, value(u, 0.01)?);
            Some((0..n).map(|i| a + b * i as f64).collect())
        }
        3 => Some((0..n).map(|_| value(u, 1.0)).collect::<Result<_>>()?),
        _ => {
            let len = usize::from(u.arbitrary::<u8>()?);
            Some(vec![0.5; if len == n { n + 1 } else { len }])
        }
    })
}

fn finite<T: Real>(p: &Pose<T>) -> bool {
    p.translation.vector.iter().all(|v| v.is_finite())
        && p.rotation.coords.iter().all(|v| v.is_finite())
}

fn run<T: Real, P: PointCodec<T>>(u: &mut Unstructured) -> Result<()> {
    let config = config::<T>(u)?;
    let caps = caps(u)?;
    if config.validate().is_err() {
        return Ok(());
    }
    let mut arena = vec![0u64; caps.arena_words::<T, P>()];
    if config.degeneracy == Degeneracy::Robust && !caps.plane_terms {
        let e = Odometry::<T, P, _>::new(config, caps, &mut arena[..]).err();
        assert_eq!(e, Some(ConfigError::PlaneTerms));
        return Ok(());
    }
    let mut odom = Odometry::<T, P, _>::new(config, caps, &mut arena[..]).expect("valid config");
    let unit = config.voxel_size.wide();
    let mut last: Vec<[f64; 3]> = Vec::new();
    for _ in 0..8 {
        let points: Vec<[f64; 3]> = match u.arbitrary::<u8>()? % 8 {
            0 => {
                assert!(
                    finite(&odom.skip_frame()),
                    "skip_frame gave a non-finite pose"
                );
                continue;
            }
            // The previous scan seen after a small motion (within a voxel and 3 degrees).
            1..=3 => {
                let t = Vector3::new(
                    f64::from(u.arbitrary::<i8>()?),
                    f64::from(u.arbitrary::<i8>()?),
                    f64::from(u.arbitrary::<i8>()?),
                ) * (unit / 128.0);
                let w = Vector3::new(
                    f64::from(u.arbitrary::<i8>()?),
                    f64::from(u.arbitrary::<i8>()?),
                    f64::from(u.arbitrary::<i8>()?),
                ) * (0.052 / 128.0);
                let m =
                    Pose::from_parts(Translation3::from(t), UnitQuaternion::from_scaled_axis(w));
                last.iter()
                    .map(|p| {
                        let q = m * Point3::from(*p);
                        [q.x, q.y, q.z]
                    })
                    .collect()
            }
            _ => {
                let n = usize::from(u.arbitrary::<u16>()? % 600);
                let mut pts = Vec::with_capacity(n);
                for _ in 0..n {
                    pts.push([value(u, unit)?, value(u, unit)?, value(u, unit)?]);
                }
                pts
            }
        };
        let stamps = stamps(u, points.len())?;
        let narrow: Vec<[T; 3]> = points.iter().map(|p| p.map(T::of)).collect();
        let before = *odom.pose();
        match odom.register_frame(&narrow, stamps.as_deref()) {
            Ok(r) => {
                assert!(finite(&r.pose), "non-finite pose {:?}", r.pose);
                assert!(r.merge_points as usize <= caps.merge_points);
                assert!(r.source_points as usize <= caps.source_points);
                assert!(r.map_voxels as usize <= caps.map_voxels);
                // The pool holds whole blocks: `map_points` rounded up to BLOCK.
                assert!(r.map_points as usize <= caps.map_points.next_multiple_of(BLOCK));
                let hw = odom.high_water();
                assert!(hw.merge_points <= caps.merge_points);
                assert!(hw.source_points <= caps.source_points);
                assert!(hw.map_voxels <= caps.map_voxels);
                assert!(hw.map_point_slots <= caps.map_points.next_multiple_of(BLOCK));
            }
            Err(e) => {
                assert_eq!(e, FrameError::EmptyScan);
                assert_eq!(*odom.pose(), before, "a refused scan moved the pose");
            }
        }
        assert!(finite(odom.pose()));
        last = points;
    }
    Ok(())
}
