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
    /// Build a prior map for localization (`--map` of run).
    Map(crate::map::MapArgs),
    /// Generate a LiDAR dataset with exact ground truth by ray casting a synthetic scene.
    Simulate(crate::simulate::SimulateArgs),
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
    let cli = match parse::<Cli>(args, err) {
        Ok(c) => c,
        Err(code) => return code,
    };
    exit_code(
        match cli.command {
            Command::Run(a) => crate::run::execute(&a, err),
            Command::Live(a) => crate::live::execute(&a, err),
            Command::Replay(a) => crate::replay::execute(&a),
            Command::ListenPoses(a) => crate::listen::execute(&a, err),
            Command::Convert(a) => crate::convert::execute(&a, err),
            Command::Eval(a) => crate::eval::execute(&a),
            Command::Map(a) => crate::map::execute(&a, err),
            Command::Simulate(a) => crate::simulate::execute(&a),
            Command::Size(a) => crate::size::execute(&a, err),
            #[cfg(feature = "ros2")]
            Command::Ros2(a) => crate::ros2::execute(&a, err),
        },
        err,
    )
}

/// The command line as `C`, or the exit status when it is not one (help and version exit 0,
/// usage errors 1 like every other error).
pub(crate) fn parse<C: Parser>(args: Vec<OsString>, err: &mut dyn Write) -> Result<C, i32> {
    C::try_parse_from(args).map_err(|e| {
        let code = if e.use_stderr() { 1 } else { 0 };
        // Help read through a pipe that closes early (`--help | head`) is no error: a write
        // that fails is not reported, where `print!` would panic.
        let _ = if e.use_stderr() {
            write!(err, "{e}")
        } else {
            write!(std::io::stdout(), "{e}")
        };
        code
    })
}

/// A command's exit status; an error is printed to `err` as one line.
pub(crate) fn exit_code(result: anyhow::Result<i32>, err: &mut dyn Write) -> i32 {
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

    #[test]
    fn the_command_line_is_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn run_names_at_most_twenty_options_and_the_rest_are_settings_keys() {
        let mut cli = Cli::command();
        let run = cli.find_subcommand_mut("run").unwrap();
        let help = run.render_long_help().to_string();
        let options: Vec<&str> = help
            .lines()
            .map(str::trim_start)
            .filter(|l| l.starts_with("--") || l.starts_with("-q, --") || l.starts_with("-h, --"))
            .collect();
        println!("run --help: {} options", options.len());
        assert!(options.len() <= 20, "{options:#?}");
        assert!(help.contains("--set <SECTION.KEY=VALUE>"), "{help}");
    }

    #[test]
    fn the_users_command_has_no_developer_command() {
        for developer in ["crosscheck", "bench"] {
            assert!(
                Cli::command().find_subcommand(developer).is_none(),
                "{developer}"
            );
            let mut err = Vec::new();
            let code = main_with(vec!["kiss-odom".into(), developer.into()], &mut err);
            let err = String::from_utf8_lossy(&err);
            assert!(
                code == 1 && err.contains("unrecognized subcommand"),
                "{err}"
            );
        }
    }
}
