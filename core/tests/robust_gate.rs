//! Robust mode's gate (`Robust::plane_gate`): a frame is registered again with
//! point-to-plane terms exactly when the reference registration's observability is below the
//! gate, and every other frame keeps the reference's pose bit for bit.

use crate::common;

use common::*;
use kiss_odom_core::{Capacities, Config, Degeneracy, Exact, Flag, FrameReport, Odometry, Robust};

const RANGE: f64 = 40.0;
const FRAMES: usize = 8;

fn scans() -> Vec<Vec<[f64; 3]>> {
    let s = street(7);
    (0..FRAMES).map(|i| scan(&s, i, RANGE)).collect()
}

/// Room for robust mode's plane terms.
fn robust_caps() -> Capacities {
    Capacities {
        plane_terms: true,
        ..caps()
    }
}

fn reports(config: Config<f64>, scans: &[Vec<[f64; 3]>]) -> Vec<FrameReport<f64>> {
    let caps = robust_caps();
    let mut arena = vec![0u64; caps.arena_words::<f64, Exact>()];
    let mut odom = Odometry::<f64, Exact, _>::new(config, caps, &mut arena[..]).unwrap();
    scans
        .iter()
        .map(|s| odom.register_frame(s, None).unwrap())
        .collect()
}

fn robust(plane_gate: f64) -> Config<f64> {
    let base = Config::robust(RANGE);
    Config {
        robust: Robust {
            plane_gate,
            ..base.robust
        },
        ..base
    }
}

fn planes(r: &[FrameReport<f64>]) -> Vec<bool> {
    r.iter().map(|r| r.status.contains(Flag::Planes)).collect()
}

fn poses(r: &[FrameReport<f64>]) -> Vec<kiss_odom_core::Pose<f64>> {
    r.iter().map(|r| r.pose).collect()
}

#[test]
fn below_every_observability_the_gate_gives_the_reference_bit_for_bit() {
    let s = scans();
    let reference = reports(Config::new(RANGE), &s);
    let gated = reports(robust(0.0), &s);
    assert_eq!(poses(&gated), poses(&reference));
    assert!(planes(&gated).iter().all(|p| !p));
    // The gate only acts in robust mode.
    let wide = Config {
        robust: Robust {
            plane_gate: 1.0,
            ..Robust::new()
        },
        ..Config::new(RANGE)
    };
    let reference_wide = reports(wide, &s);
    assert_eq!(poses(&reference_wide), poses(&reference));
    assert!(planes(&reference_wide).iter().all(|p| !p));
}

#[test]
fn a_gate_of_one_registers_every_frame_but_the_first_with_planes_and_still_tracks() {
    let s = scans();
    let reference = reports(Config::new(RANGE), &s);
    let always = reports(robust(1.0), &s);
    let flagged = planes(&always);
    assert!(
        !flagged[0],
        "the first frame has no map to register against"
    );
    assert!(flagged[1..].iter().all(|p| *p));
    assert_ne!(poses(&always), poses(&reference));
    let worst = (0..FRAMES)
        .map(|i| error_at(&always[i].pose, i))
        .fold(0.0, f64::max);
    println!("plane terms on every frame: worst translation error {worst:.2e} m (allowed 2e-2)");
    assert!(worst < 2e-2);
    // Above every observability the reference registration comes first and is then replaced:
    // the second registration starts afresh from the prediction, so the poses are the same.
    let highest = reference[1..]
        .iter()
        .filter_map(|r| r.observability)
        .fold(0.0, f64::max);
    let gated = reports(robust(highest * 1.5), &s);
    assert!(highest < 1.0 / 1.5);
    assert_eq!(poses(&gated), poses(&always));
    assert_eq!(planes(&gated), flagged);
}

#[test]
fn a_frame_is_registered_again_only_below_the_gate() {
    let s = scans();
    let reference = reports(Config::new(RANGE), &s);
    let first = reference[1].observability.expect("the street is measured");
    // At the first registration's observability itself: not below, so the reference's pose.
    let at = reports(robust(first), &s[..2]);
    assert!(!at[1].status.contains(Flag::Planes));
    assert_eq!(at[1].pose, reference[1].pose);
    // Just above it: registered again.
    let above = reports(robust(first * (1.0 + 1e-12)), &s[..2]);
    assert!(above[1].status.contains(Flag::Planes));
    assert_ne!(above[1].pose, reference[1].pose);
    assert_eq!(
        Config::<f64>::robust(RANGE).degeneracy,
        Degeneracy::Robust,
        "robust() is robust mode"
    );
}

fn with_priors(config: Config<f64>, hold: f64, lateral: f64) -> Config<f64> {
    Config {
        robust: Robust {
            prediction_prior: hold,
            lateral_prior: lateral,
            ..config.robust
        },
        ..config
    }
}

#[test]
fn the_motion_prior_acts_on_frames_with_plane_terms_from_the_third_on() {
    let s = scans();
    let reference = reports(Config::new(RANGE), &s);
    // No frame registered with plane terms (a gate of 0), or not robust mode: no effect.
    for config in [robust(0.0), Config::new(RANGE)] {
        let r = reports(with_priors(config, 0.01, 1.0), &s);
        assert_eq!(poses(&r), poses(&reference));
    }
    let planes_only = poses(&reports(robust(1.0), &s));
    let planes_worst = (0..FRAMES)
        .map(|i| error_at(&planes_only[i], i))
        .fold(0.0, f64::max);
    for (hold, lateral) in [(0.01, 0.0), (0.0, 1.0), (0.01, 1.0)] {
        let r = reports(with_priors(robust(1.0), hold, lateral), &s);
        let p = poses(&r);
        // Frame 1 has plane terms but no velocity yet: no prior.
        assert_eq!(p[..2], planes_only[..2], "hold {hold}, lateral {lateral}");
        for i in 2..FRAMES {
            assert_ne!(
                p[i], planes_only[i],
                "frame {i}, hold {hold}, lateral {lateral}"
            );
        }
        let worst = (0..FRAMES).map(|i| error_at(&p[i], i)).fold(0.0, f64::max);
        println!("hold {hold}, lateral {lateral}: worst translation error {worst:.2e} m");
        if lateral == 0.0 {
            println!("  (allowed 2e-2)");
            assert!(worst < 2e-2);
        } else {
            // This street's sensor slides sideways (its heading lags its motion by up to 0.07
            // rad): the vehicle prior's assumption does not hold, and it costs accuracy.
            println!("  (more than plane terms alone: {planes_worst:.2e} m)");
            assert!(worst > planes_worst);
        }
    }
}
