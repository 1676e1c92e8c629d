//! The process's own memory, as Linux reports it in `/proc/self/status`: what `run` puts in
//! `summary.json` and what `bench` and the long-run test measure around their runs.

fn proc_status_bytes(field: &str) -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with(field))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Peak resident set size of this process (`VmHWM`), if the OS tells.
pub fn peak_rss_bytes() -> Option<u64> {
    proc_status_bytes("VmHWM:")
}

/// Current resident set size (`VmRSS`), if the OS tells.
pub fn rss_bytes() -> Option<u64> {
    proc_status_bytes("VmRSS:")
}

/// Resets the kernel's peak-RSS counter to the current RSS; false if it cannot (then
/// [`peak_rss_bytes`] is the peak since the process started).
pub fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peak_is_at_least_current_on_linux() {
        // The current size first: other tests of this process allocate in between, and the
        // peak read after it can only have grown.
        let now = rss_bytes();
        if let (Some(peak), Some(now)) = (peak_rss_bytes(), now) {
            assert!(peak >= now && now > 0, "peak {peak} now {now}");
        }
    }
}
