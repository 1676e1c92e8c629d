//! `kiss-odom-dev`: the developer's tool, beside the user's `kiss-odom`. It runs kiss-odom and
//! the reference kiss-icp 1.3.0 on the same frames, to compare them (`crosscheck`) or to time
//! them (`bench`). Built with the `dev` feature; `cargo install --path host/cli` leaves it out.

use crate::cli::{exit_code, parse};
use clap::{Parser, Subcommand};
use std::ffi::OsString;
use std::io::Write;

/// kiss-odom next to the reference kiss-icp 1.3.0: cross-checks and timings.
#[derive(Debug, Parser)]
#[command(name = "kiss-odom-dev", version, about, long_about = None)]
pub struct DevCli {
    /// What to do.
    #[command(subcommand)]
    pub command: DevCommand,
}

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum DevCommand {
    /// Run kiss-odom and the reference kiss-icp 1.3.0 on the same frames and compare them.
    Crosscheck(crate::crosscheck::CrosscheckArgs),
    /// Time kiss-odom against the reference on preloaded frames.
    Bench(crate::bench::BenchArgs),
}

/// As [`crate::cli::main_with`], for the developer's commands.
pub fn main_with(args: Vec<OsString>, err: &mut dyn Write) -> i32 {
    let cli = match parse::<DevCli>(args, err) {
        Ok(c) => c,
        Err(code) => return code,
    };
    exit_code(
        match cli.command {
            DevCommand::Crosscheck(a) => crate::crosscheck::execute(&a, err),
            DevCommand::Bench(a) => crate::bench::execute(&a, err),
        },
        err,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    fn help(cli: clap::Command, command: &str) -> String {
        let mut cli = cli;
        let sub = cli.find_subcommand_mut(command).unwrap();
        sub.render_long_help().to_string()
    }

    #[test]
    fn the_command_line_is_consistent() {
        DevCli::command().debug_assert();
    }

    #[test]
    fn each_command_states_its_own_defaults_for_the_shared_options() {
        let run = help(crate::cli::Cli::command(), "run");
        let (bench, cross) = (
            help(DevCli::command(), "bench"),
            help(DevCli::command(), "crosscheck"),
        );
        for h in [&run, &bench, &cross] {
            for flag in ["--frames", "--max-range", "--set", "--threads"] {
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
        assert!(cross.contains("also runs the f64 build"), "{cross}");
        assert!(
            !run.contains("The reference gets") && !run.contains("--python"),
            "{run}"
        );
    }
}
