//! The per-frame work budget: counted work never exceeds it, it stops ICP on the same iterate
//! whichever executor runs the chunks, and without it (or with one above what a frame needs)
//! nothing changes.

use crate::common;

use common::*;
use kiss_odom_core::{Capacities, Config, Exact, Executor, Flag, FrameReport, Odometry};

const RANGE: f64 = 40.0;
const FRAMES: usize = 16;

fn scans() -> Vec<Vec<[f64; 3]>> {
    let s = street(3);
    (0..FRAMES).map(|i| scan(&s, i, RANGE)).collect()
}

/// Runs chunks last to first: a stand-in for threads finishing in any order.
struct Reversed;
impl Executor for Reversed {
    fn for_each<C: Send>(&self, chunks: &mut [C], work: &(dyn Fn(&mut C) + Sync)) {
        for c in chunks.iter_mut().rev() {
            work(c);
        }
    }
}

fn run_with<E: Executor>(
    exec: &E,
    budget: Option<u64>,
    caps: Capacities,
    frames: &[Vec<[f64; 3]>],
) -> Vec<FrameReport<f64>> {
    let config = Config {
        work_budget: budget,
        ..Config::new(RANGE)
    };
    let mut words = vec![0u64; caps.arena_words::<f64, Exact>()];
    let mut odom = Odometry::<f64, Exact, _>::new(config, caps, &mut words[..]).unwrap();
    frames
        .iter()
        .map(|s| odom.register_frame_with(exec, s, None).unwrap())
        .collect()
}

#[test]
fn counted_work_never_exceeds_the_budget_and_stops_are_flagged() {
    let frames = scans();
    let free = run_with(&kiss_odom_core::Sequential, None, caps(), &frames);
    let most = free.iter().map(|r| r.work).max().unwrap();
    let median = {
        let mut w: Vec<u64> = free.iter().skip(1).map(|r| r.work).collect();
        w.sort();
        w[w.len() / 2]
    };
    assert!(free.iter().all(|r| !r.status.contains(Flag::Budget)));
    println!("unbudgeted: work per frame median {median}, most {most}");
    for budget in [median / 4, median / 2, median, most] {
        let got = run_with(&kiss_odom_core::Sequential, Some(budget), caps(), &frames);
        let stopped = got
            .iter()
            .filter(|r| r.status.contains(Flag::Budget))
            .count();
        let worst = got.iter().map(|r| r.work).max().unwrap();
        let err = error_at(&got[FRAMES - 1].pose, FRAMES - 1);
        println!(
            "budget {budget}: most work {worst} (allowed {budget}), {stopped} of {FRAMES} \
             frames stopped by it, final error {err:.4} m"
        );
        for (i, (r, f)) in got.iter().zip(&free).enumerate() {
            assert!(r.work <= budget, "frame {i}: {} > {budget}", r.work);
            assert!(r.pose.translation.vector.iter().all(|v| v.is_finite()));
            if r.status.contains(Flag::Budget) {
                assert!(!r.status.contains(Flag::IterationCap));
            } else if got[..i]
                .iter()
                .all(|e| e.pose == free[e.index as usize].pose)
            {
                // Same history, enough budget: the unbudgeted frame exactly.
                assert_eq!((r.pose, r.work), (f.pose, f.work), "frame {i}");
            }
        }
        if budget < median {
            assert!(
                stopped > 0,
                "a budget below the median must stop some frame"
            );
        }
    }
}

#[test]
fn the_budget_stops_on_the_same_iterate_whatever_runs_the_chunks() {
    let frames = scans();
    let free = run_with(&kiss_odom_core::Sequential, None, caps(), &frames);
    let budget = free[5].work / 3;
    let a = run_with(&kiss_odom_core::Sequential, Some(budget), caps(), &frames);
    let b = run_with(&Reversed, Some(budget), caps(), &frames);
    assert_eq!(a, b);
    assert!(a.iter().any(|r| r.status.contains(Flag::Budget)));
}

#[test]
fn no_budget_and_a_budget_above_every_frame_give_the_unbudgeted_run() {
    let frames = scans();
    let free = run_with(&kiss_odom_core::Sequential, None, caps(), &frames);
    let most = free.iter().map(|r| r.work).max().unwrap();
    // Each chunk needs room for a worst-case search beyond what it uses: allow that headroom.
    let roomy = run_with(
        &kiss_odom_core::Sequential,
        Some(most * 4 + 1_000_000),
        caps(),
        &frames,
    );
    assert_eq!(free, roomy);
    assert!(free.iter().skip(1).all(|r| r.work > 0));
}
