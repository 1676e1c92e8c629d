//! `kiss-odom`: the command-line tool around the no_std core (filled in by the host issue).

fn main() {
    println!("kiss-odom {}", env!("CARGO_PKG_VERSION"));
}
