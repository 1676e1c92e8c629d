//! `kiss-odom`: the command-line tool. All logic lives in the library so that the workspace
//! tests drive the same code path in-process.

fn main() {
    let args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    let code = kiss_odom::cli::main_with(args, &mut std::io::stderr());
    std::process::exit(code);
}
