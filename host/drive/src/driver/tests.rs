//! The driver against the core's own API on real scans (every 8th point of the KITTI sample,
//! so the tests stay quick): the same poses bit for bit, whichever way the frames come.

use super::*;
use crate::settings::PresetName;
use crate::widen::widen;
use kiss_odom_core::{Config, Exact, Flag, FrameReport, Odometry};
use kiss_odom_io::pose::pose_difference;
use std::path::Path;

fn scans(n: usize) -> Vec<Frame> {
    let dir =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/kitti-05-reduced/velodyne");
    (0..n)
        .map(|k| {
            let path = dir.join(format!("{k:06}.bin"));
            let bytes = std::fs::read(&path).unwrap();
            let points: Vec<[f64; 3]> = kiss_odom_io::folders::bin::parse(&bytes)
                .unwrap()
                .into_iter()
                .step_by(8)
                .collect();
            // A sweep's capture times by azimuth, so that deskewing is exercised.
            let stamps = points
                .iter()
                .map(|p| 0.1 * (std::f64::consts::PI - p[1].atan2(p[0])) / std::f64::consts::TAU)
                .collect();
            Frame {
                index: k,
                name: path.display().to_string(),
                points,
                stamps: Some(stamps),
                ..Frame::default()
            }
        })
        .collect()
}

fn settings(scalar: Scalar, storage: Storage) -> Settings {
    let mut s = Settings::default();
    s.runtime.scalar = scalar;
    s.runtime.map_storage = storage;
    s.runtime.threads = 1;
    s
}

fn poses(outcomes: &[Outcome]) -> Vec<Isometry3<f64>> {
    outcomes.iter().map(|o| o.pose).collect()
}

fn register_all(driver: &mut Driver, frames: &[Frame]) -> Vec<Outcome> {
    frames.iter().map(|f| driver.register(f).unwrap()).collect()
}

#[test]
fn the_driver_gives_the_cores_own_poses_and_reports() {
    let frames = scans(4);
    let s = settings(Scalar::F64, Storage::Exact);
    let mut driver = Driver::new(&s).unwrap();
    let got = register_all(&mut driver, &frames);

    let mut odom =
        Odometry::<f64, Exact, _>::boxed(Config::new(100.0), s.capacities().unwrap()).unwrap();
    for (f, o) in frames.iter().zip(&got) {
        let sigma = odom.sigma();
        let r = odom.register_frame(&f.points, f.stamps.as_deref()).unwrap();
        assert_eq!(o.pose, widen(&r.pose), "frame {}", f.index);
        let want = FrameReport {
            pose: widen(&r.pose),
            ..r
        };
        assert_eq!(o.report(), Some(&want), "frame {}", f.index);
        assert_eq!((o.sigma, o.input_points), (sigma, f.points.len()));
        assert_eq!(o.meta.source, f.name);
    }
    assert!(got[3].report().unwrap().deskewed);
    assert!(got[3].pose.translation.vector.norm() > 1.0, "the car moved");
    assert_eq!(driver.high_water(), odom.high_water());
    assert_eq!(driver.build().state_bytes, odom.state_bytes());
    assert_eq!(driver.source_cloud().len(), odom.source().len());
    assert_eq!(driver.merge_cloud().len(), odom.merge_cloud().len());
    assert_eq!(driver.map_points().len(), odom.map().points());
    let f = &frames[3];
    assert_eq!(
        driver.deskewed_scan(&f.points, f.stamps.as_deref()).len(),
        got[3].report().unwrap().input_points as usize
            - got[3].report().unwrap().out_of_range as usize
    );
}

#[test]
fn every_build_registers_and_f32_stays_close_to_f64() {
    let frames = scans(3);
    let reference = poses(&register_all(
        &mut Driver::new(&settings(Scalar::F64, Storage::Exact)).unwrap(),
        &frames,
    ));
    for (scalar, storage) in [
        (Scalar::F64, Storage::Quantized),
        (Scalar::F32, Storage::Exact),
        (Scalar::F32, Storage::Quantized),
    ] {
        let mut d = Driver::new(&settings(scalar, storage)).unwrap();
        assert_eq!((d.build().scalar, d.build().storage), (scalar, storage));
        let got = register_all(&mut d, &frames);
        for (o, want) in got.iter().zip(&reference) {
            assert!(o.report().is_some());
            let (t, _) = pose_difference(&o.pose, want);
            assert!(t < 0.05, "{scalar:?} {storage:?}: {t} m from f64 exact");
        }
    }
}

#[test]
fn preloaded_frames_give_the_same_poses_and_refuse_another_scalar() {
    let frames = scans(3);
    let s = settings(Scalar::F32, Storage::Exact);
    let whole = register_all(&mut Driver::new(&s).unwrap(), &frames);
    let mut d = Driver::new(&s).unwrap();
    let pre = d.preload(&frames);
    assert_eq!(pre.len(), 3);
    for (k, want) in whole.iter().enumerate() {
        let got = d.register_preloaded(&pre, k).unwrap();
        assert_eq!((got.pose, &got.meta), (want.pose, &want.meta));
    }
    assert!(d.register_preloaded(&pre, 3).is_err());
    let mut other = Driver::new(&settings(Scalar::F64, Storage::Exact)).unwrap();
    assert!(other.register_preloaded(&pre, 0).is_err());
}

#[test]
fn empty_and_unreadable_frames_advance_on_the_constant_velocity_model() {
    let frames = scans(3);
    let mut d = Driver::new(&settings(Scalar::F64, Storage::Exact)).unwrap();
    let got = register_all(&mut d, &frames);
    let motion = got[1].pose.inverse() * got[2].pose;
    let far = Frame {
        index: 3,
        points: vec![[500.0, 0.0, 0.0], [f64::NAN, 0.0, 0.0]],
        ..Frame::default()
    };
    let predicted = got[2].pose * d.last_delta();
    let empty = d.register(&far).unwrap();
    assert_eq!(empty.step, Step::Empty);
    let (t, r) = pose_difference(&empty.pose, &predicted);
    assert!(
        t < 1e-12 && r < 1e-12,
        "{t:e} m {r:e} rad off the prediction"
    );
    let skipped = d.skip(
        FrameMeta {
            index: 4,
            ..FrameMeta::default()
        },
        "x: unreadable".into(),
    );
    assert_eq!(skipped.step, Step::Skipped("x: unreadable".into()));
    assert_eq!(skipped.latency, Duration::ZERO);
    assert_eq!(skipped.cpu, Duration::ZERO);
    for (o, before) in [(&empty, got[2].pose), (&skipped, empty.pose)] {
        let (t, r) = pose_difference(&o.pose, &(before * motion));
        assert!(
            t < 1e-12 && r < 1e-12,
            "{t:e} m {r:e} rad off the prediction"
        );
        assert_eq!(o.status(), None);
    }
}

#[test]
fn reset_gives_the_poses_of_a_new_driver_and_the_first_frame_is_the_origin() {
    let frames = scans(3);
    let s = settings(Scalar::F64, Storage::Quantized);
    let mut d = Driver::new(&s).unwrap();
    let first = poses(&register_all(&mut d, &frames));
    d.reset();
    assert_eq!(poses(&register_all(&mut d, &frames)), first);
    assert_eq!(first[0], Isometry3::identity());
}

#[test]
fn a_huge_voxel_is_flagged_degenerate_after_the_first_frame() {
    let frames = scans(3);
    let mut s = settings(Scalar::F64, Storage::Exact);
    s.mapping.voxel_size = Some(1e6);
    let got = register_all(&mut Driver::new(&s).unwrap(), &frames);
    assert!(!got[0].status().unwrap().contains(Flag::Degenerate));
    for o in &got[1..] {
        assert!(
            o.status().unwrap().contains(Flag::Degenerate),
            "{:?}",
            o.step
        );
    }
}

#[test]
fn a_driver_can_move_to_another_thread() {
    fn send<T: Send>() {}
    send::<Driver>(); // bindings and batch runs hold one per worker
}

mod growth;

#[test]
fn a_scan_of_one_plane_under_the_accurate_preset_is_held_and_warned_once() {
    let mut frames = scans(5);
    // The third and fourth scans: flat ground 1.73 m below the sensor (KITTI's mount), nothing
    // else.
    for k in [2, 3] {
        let ground: Vec<[f64; 3]> = (0..8000)
            .map(|i| {
                let (r, a) = (3.0 + (i % 80) as f64 * 0.45, i as f64 * 0.0123);
                [r * a.cos(), r * a.sin(), -1.73]
            })
            .collect();
        frames[k].stamps = None;
        frames[k].points = ground;
    }
    let mut s = Settings::preset(PresetName::Accurate);
    s.runtime.threads = 1;
    let mut driver = Driver::new(&s).unwrap();
    let mut warnings = Vec::new();
    for f in &frames {
        let o = driver.register(f).unwrap();
        let held = o.status().unwrap().contains(Flag::OnePlane);
        assert_eq!(held, f.index == 2 || f.index == 3, "frame {}", f.index);
        warnings.extend(driver.one_plane_warning(&o));
    }
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].contains("000002.bin") && warnings[0].contains("one plane"));
    // Reference mode registers it and says nothing.
    let mut driver = Driver::new(&settings(Scalar::F64, Storage::Exact)).unwrap();
    for f in &frames {
        let o = driver.register(f).unwrap();
        assert!(driver.one_plane_warning(&o).is_none());
    }
}
