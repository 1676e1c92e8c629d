//! The process's own memory, as Linux reports it in `/proc/self/status`: what `run` puts in
//! `summary.json` and what `bench` and the long-run test measure around their runs.

fn proc_status_bytes(field: &str) -> Option<u64> {
    status_field_bytes(&std::fs::read_to_string("/proc/self/status").ok()?, field)
}

/// One `kB` field of a `/proc/<pid>/status` text, in bytes.
fn status_field_bytes(status: &str, field: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with(field))?;
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
    fn fields_are_read_in_bytes_and_a_missing_one_is_none() {
        let status = "Name:\tkiss-odom\nVmHWM:\t   6276 kB\nVmRSS:\t   6284 kB\n";
        assert_eq!(status_field_bytes(status, "VmHWM:"), Some(6276 * 1024));
        assert_eq!(status_field_bytes(status, "VmRSS:"), Some(6284 * 1024));
        assert_eq!(status_field_bytes(status, "VmSwap:"), None);
        assert_eq!(status_field_bytes("VmRSS:\tmany kB\n", "VmRSS:"), None);
    }

    #[test]
    fn peak_is_at_least_current_on_linux() {
        // Both from one snapshot: other tests of this process allocate, free and reset the
        // peak (`bench`) in between two separate reads.
        let Ok(status) = std::fs::read_to_string("/proc/self/status") else {
            return;
        };
        let peak = status_field_bytes(&status, "VmHWM:");
        let now = status_field_bytes(&status, "VmRSS:");
        if let (Some(peak), Some(now)) = (peak, now) {
            assert!(peak >= now && now > 0, "peak {peak} now {now}");
        }
        assert_eq!(peak.is_some(), peak_rss_bytes().is_some());
        assert_eq!(now.is_some(), rss_bytes().is_some());
    }
}
