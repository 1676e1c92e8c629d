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
//!
//! Waits that a user sizes (`replay`'s pace, `live --idle-timeout`) go through [`seconds`],
//! which never panics, and [`sleep`], which a signal cuts short.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

/// How often a [`sleep`] looks at the flag: a signal ends it within this.
pub const POLL: Duration = Duration::from_millis(50);

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

/// `secs` seconds as a [`Duration`], saturating: negative or NaN is none, anything beyond
/// `Duration`'s range (`1e20`, infinity) is [`Duration::MAX`], in effect forever.
pub fn seconds(secs: f64) -> Duration {
    if secs.is_nan() || secs <= 0.0 {
        return Duration::ZERO;
    }
    Duration::try_from_secs_f64(secs).unwrap_or(Duration::MAX)
}

/// Sleeps for `wait` unless a signal asks the process to stop first; returns that signal.
pub fn sleep(wait: Duration) -> Option<i32> {
    // `None`: past `Instant`'s range, which no process lives to see.
    let deadline = Instant::now().checked_add(wait);
    loop {
        if let Some(sig) = requested() {
            return Some(sig);
        }
        let left = match deadline {
            Some(d) => d.saturating_duration_since(Instant::now()),
            None => POLL,
        };
        if left.is_zero() {
            return None;
        }
        std::thread::sleep(left.min(POLL));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn any_number_of_seconds_is_a_duration_without_panicking() {
        assert_eq!(seconds(1.5), Duration::from_millis(1500));
        for none in [0.0, -1.0, -0.0, f64::NAN, f64::NEG_INFINITY] {
            assert_eq!(seconds(none), Duration::ZERO, "{none}");
        }
        for forever in [1e20, 1e30 / 1e-30, f64::INFINITY, f64::MAX] {
            assert_eq!(seconds(forever), Duration::MAX, "{forever}");
        }
        // A wait that long is not added to an instant (which would panic).
        assert_eq!(sleep(Duration::ZERO), None);
    }
}
