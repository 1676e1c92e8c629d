//! Tests of `trajectory`.

use super::*;

fn profiles() -> [Profile; 9] {
    [
        Profile::Urban,
        Profile::Corridor,
        Profile::Fast,
        Profile::Plane,
        Profile::Tunnel,
        Profile::Field,
        Profile::Suburban,
        Profile::Handheld,
        Profile::Drone,
    ]
}

#[test]
fn position_derivative_is_the_heading_direction() {
    // p(s) is the integral of (cos psi, sin psi): a central difference must match it.
    for profile in profiles() {
        let tr = Trajectory::generate(profile, 3, 60.0);
        let r = tr.route();
        let mut worst: f64 = 0.0;
        let mut s = -150.0;
        while s < 900.0 {
            let h = 1e-3;
            let (a, b) = (r.position(s - h), r.position(s + h));
            let d = [(b[0] - a[0]) / (2.0 * h), (b[1] - a[1]) / (2.0 * h)];
            let psi = r.heading(s);
            worst = worst
                .max((d[0] - libm::cos(psi)).abs())
                .max((d[1] - libm::sin(psi)).abs());
            s += 0.37;
        }
        println!("{profile:?}: worst |dp/ds - (cos, sin)| = {worst:.2e} (tol 1e-6)");
        assert!(worst < 1e-6);
    }
}

#[test]
fn heading_derivative_is_the_curvature() {
    let r = &Trajectory::generate(Profile::Fast, 1, 60.0).route;
    let mut worst: f64 = 0.0;
    let mut s = -100.0;
    while s < 1500.0 {
        let h = 1e-4;
        let d = (r.heading(s + h) - r.heading(s - h)) / (2.0 * h);
        worst = worst.max((d - r.curvature(s)).abs());
        s += 0.29;
    }
    println!("worst |dpsi/ds - kappa| = {worst:.2e} (tol 1e-6)");
    assert!(worst < 1e-6);
}

#[test]
fn pose_is_continuous_at_knots_and_piece_boundaries() {
    let r = &Trajectory::generate(Profile::Urban, 5, 100.0).route;
    for p in r.pieces.iter().take(40) {
        let s = p.end();
        let (a, b) = (r.position(s - 1e-9), r.position(s + 1e-9));
        assert!(
            (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-8,
            "jump at piece end {s}"
        );
    }
    for j in 1..500 {
        let s = r.s_min + j as f64 * KNOT;
        let (a, b) = (r.position(s - 1e-9), r.position(s + 1e-9));
        assert!((a[0] - b[0]).hypot(a[1] - b[1]) < 1e-8, "jump at knot {s}");
    }
}

#[test]
fn speed_stays_in_the_profile_band_and_varies() {
    for (profile, lo, hi) in [
        (Profile::Urban, 5.0, 15.0),
        (Profile::Fast, 20.0, 30.0),
        (Profile::Handheld, 1.0, 1.8),
        (Profile::Drone, 3.0, 10.0),
    ] {
        let tr = Trajectory::generate(profile, 9, 200.0);
        assert_eq!(tr.speed(0.0), 0.0, "a standing start");
        let (mut vmin, mut vmax) = (f64::MAX, f64::MIN);
        for i in 0..20_000 {
            let t = i as f64 * 0.01;
            let v = tr.speed(t);
            assert!((0.0..=hi + 1e-9).contains(&v), "{v} at {t}");
            // Past the launch the speed is within the band (the envelope is 0.999 by 8 tau).
            if t > 15.0 {
                vmin = vmin.min(v);
                vmax = vmax.max(v);
            }
        }
        println!("{profile:?}: speed in [{vmin:.2}, {vmax:.2}] (band [{lo}, {hi}])");
        assert!(vmin >= 0.999 * lo && vmax <= hi + 1e-9);
        // Not a constant-velocity run: the speed sweeps a good part of the band.
        assert!(vmax - vmin > 0.4 * (hi - lo));
    }
}

#[test]
fn arc_length_is_the_integral_of_speed_and_speed_of_acceleration() {
    // The closed forms against Simpson's rule over 0.01 s steps, launch included.
    for profile in [Profile::Urban, Profile::Fast, Profile::Corridor] {
        let sp = &Trajectory::generate(profile, 21, 60.0).speed;
        let (h, mut s, mut v_err, mut s_err) = (0.01, 0.0, 0.0f64, 0.0f64);
        for i in 0..6000 {
            let t = i as f64 * h;
            s += h / 6.0 * (sp.speed(t) + 4.0 * sp.speed(t + 0.5 * h) + sp.speed(t + h));
            s_err = s_err.max((s - sp.arc_length(t + h)).abs());
            let a = (sp.speed(t + h + 1e-6) - sp.speed(t + h - 1e-6)) / 2e-6;
            v_err = v_err.max((a - sp.accel(t + h)).abs());
        }
        println!("{profile:?}: |s - integral v| <= {s_err:.1e} m, |dv/dt - a| <= {v_err:.1e}");
        assert!(s_err < 1e-6 && v_err < 1e-5);
    }
}

#[test]
fn urban_turns_keep_lateral_and_yaw_acceleration_car_like() {
    for seed in 0..4 {
        let tr = Trajectory::generate(Profile::Urban, seed, 300.0);
        let (mut lat, mut yaw_acc, mut yaw_rate) = (0.0f64, 0.0f64, 0.0f64);
        let rate = |t: f64| tr.speed(t) * tr.route.curvature(tr.arc_length(t));
        for i in 0..30_000 {
            let t = i as f64 * 0.01;
            let w = rate(t);
            lat = lat.max((w * tr.speed(t)).abs());
            yaw_rate = yaw_rate.max(w.abs());
            yaw_acc = yaw_acc.max(((rate(t + 1e-4) - rate(t - 1e-4)) / 2e-4).abs());
        }
        println!("seed {seed}: lateral <= {lat:.2} m/s^2, yaw rate <= {yaw_rate:.2} rad/s, yaw accel <= {yaw_acc:.2} rad/s^2");
        // The bounds hold at the speed sampled when the turn was laid out; the speed can
        // drift a little between samples, hence the margin.
        assert!(lat < 1.2 * URBAN_LATERAL_ACCEL && yaw_acc < 1.5 * URBAN_YAW_ACCEL);
        assert!(yaw_rate > 0.15, "the route does turn");
    }
}

#[test]
fn fast_profile_turns_at_about_one_radian_per_second() {
    let tr = Trajectory::generate(Profile::Fast, 0, 120.0);
    let mut peak: f64 = 0.0;
    for i in 0..1200 {
        let t = i as f64 * 0.1;
        let s = tr.arc_length(t);
        peak = peak.max((tr.speed(t) * tr.route.curvature(s)).abs());
    }
    println!("peak yaw rate {peak:.2} rad/s");
    assert!(peak > 0.7 && peak < 1.6);
}

#[test]
fn corridor_route_stays_on_the_axis() {
    let tr = Trajectory::generate(Profile::Corridor, 4, 400.0);
    let mut worst: f64 = 0.0;
    for i in 0..4000 {
        let ([roll, pitch, _], p) = tr.state(i as f64 * 0.1);
        worst = worst.max(p[1].abs());
        assert!(roll.abs() < 0.1 && pitch.abs() < 0.1);
    }
    println!("corridor: max lateral offset {worst:.3} m (tol 2 m)");
    assert!(worst < 2.0 && worst > 0.05);
}

#[test]
fn first_pose_starts_at_the_origin_heading_along_x() {
    let tr = Trajectory::generate(Profile::Urban, 0, 10.0);
    let ([_, _, yaw], p) = tr.state(0.0);
    assert!(p[0].abs() < 1e-9 && p[1].abs() < 1e-9 && yaw.abs() < 1e-12);
}

#[test]
fn the_drone_flies_5_to_11_m_up_and_climbs_at_most_2_5_m_per_s_and_the_walker_stays_low() {
    for seed in [1, 2, 3] {
        let (mut lo, mut hi, mut climb) = (f64::MAX, f64::MIN, 0.0f64);
        let tr = Trajectory::generate(Profile::Drone, seed, 120.0);
        for i in 0..12_000 {
            let t = i as f64 * 0.01;
            let z = tr.state(t).1[2];
            let dz = (tr.state(t + 1e-4).1[2] - tr.state(t - 1e-4).1[2]) / 2e-4;
            (lo, hi, climb) = (lo.min(z), hi.max(z), climb.max(dz.abs()));
        }
        println!("drone seed {seed}: {lo:.2}-{hi:.2} m up, climbing up to {climb:.2} m/s");
        assert!(lo >= 4.7 && hi <= 11.3 && hi - lo > 3.0 && climb <= 2.55 && climb > 0.8);
        let walker = Trajectory::generate(Profile::Handheld, seed, 60.0);
        let zs = (0..6_000).map(|i| walker.state(i as f64 * 0.01).1[2]);
        let (wlo, whi) = zs.fold((f64::MAX, f64::MIN), |(a, b), z| (a.min(z), b.max(z)));
        assert!(wlo > 1.3 && whi < 1.5, "hand at {wlo}-{whi} m");
    }
}

#[test]
fn a_lead_in_enters_the_same_drive_that_many_seconds_in() {
    let lead_in = 8.0;
    for profile in profiles() {
        let from_rest = Trajectory::generate(profile, 5, 30.0);
        let entered = Trajectory::generate_after(profile, 5, lead_in, 20.0);
        let mut worst: f64 = 0.0;
        for i in 0..200 {
            let t = i as f64 * 0.1;
            let a = from_rest.pose(lead_in + t);
            let b = entered.pose(t);
            worst = worst
                .max((a.translation.vector - b.translation.vector).amax())
                .max((a.rotation.matrix() - b.rotation.matrix()).amax());
        }
        let driven = entered.arc_length(20.0);
        let expected = from_rest.arc_length(lead_in + 20.0) - from_rest.arc_length(lead_in);
        // The same route and motion at the same drive time: the same bits.
        println!("{profile:?}: worst pose entry {worst:.2e} (tol 0), {driven:.1} m driven");
        assert_eq!(worst, 0.0, "{profile:?}");
        assert!((driven - expected).abs() < 1e-9, "{profile:?}: {driven} m");
        assert!(
            entered.arc_length(0.0) == 0.0 && entered.speed(0.0) > 0.0,
            "{profile:?}"
        );
    }
}
