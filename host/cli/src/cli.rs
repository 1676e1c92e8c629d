//! The `kiss-odom` command line: argument parsing and dispatch to one module per command.

use clap::{Parser, Subcommand};
use std::ffi::OsString;
use std::io::Write;

/// KISS-ICP LiDAR odometry on recorded data, on top of a bounded no_std core.
#[derive(Debug, Parser)]
#[command(name = "kiss-odom", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run odometry on a recording and write poses, metrics and a plot.
    Run(crate::run::RunArgs),
    /// Odometry from a sensor on the network (Velodyne or Ouster UDP), poses as sweeps
    /// complete, `run`'s outputs at the end (also on Ctrl-C).
    Live(crate::live::LiveArgs),
    /// Send a pcap recording as UDP at its recorded pace (to test `live` without a sensor).
    Replay(crate::replay::ReplayArgs),
    /// Collect the poses a receiver that runs the odometry (the `embedded/` network firmware)
    /// sends, one UDP datagram per sweep, into `run`'s outputs.
    ListenPoses(crate::listen::ListenArgs),
    /// Write a recording (pcap, bag, MCAP, folder) as the generic layout: velodyne/*.bin
    /// (f32 x y z intensity) and timestamps/*.bin (f64 per-point times).
    Convert(crate::convert::ConvertArgs),
    /// Score an estimated trajectory against ground truth (KITTI 3x4 files).
    Eval(crate::eval::EvalArgs),
    /// Generate a LiDAR dataset with exact ground truth by ray casting a synthetic scene.
    Simulate(crate::simulate::SimulateArgs),
    /// Run kiss-odom and the reference kiss-icp 1.3.0 on the same frames and compare them.
    Crosscheck(crate::crosscheck::CrosscheckArgs),
    /// Time kiss-odom against the reference on preloaded frames.
    Bench(crate::bench::BenchArgs),
    /// The smallest fixed capacities that held a run, and their bytes of state on each target
    /// (to size firmware from a recording).
    Size(crate::size::SizeArgs),
    /// ROS 2 node over DDS: PointCloud2 in, odometry and /tf out (or --play a recording).
    #[cfg(feature = "ros2")]
    Ros2(crate::ros2::Ros2Args),
}

/// Parses `args` (program name first), runs the command and returns the exit status. Errors are
/// printed to `err` as one line naming the file and the reason; nothing here panics on bad
/// input.
pub fn main_with(args: Vec<OsString>, err: &mut dyn Write) -> i32 {
    let cli = match Cli::try_parse_from(args) {
        Ok(c) => c,
        Err(e) => {
            // --help and --version exit 0; usage errors exit 1 like every other error.
            let code = if e.use_stderr() { 1 } else { 0 };
            // Help read through a pipe that closes early (`--help | head`) is no error: a write
            // that fails is not reported, where `print!` would panic.
            let _ = if e.use_stderr() {
                write!(err, "{e}")
            } else {
                write!(std::io::stdout(), "{e}")
            };
            return code;
        }
    };
    let result = match cli.command {
        Command::Run(a) => crate::run::execute(&a, err),
        Command::Live(a) => crate::live::execute(&a, err),
        Command::Replay(a) => crate::replay::execute(&a),
        Command::ListenPoses(a) => crate::listen::execute(&a, err),
        Command::Convert(a) => crate::convert::execute(&a, err),
        Command::Eval(a) => crate::eval::execute(&a),
        Command::Simulate(a) => crate::simulate::execute(&a),
        Command::Crosscheck(a) => crate::crosscheck::execute(&a, err),
        Command::Bench(a) => crate::bench::execute(&a, err),
        Command::Size(a) => crate::size::execute(&a, err),
        #[cfg(feature = "ros2")]
        Command::Ros2(a) => crate::ros2::execute(&a, err),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            let _ = writeln!(err, "error: {}", kiss_odom_drive::one_line(&e));
            1
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    fn help(command: &str) -> String {
        let mut cli = Cli::command();
        let sub = cli.find_subcommand_mut(command).unwrap();
        sub.render_long_help().to_string()
    }

    #[test]
    fn the_command_line_is_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn each_command_states_its_own_defaults_for_the_shared_options() {
        let (run, bench, cross) = (help("run"), help("bench"), help("crosscheck"));
        for h in [&run, &bench, &cross] {
            for flag in [
                "--frames",
                "--max-range",
                "--voxel-size",
                "--scalar",
                "--threads",
            ] {
                assert!(h.contains(flag), "{flag} missing:\n{h}");
            }
        }
        assert!(
            run.contains("[default: the settings' (all cores)]"),
            "{run}"
        );
        for h in [&bench, &cross] {
            assert!(
                h.contains("[default: 1: the reference is nondeterministic"),
                "{h}"
            );
            assert!(h.contains("The reference gets only the range"), "{h}");
            assert!(h.contains("--python") && h.contains("--driver"), "{h}");
        }
        assert!(cross.contains("f32 also runs the f64 build"), "{cross}");
        assert!(
            !run.contains("The reference gets") && !run.contains("--python"),
            "{run}"
        );
    }
}
