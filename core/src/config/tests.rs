//! Tests of `config`.

use super::*;

#[test]
fn robust_is_the_reference_with_planes_and_its_gate_is_checked() {
    let (r, n) = (Config::<f64>::robust(80.0), Config::<f64>::new(80.0));
    assert_eq!(r.degeneracy, Degeneracy::Robust);
    assert_eq!(n.robust.plane_gate, 0.015);
    assert_eq!(
        (n.robust.prediction_prior, n.robust.lateral_prior),
        (0.0, 0.0)
    );
    assert_eq!(
        Config {
            degeneracy: n.degeneracy,
            ..r
        },
        n
    );
    assert!(r.validate().is_ok());
    assert!(Capacities::ROBUST.validate().is_ok());
    for bad in [-0.1, f64::NAN, f64::INFINITY] {
        let with = |robust| Config { robust, ..r };
        let gate = with(Robust {
            plane_gate: bad,
            ..r.robust
        });
        let hold = with(Robust {
            prediction_prior: bad,
            ..r.robust
        });
        let lateral = with(Robust {
            lateral_prior: bad,
            ..r.robust
        });
        let all = [(gate, "plane_gate"), (hold, "hold"), (lateral, "lateral")];
        for (c, name) in all {
            assert_eq!(c.validate(), Err(ConfigError::Threshold), "{name} {bad}");
        }
    }
    let priors = Config {
        robust: Robust::tunnel(),
        ..r
    };
    assert!(priors.validate().is_ok());
    // Room for a finer map than the full-scale one (a tunnel's 0.2 m voxels).
    let full = Capacities::FULL_SCALE;
    assert!(Capacities::ROBUST.map_voxels >= 4 * full.map_voxels);
}

#[test]
fn accurate_is_robust_mode_on_every_frame_on_a_finer_map_without_priors() {
    let (a, r) = (Config::<f64>::accurate(80.0), Config::<f64>::robust(80.0));
    assert_eq!(a.voxel_size, 0.4);
    assert!(a.robust.plane_gate >= 1.0, "every frame with plane terms");
    assert_eq!(
        (a.robust.prediction_prior, a.robust.lateral_prior),
        (0.0, 0.0),
        "no motion prior"
    );
    assert!(
        a.robust.cycle_stop && !r.robust.cycle_stop,
        "the preset's cycle stop only"
    );
    assert!(a.redeskew && !r.redeskew, "the preset's second deskew only");
    assert_eq!(
        (a.desired_source_points, r.desired_source_points),
        (3_000, 0),
        "the preset's thinned registration cloud only"
    );
    assert!(
        !Config::<f64>::new(80.0).redeskew,
        "the reference deskews once"
    );
    assert!(
        !a.reference_order && r.reference_order && Config::<f64>::new(80.0).reference_order,
        "the preset's clouds in scan order only"
    );
    let back = Config {
        voxel_size: r.voxel_size,
        robust: Robust {
            plane_gate: r.robust.plane_gate,
            cycle_stop: r.robust.cycle_stop,
            ..a.robust
        },
        desired_source_points: r.desired_source_points,
        redeskew: r.redeskew,
        reference_order: r.reference_order,
        ..a
    };
    assert_eq!(back, r, "nothing else differs from robust mode");
    assert!(a.validate().is_ok());
    // Its 16-beam capacities: room for plane terms, more of every buffer than TINY's.
    let (t, ta) = (Capacities::TINY, Capacities::TINY_ACCURATE);
    assert!(ta.validate().is_ok() && ta.plane_terms);
    assert_eq!(ta.scan_points, t.scan_points);
    assert!(ta.merge_points > 2 * t.merge_points && ta.source_points > 2 * t.source_points);
    assert!(ta.map_voxels > 2 * t.map_voxels && ta.map_points > 2 * t.map_points);
}

#[test]
fn the_tunnel_and_tiny_settings_are_what_their_docs_say() {
    // Robust::tunnel: plane terms on every frame, the vehicle prior 1 and the hold prior
    // 0.01; the rest robust mode's defaults.
    let (t, n) = (Robust::<f64>::tunnel(), Robust::<f64>::new());
    assert_eq!(
        (t.plane_gate, t.lateral_prior, t.prediction_prior),
        (1.0, 1.0, 0.01)
    );
    let back = Robust {
        plane_gate: n.plane_gate,
        lateral_prior: n.lateral_prior,
        prediction_prior: n.prediction_prior,
        ..t
    };
    assert_eq!(back, n);
    // Config::tiny: r_max 50 m, 2 m voxels of at most 10 points; the rest the reference's.
    let (c, r) = (Config::<f64>::tiny(), Config::<f64>::new(50.0));
    assert_eq!(
        (c.max_range, c.voxel_size, c.max_points_per_voxel),
        (50.0, 2.0, 10)
    );
    let back = Config {
        voxel_size: r.voxel_size,
        max_points_per_voxel: r.max_points_per_voxel,
        ..c
    };
    assert_eq!(back, r);
}
