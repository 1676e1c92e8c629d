//! The host twin: the same workload on a `std` target, printing to stdout. It has no
//! instruction counter and no painted stack; it exists so `compare.sh` can diff poses.

pub fn main() {
    let code = crate::app(None, || None, "none");
    std::process::exit(code)
}
