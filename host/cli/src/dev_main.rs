//! `kiss-odom-dev`: the developer's tool (`crosscheck`, `bench`); see `kiss_odom::dev`.

fn main() {
    let args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    let code = kiss_odom::dev::main_with(args, &mut std::io::stderr());
    std::process::exit(code);
}
