use super::*;
use nalgebra::{Translation3, UnitQuaternion};
use std::println;

fn pose(x: f64, y: f64, yaw: f64) -> Pose<f64> {
    Pose::from_parts(
        Translation3::new(x, y, 0.0),
        UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
    )
}

/// The 6x6 matrix and gradient of a packed system.
fn unpack(sum: &[f64; SYSTEM_LEN]) -> (nalgebra::Matrix6<f64>, nalgebra::Vector6<f64>) {
    let mut h = nalgebra::Matrix6::zeros();
    let mut k = 0;
    for r in 0..6 {
        for c in r..6 {
            h[(r, c)] = sum[k];
            h[(c, r)] = sum[k];
            k += 1;
        }
    }
    let g = nalgebra::Vector6::from_row_slice(&sum[21..27]);
    (h, g)
}

#[test]
fn the_lateral_direction_is_the_y_axis_halfway_between_the_two_poses() {
    let p = MotionPrior::new(&pose(1.0, 2.0, 0.0), &pose(3.0, 2.0, 0.2), 0.5, 2.0);
    let want = Vector3::new(-libm::sin(0.1), libm::cos(0.1), 0.0);
    println!("lateral {:?} want {want:?}", p.lateral);
    assert!((p.lateral - want).norm() < 1e-15);
    assert_eq!((p.hold, p.sideways), (0.5, 2.0));
    assert_eq!(p.last, Vector3::new(1.0, 2.0, 0.0));
    assert_eq!(p.predicted, Vector3::new(3.0, 2.0, 0.0));
    // Half a turn apart there is no halfway axis: no lateral term.
    let flip = MotionPrior::new(
        &pose(0.0, 0.0, 0.0),
        &pose(1.0, 0.0, core::f64::consts::PI),
        0.5,
        2.0,
    );
    assert_eq!(flip.sideways, 0.0);
}

#[test]
fn a_solve_of_the_prior_alone_lands_on_the_prediction_or_on_the_heading() {
    // Hold only: one Gauss-Newton step of the translation block goes to t_pred.
    let (last, pred) = (pose(10.0, 5.0, 0.3), pose(11.0, 5.5, 0.3));
    let t = Vector3::new(12.0, 4.0, 1.0);
    let mut sum = [0.0; SYSTEM_LEN];
    sum[27] = 4.0;
    sum[28] = 3.0;
    MotionPrior::new(&last, &pred, 2.0, 0.0).add(&mut sum, &t);
    assert_eq!(
        (sum[27], sum[28]),
        (4.0, 3.0),
        "the prior is no correspondence"
    );
    let (h, g) = unpack(&sum);
    // Weight 2 a correspondence over the system's 4 correspondences.
    assert_eq!(h[(0, 0)], 8.0);
    let rho = h
        .fixed_view::<3, 3>(0, 0)
        .cholesky()
        .unwrap()
        .solve(&(-g.fixed_rows::<3>(0)));
    let target = pred.translation.vector;
    println!(
        "hold step lands {:?} off the prediction",
        (t + rho - target).norm()
    );
    assert!((t + rho - target).norm() < 1e-12);

    // Lateral only: the residual is the motion along y rotated halfway, weighted likewise.
    let mut sum = [0.0; SYSTEM_LEN];
    sum[27] = 4.0;
    let p = MotionPrior::new(&last, &pred, 0.0, 3.0);
    p.add(&mut sum, &t);
    let (h, g) = unpack(&sum);
    let l = p.lateral;
    let across = l.dot(&(t - last.translation.vector));
    let j = nalgebra::Vector6::new(l.x, l.y, l.z, 0.0, 0.0, 0.0) + {
        let c = t.cross(&l);
        nalgebra::Vector6::new(0.0, 0.0, 0.0, c.x, c.y, c.z)
    };
    assert!((h - 12.0 * j * j.transpose()).norm() < 1e-12);
    assert!((g - 12.0 * across * j).norm() < 1e-12);
}

#[test]
fn zero_weights_add_nothing() {
    let mut sum = [1.5; SYSTEM_LEN];
    let p = MotionPrior::new(&pose(0.0, 0.0, 0.0), &pose(1.0, 0.0, 0.0), 0.0, 0.0);
    p.add(&mut sum, &Vector3::new(3.0, 1.0, 0.0));
    assert_eq!(sum, [1.5; SYSTEM_LEN]);
}
