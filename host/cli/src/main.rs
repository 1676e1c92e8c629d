//! `kiss-odom`: the command-line tool. All logic lives in the library so that the workspace
//! tests drive the same code path in-process; only the signal handlers are the binary's.

fn main() {
    if let Err(e) = kiss_odom::interrupt::install() {
        eprintln!("warning: cannot handle SIGINT/SIGTERM ({e}): an interrupt ends the run at once");
    }
    let args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    let code = kiss_odom::cli::main_with(args, &mut std::io::stderr());
    std::process::exit(code);
}
