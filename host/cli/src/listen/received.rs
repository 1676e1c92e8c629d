//! What `listen-poses` keeps of the datagrams: the pose datagrams by sweep index (the first one
//! of a sweep), and counts of everything else.

use kiss_odom_sensors::pose_datagram::{PoseDatagram, PoseDatagramError};
use std::collections::BTreeMap;
use std::net::SocketAddr;

/// Missing sweeps listed by index (all are counted): a receiver whose sweep index jumps far
/// must not make the summary gigabytes long.
pub const MISSING_LISTED: usize = 10_000;

/// Datagrams that were not pose datagrams, by [`PoseDatagramError`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Undecodable {
    /// Not a datagram's length.
    pub length: u64,
    /// Without the magic.
    pub magic: u64,
    /// Another layout version.
    pub version: u64,
}

impl Undecodable {
    /// All of them.
    pub fn total(&self) -> u64 {
        self.length + self.magic + self.version
    }
}

/// What came in.
#[derive(Debug, Default)]
pub struct Received {
    /// The first pose datagram of each sweep, in sweep order.
    pub sweeps: BTreeMap<u32, PoseDatagram>,
    /// Datagrams of any kind.
    pub datagrams: u64,
    /// Pose datagrams of a sweep that had already come (ignored).
    pub duplicates: u64,
    /// Pose datagrams that came after a later sweep's.
    pub out_of_order: u64,
    /// Datagrams that were not pose datagrams (ignored).
    pub undecodable: Undecodable,
    /// Datagrams by sender.
    pub senders: BTreeMap<SocketAddr, u64>,
}

impl Received {
    /// Takes one datagram's `bytes` from `from`.
    pub fn take(&mut self, bytes: &[u8], from: SocketAddr) {
        self.datagrams += 1;
        *self.senders.entry(from).or_insert(0) += 1;
        let d = match PoseDatagram::decode(bytes) {
            Ok(d) => d,
            Err(e) => {
                let u = &mut self.undecodable;
                *match e {
                    PoseDatagramError::Length => &mut u.length,
                    PoseDatagramError::Magic => &mut u.magic,
                    PoseDatagramError::Version => &mut u.version,
                } += 1;
                return;
            }
        };
        if self.sweeps.contains_key(&d.sweep) {
            self.duplicates += 1;
            return;
        }
        if self
            .sweeps
            .last_key_value()
            .is_some_and(|(&k, _)| k > d.sweep)
        {
            self.out_of_order += 1;
        }
        self.sweeps.insert(d.sweep, d);
    }

    /// The sweeps between the first and the last one received that did not come (the first
    /// [`MISSING_LISTED`] of them), and how many there are. Sweeps before the first one are
    /// not counted: the listener may have started after the receiver.
    pub fn missing(&self) -> (Vec<u32>, u64) {
        let (mut listed, mut count) = (Vec::new(), 0u64);
        let mut keys = self.sweeps.keys();
        let Some(&(mut prev)) = keys.next() else {
            return (listed, count);
        };
        for &k in keys {
            count += u64::from(k - prev - 1);
            let room = MISSING_LISTED.saturating_sub(listed.len());
            listed.extend((prev + 1..k).take(room));
            prev = k;
        }
        (listed, count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sweep(k: u32) -> [u8; 160] {
        PoseDatagram {
            sweep: k,
            ..PoseDatagram::default()
        }
        .encode()
    }

    #[test]
    fn gaps_duplicates_and_late_sweeps_are_counted_and_the_first_of_a_sweep_kept() {
        let from: SocketAddr = "127.0.0.1:9".parse().unwrap();
        let mut r = Received::default();
        let mut second_five = sweep(5);
        second_five[12] = 7; // points: tells the two apart
        for bytes in [sweep(5), sweep(9), sweep(6), second_five, sweep(12)] {
            r.take(&bytes, from);
        }
        r.take(b"short", from);
        assert_eq!(r.sweeps.keys().copied().collect::<Vec<_>>(), [5, 6, 9, 12]);
        assert_eq!(r.sweeps[&5].points, 0);
        assert_eq!((r.duplicates, r.out_of_order, r.datagrams), (1, 1, 6));
        assert_eq!(r.undecodable.length, 1);
        assert_eq!(r.missing(), (vec![7, 8, 10, 11], 4));
    }

    #[test]
    fn a_jump_of_billions_of_sweeps_is_counted_but_listed_only_in_part() {
        let from: SocketAddr = "127.0.0.1:9".parse().unwrap();
        let mut r = Received::default();
        for k in [0, u32::MAX] {
            r.take(&sweep(k), from);
        }
        let (listed, count) = r.missing();
        assert_eq!(count, u64::from(u32::MAX) - 1);
        assert_eq!(listed.len(), MISSING_LISTED);
        assert_eq!(listed[..2], [1, 2]);
    }
}
