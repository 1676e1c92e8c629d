//! Stopping cleanly on SIGINT or SIGTERM.
//!
//! The `kiss-odom` binary installs the handlers once ([`install`]); the first signal only
//! raises a flag ([`requested`]), which the commands poll between frames: `run` then writes what
//! it has (poses so far, `summary.json` with `"interrupted": true`), `simulate` drops its
//! unfinished data set, and both exit with `128 + signal` (130 for SIGINT, 143 for SIGTERM).
//! Temporary files are removed as their owners drop, readers' included, so long operations
//! inside a reader may poll [`requested`] too. A second signal ends the process at once with
//! the same status, for when a step does not return.
//!
//! In-process callers (the tests, bindings) do not install the handlers, and the flag then
//! rises only through [`raise`].

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

struct Flags {
    raised: Arc<AtomicBool>,
    signal: Arc<AtomicUsize>,
}

fn flags() -> &'static Flags {
    static FLAGS: OnceLock<Flags> = OnceLock::new();
    FLAGS.get_or_init(|| Flags {
        raised: Arc::new(AtomicBool::new(false)),
        signal: Arc::new(AtomicUsize::new(0)),
    })
}

/// Installs the SIGINT and SIGTERM handlers (Unix; elsewhere nothing happens).
pub fn install() -> std::io::Result<()> {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGINT, SIGTERM};
        let f = flags();
        for sig in [SIGINT, SIGTERM] {
            // Registered first, so it sees the flag as the previous signal left it.
            signal_hook::flag::register_conditional_shutdown(
                sig,
                128 + sig,
                Arc::clone(&f.raised),
            )?;
            signal_hook::flag::register_usize(sig, Arc::clone(&f.signal), sig as usize)?;
            signal_hook::flag::register(sig, Arc::clone(&f.raised))?;
        }
    }
    Ok(())
}

/// Asks the commands to stop as if `signal` had arrived: for callers that catch the signal
/// themselves (bindings whose host language owns the handlers) and for tests. It stays
/// raised for the rest of the process.
pub fn raise(signal: i32) {
    let f = flags();
    f.signal.store(signal as usize, Ordering::Relaxed);
    f.raised.store(true, Ordering::Relaxed);
}

/// The signal that asked the process to stop, if one did.
pub fn requested() -> Option<i32> {
    let f = flags();
    if !f.raised.load(Ordering::Relaxed) {
        return None;
    }
    Some(f.signal.load(Ordering::Relaxed) as i32)
}

/// The exit status of a command stopped by `signal`.
pub fn exit_status(signal: i32) -> i32 {
    128 + signal
}
