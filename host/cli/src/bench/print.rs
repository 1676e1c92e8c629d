//! The table `kiss-odom-dev bench` prints.

use super::report::{Report, SideStats};

fn mib(b: u64) -> f64 {
    b as f64 / (1u64 << 20) as f64
}

/// Prints the report as a table and a few lines of memory and agreement figures.
pub(super) fn print_report(r: &Report) {
    println!(
        "bench: {} ({} frames, {} points), {} thread(s), {:?} {:?}, {} timed runs each after \
         a warm-up, alternating",
        r.dataset, r.frames, r.points, r.threads, r.scalar, r.storage, r.repeats
    );
    println!(
        "latency: per-frame median over the runs, frames {}.. ; max(any run) includes machine \
         noise",
        r.latency_from
    );
    println!(
        "{:<16} {:>9} {:>8} {:>8} {:>8} {:>8} {:>8} {:>13} {:>10} {:>10}",
        "",
        "frames/s",
        "p50 ms",
        "p99 ms",
        "max ms",
        "p99/p50",
        "max/p50",
        "max(any) ms",
        "peak RSS",
        "RSS grow"
    );
    let row = |name: &str, s: &SideStats| {
        println!(
            "{:<16} {:>9.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>13.2} {:>6.1} MiB {:>6.1} MiB",
            name,
            s.fps,
            s.p50_ms,
            s.p99_ms,
            s.max_ms,
            s.p99_ms / s.p50_ms,
            s.max_ms / s.p50_ms,
            s.max_any_run_ms,
            s.peak_rss_bytes.map_or(f64::NAN, mib),
            s.rss_growth_bytes.map_or(f64::NAN, mib),
        )
    };
    row("kiss-odom", &r.ours);
    if let Some(c) = &r.ours.cpu {
        println!(
            "kiss-odom, this thread's CPU time: p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms, \
             p99/p50 {:.2}, max/p50 {:.2}",
            c.p50_ms,
            c.p99_ms,
            c.max_ms,
            c.p99_ms / c.p50_ms,
            c.max_ms / c.p50_ms
        );
    }
    if let Some(rs) = &r.reference {
        row("kiss-icp 1.3.0", rs);
    }
    if let Some(ratio) = r.speed_ratio {
        let runs: Vec<String> = r
            .speed_ratio_runs
            .iter()
            .map(|x| format!("{x:.2}"))
            .collect();
        println!(
            "speed ours/reference: {ratio:.2}x frames/s (median of paired runs: {})",
            runs.join(" ")
        );
    }
    let m = &r.memory;
    println!(
        "kiss-odom state: {:.2} MiB fixed at start ({:.2} MiB at the high-water marks); \
         local map {:.2} MiB fixed ({:.2} MiB at the high-water marks)",
        mib(m.state_bytes as u64),
        m.state_high_water_bytes.map_or(f64::NAN, |b| mib(b as u64)),
        mib(m.map_bytes as u64),
        mib(m.map_high_water_bytes as u64),
    );
    println!("high-water / capacity: {}", m.high_water);
    if let (Some(v), Some(b), Some(bt)) = (
        m.reference_voxels,
        m.reference_map_bytes,
        m.reference_map_bytes_with_table,
    ) {
        println!(
            "reference local map: at most {v} voxels ({} points): {:.2} MiB of point buffers, \
             {:.2} MiB with chunk headers and buckets; ours (fixed) / reference: {:.2} \
             ({:.2} with table)",
            m.reference_points.unwrap_or(0),
            mib(b as u64),
            mib(bt as u64),
            m.map_bytes as f64 / b as f64,
            m.map_bytes as f64 / bt as f64,
        );
    }
    if let Some(s) = r.reference_binding_share {
        println!(
            "reference: numpy -> C++ conversion of the input scan is {:.1}% of its frame time",
            s * 100.0
        );
    }
    println!(
        "worst case per frame from the capacities: {} distance evaluations (source x 27 x \
         N_max x iteration cap); most iterations seen: {}",
        r.worst_case_distance_evaluations, r.max_iterations_seen
    );
    match (r.pose_diff_m, r.pose_diff_rad) {
        (Some(dm), Some(dr)) => println!(
            "poses vs reference: max {dm:.3e} m, {dr:.3e} rad; our runs bit-identical: {}; \
             degraded frames: {}",
            r.ours_repeatable, r.degraded_frames
        ),
        _ => println!(
            "our runs bit-identical: {}; degraded frames: {}",
            r.ours_repeatable, r.degraded_frames
        ),
    }
}
