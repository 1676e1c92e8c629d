use super::*;
use crate::profile::Profile;
use crate::simulation::SimParams;

fn sim(profile: Profile, seed: u64, frames: u64) -> Simulation {
    Simulation::new(SimParams::new(profile, seed, frames)).unwrap()
}

/// Integrates exact samples over `[t0, t1]` (midpoint rule on the rate, trapezoid on the
/// force) and compares with the IMU's true pose at `t1`: rotation (rad) and position (m).
fn integrate_against_truth(s: &Simulation, spec: &ImuSpec, t0: f64, t1: f64) -> (f64, f64) {
    let ext = spec.extrinsic();
    let imu = |t: f64| s.trajectory().pose(t) * ext;
    let start = imu(t0);
    let mut r = start.rotation;
    let mut p = start.translation.vector;
    // The true velocity at t0, from the positions.
    let h = 1e-4;
    let mut v = (imu(t0 + h).translation.vector - imu(t0 - h).translation.vector) / (2.0 * h);
    let n = ((t1 - t0) * 4000.0).round() as usize;
    let dt = (t1 - t0) / n as f64;
    let g = Vector3::new(0.0, 0.0, -GRAVITY);
    for k in 0..n {
        let t = t0 + k as f64 * dt;
        let (_, f0) = exact(s, &ext, t);
        let (wm, _) = exact(s, &ext, t + 0.5 * dt);
        let (_, f1) = exact(s, &ext, t + dt);
        let a0 = r * Vector3::from(f0) + g;
        let r1 = r * Rotation3::from_scaled_axis(Vector3::from(wm) * dt);
        let a1 = r1 * Vector3::from(f1) + g;
        p += v * dt + (2.0 * a0 + a1) * (dt * dt / 6.0);
        v += 0.5 * (a0 + a1) * dt;
        r = r1;
    }
    let end = imu(t1);
    let rot = rotation_log(&(end.rotation.inverse() * r)).norm();
    (rot, (end.translation.vector - p).norm())
}

#[test]
fn exact_rates_and_forces_integrate_to_the_imus_own_path() {
    // A lever arm and a tilted mount, so both have to be right.
    let spec = ImuSpec {
        lidar_from_imu: [0.3, -0.2, 0.1, 10.0, -20.0, 30.0],
        ..ImuSpec::mems(200.0).exact()
    };
    for (profile, seed) in [
        (Profile::Urban, 3),
        (Profile::Handheld, 4),
        (Profile::Drone, 5),
    ] {
        let s = sim(profile, seed, 20);
        let (rot, pos) = integrate_against_truth(&s, &spec, 1.0, 1.5);
        println!("{profile:?}: 0.5 s integrated: {rot:.2e} rad, {pos:.2e} m (tol 1e-5, 1e-4)");
        assert!(rot < 1e-5 && pos < 1e-4, "{profile:?}: {rot} rad, {pos} m");
    }
    // The lever arm matters: without it the integration misses.
    let s = sim(Profile::Drone, 5, 20);
    let wrong = ImuSpec {
        lidar_from_imu: [0.0, 0.0, 0.0, 10.0, -20.0, 30.0],
        ..spec
    };
    let (_, force) = exact(&s, &spec.extrinsic(), 1.2);
    let (_, force0) = exact(&s, &wrong.extrinsic(), 1.2);
    let d = Vector3::from(force) - Vector3::from(force0);
    assert!(
        d.norm() > 1e-3,
        "lever arm changes the force by {:.2e}",
        d.norm()
    );
}

#[test]
fn a_level_imu_at_rest_reads_plus_one_g_up() {
    // The urban drive stands still before it starts at 0 s; its body still wobbles a little,
    // so within 0.5 m/s^2 and 0.05 rad/s.
    let s = sim(Profile::Urban, 1, 5);
    let spec = ImuSpec::mems(100.0).exact();
    let (rate, force) = exact(&s, &spec.extrinsic(), -1.0);
    println!("at rest: rate {rate:?}, force {force:?}");
    assert!((force[2] - GRAVITY).abs() < 0.5 && force[0].abs() < 0.1 && force[1].abs() < 0.1);
    assert!(rate.iter().all(|w| w.abs() < 0.05));
}

#[test]
fn noise_and_bias_follow_the_stated_model() {
    let s = sim(Profile::Urban, 9, 30);
    let spec = ImuSpec::mems(400.0);
    let noisy = samples(&s, &spec, 2.5);
    let exact_spec = spec.exact();
    let clean = samples(&s, &exact_spec, 2.5);
    assert_eq!(noisy.len(), 1001);
    assert_eq!(clean.len(), noisy.len());
    let (g0, a0) = turn_on_bias(&spec, 9);
    let n = noisy.len() as f64;
    for i in 0..3 {
        let dg: Vec<f64> = noisy
            .iter()
            .zip(&clean)
            .map(|(a, b)| a.gyro[i] - b.gyro[i])
            .collect();
        let da: Vec<f64> = noisy
            .iter()
            .zip(&clean)
            .map(|(a, b)| a.accel[i] - b.accel[i])
            .collect();
        let mean = |v: &[f64]| v.iter().sum::<f64>() / n;
        let sd = |v: &[f64]| {
            let m = mean(v);
            (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / n).sqrt()
        };
        let want_g = spec.gyro_noise_density * 400f64.sqrt();
        let want_a = spec.accel_noise_density * 400f64.sqrt();
        println!(
            "axis {i}: gyro bias {:.5} (turn-on {:.5}) sd {:.5} (model {want_g:.5}); \
             accel bias {:.4} (turn-on {:.4}) sd {:.4} (model {want_a:.4})",
            mean(&dg),
            g0[i],
            sd(&dg),
            mean(&da),
            a0[i],
            sd(&da)
        );
        // The bias walks by ~2e-5 rad/s and ~5e-4 m/s^2 in 2.5 s; the mean of 1,001 draws is
        // within 4 sd/sqrt(n) of it.
        assert!((mean(&dg) - g0[i]).abs() < 4.0 * want_g / n.sqrt() + 1e-4);
        assert!((mean(&da) - a0[i]).abs() < 4.0 * want_a / n.sqrt() + 2e-3);
        assert!((sd(&dg) / want_g - 1.0).abs() < 0.1 && (sd(&da) / want_a - 1.0).abs() < 0.1);
    }
    // Turn-on biases differ by seed and stay within the stated bound.
    let (g1, _) = turn_on_bias(&spec, 10);
    assert_ne!(g0, g1);
    assert!(g0.iter().chain(&g1).all(|b| b.abs() <= spec.gyro_bias_max));
    // Sample times: the frames' clock plus the offset.
    let shifted = ImuSpec {
        time_offset: 0.02,
        ..exact_spec
    };
    let later = samples(&s, &shifted, 0.01);
    assert_eq!(later.len(), 5);
    assert_eq!(later[1].time, 0.0025 + 0.02);
    assert_eq!(later[1].gyro, clean[1].gyro);
}

#[test]
fn hand_held_and_drone_turn_fast_and_cars_do_not() {
    let peak = |profile, seed| {
        let s = sim(profile, seed, 600);
        let spec = ImuSpec::mems(100.0).exact();
        samples(&s, &spec, 60.0)
            .iter()
            .map(|x| Vector3::from(x.gyro).norm().to_degrees())
            .fold(0.0, f64::max)
    };
    for seed in [1, 2] {
        let (u, h, d) = (
            peak(Profile::Urban, seed),
            peak(Profile::Handheld, seed),
            peak(Profile::Drone, seed),
        );
        println!("seed {seed}: peak rate urban {u:.0}, handheld {h:.0}, drone {d:.0} deg/s");
        assert!(u < 60.0, "urban {u}");
        assert!((90.0..300.0).contains(&h), "handheld {h}");
        assert!((90.0..300.0).contains(&d), "drone {d}");
    }
}

#[test]
fn the_csv_reads_back_to_the_same_numbers() {
    let s = sim(Profile::Drone, 2, 5);
    let v = samples(&s, &ImuSpec::mems(200.0), 0.3);
    let text = csv(&v);
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(CSV_HEADER));
    for (line, x) in lines.zip(&v) {
        let f: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
        assert_eq!(f.len(), 7);
        assert!((f[0] - x.time).abs() < 1e-9);
        assert_eq!(&f[1..4], &x.gyro[..]);
        assert_eq!(&f[4..7], &x.accel[..]);
    }
}
