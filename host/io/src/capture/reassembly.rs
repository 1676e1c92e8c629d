//! IP fragments back into datagrams, with bounded memory and never a datagram made of two.
//!
//! An Ouster packet is larger than a standard MTU, so a capture holds it as IPv4 (or IPv6)
//! fragments. A datagram is the fragments that share a [`Key`] (addresses, protocol, IP ID,
//! VLAN, capture interface), but an IP ID is reused after 65,536 datagrams, and a fragment
//! the capture lost leaves its datagram waiting. The rules, so that a waiting datagram is
//! never completed with another datagram's fragments and never kept for ever:
//!
//! - a fragment that overlaps one already held with other bytes, or contradicts the known end,
//!   belongs to another datagram: the waiting one is given up (`replaced`) and the fragment
//!   starts a new one; an identical copy is a duplicate and ignored;
//! - a waiting datagram expires [`MAX_AGE_NS`] of capture time after its first fragment, or
//!   once [`MAX_AGE_FRAGMENTS`] fragments of other datagrams have come since its last one
//!   (`expired`): a reused IP ID is 65,536 datagrams later;
//! - at most [`MAX_WAITING`] datagrams and [`MAX_BYTES`] bytes wait; past that the one whose
//!   last fragment is oldest is given up (`evicted`);
//! - a complete UDP datagram with a checksum is checked against it (`checksum`): fragments of
//!   two datagrams would have to agree on 16 bits by chance.
//!
//! Every datagram given up is counted in [`FragmentCounts`], for the capture's warnings.

use std::collections::HashMap;
use std::net::IpAddr;

/// Capture time a datagram may wait for its fragments after the first one arrived, ns. A
/// sensor sends a datagram's fragments back to back, within microseconds.
pub const MAX_AGE_NS: u64 = 2_000_000_000;
/// Fragments of other datagrams after which a datagram still waiting is given up.
pub const MAX_AGE_FRAGMENTS: u64 = 4096;
/// Datagrams waiting at once, at most.
pub const MAX_WAITING: usize = 64;
/// Bytes of waiting datagrams, at most (64 full-size IPv4 datagrams).
pub const MAX_BYTES: usize = 64 * 65_535;
/// Largest datagram reassembled: an IPv4 total length (IPv6 jumbograms are not fragmented).
const MAX_DATAGRAM: usize = 65_535;
/// UDP's IP protocol number.
const UDP: u8 = 17;

/// What the fragments of one datagram share.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Key {
    /// Sender.
    pub source: IpAddr,
    /// Receiver.
    pub destination: IpAddr,
    /// IP protocol of the payload (17: UDP).
    pub protocol: u8,
    /// IP identification (16 bits in IPv4, 32 in IPv6).
    pub id: u32,
    /// VLAN ids, outer and inner (0 without).
    pub vlan: (u16, u16),
    /// Capture interface (pcapng; 0 otherwise).
    pub interface: u32,
}

/// One fragment.
#[derive(Clone, Copy, Debug)]
pub struct Fragment<'a> {
    /// Byte offset in the datagram's payload (a multiple of 8).
    pub offset: usize,
    /// Whether more fragments follow (the IP "more fragments" flag).
    pub more: bool,
    /// The fragment's bytes.
    pub bytes: &'a [u8],
}

/// What became of fragments, for the capture's report.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FragmentCounts {
    /// Fragments taken.
    pub fragments: u64,
    /// Datagrams completed and handed on.
    pub datagrams: u64,
    /// Fragments identical to one already held (ignored).
    pub duplicates: u64,
    /// Datagrams given up waiting too long (capture time or fragments since).
    pub expired: u64,
    /// Datagrams given up to make room.
    pub evicted: u64,
    /// Datagrams given up for a fragment that cannot be theirs (the IP ID reused).
    pub replaced: u64,
    /// Datagrams still incomplete at the end of the capture.
    pub unfinished: u64,
    /// Fragments that fit no datagram (unaligned, beyond 65,535 bytes, empty).
    pub malformed: u64,
    /// Completed UDP datagrams whose checksum is wrong (fragments of two datagrams?): dropped.
    pub checksum: u64,
}

impl FragmentCounts {
    /// Datagrams given up incomplete, for whatever reason.
    pub fn incomplete(&self) -> u64 {
        self.expired + self.evicted + self.replaced + self.unfinished
    }

    /// One line per kind of loss, empty when nothing was lost.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        if self.incomplete() > 0 {
            let parts: Vec<String> = [
                (self.expired, "expired waiting"),
                (self.evicted, "given up for room"),
                (
                    self.replaced,
                    "superseded by another datagram with the same IP ID",
                ),
                (self.unfinished, "incomplete at the end of the capture"),
            ]
            .iter()
            .filter(|(n, _)| *n > 0)
            .map(|(n, what)| format!("{n} {what}"))
            .collect();
            w.push(format!(
                "{} fragmented IP datagram(s) dropped, a fragment never came ({}): their \
                 packets count as lost",
                self.incomplete(),
                parts.join(", ")
            ));
        }
        if self.checksum > 0 {
            w.push(format!(
                "{} reassembled UDP datagram(s) failed their checksum (fragments of two \
                 datagrams?): dropped",
                self.checksum
            ));
        }
        if self.malformed > 0 {
            w.push(format!(
                "{} malformed IP fragment(s) skipped (unaligned, empty or beyond 65,535 bytes)",
                self.malformed
            ));
        }
        w
    }
}

/// A datagram waiting for fragments.
struct Waiting {
    /// The payload so far; bytes not yet received are zero.
    data: Vec<u8>,
    /// Received byte ranges, sorted, disjoint.
    have: Vec<(usize, usize)>,
    /// Payload length, once the last fragment came.
    end: Option<usize>,
    first_ns: u64,
    /// Fragment counter at its last fragment.
    last_seen: u64,
}

impl Waiting {
    fn new(first_ns: u64, seen: u64) -> Self {
        Self {
            data: Vec::new(),
            have: Vec::new(),
            end: None,
            first_ns,
            last_seen: seen,
        }
    }

    fn complete(&self) -> bool {
        matches!((self.end, self.have.as_slice()), (Some(e), [(0, b)]) if *b == e)
    }
}

/// What adding a fragment to a waiting datagram found.
enum Added {
    Taken,
    Duplicate,
    /// The fragment belongs to another datagram.
    Conflict,
}

impl Waiting {
    fn add(&mut self, f: &Fragment<'_>) -> Added {
        let (start, end) = (f.offset, f.offset + f.bytes.len());
        match self.end {
            Some(e) if end > e || (!f.more && end != e) => return Added::Conflict,
            None if !f.more && self.have.last().is_some_and(|&(_, b)| b > end) => {
                return Added::Conflict
            }
            _ => {}
        }
        for &(a, b) in &self.have {
            if start < b && a < end {
                // An exact copy of bytes held is a duplicate; anything else overlapping is
                // another datagram's.
                let same = a <= start && end <= b && self.data.get(start..end) == Some(f.bytes);
                return if same {
                    Added::Duplicate
                } else {
                    Added::Conflict
                };
            }
        }
        if self.data.len() < end {
            self.data.resize(end, 0);
        }
        self.data[start..end].copy_from_slice(f.bytes);
        let at = self.have.partition_point(|&(a, _)| a < start);
        self.have.insert(at, (start, end));
        // Merge touching neighbours.
        let mut merged: Vec<(usize, usize)> = Vec::with_capacity(self.have.len());
        for &(a, b) in &self.have {
            match merged.last_mut() {
                Some(last) if last.1 == a => last.1 = b,
                _ => merged.push((a, b)),
            }
        }
        self.have = merged;
        if !f.more {
            self.end = Some(end);
        }
        Added::Taken
    }
}

/// A complete datagram's payload.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Whole {
    /// IP protocol of the payload.
    pub protocol: u8,
    /// The reassembled payload (the UDP header first, for UDP).
    pub payload: Vec<u8>,
}

/// Datagrams being reassembled (see the module doc for the rules).
#[derive(Default)]
pub struct Reassembly {
    waiting: HashMap<Key, Waiting>,
    bytes: usize,
    seen: u64,
    counts: FragmentCounts,
}

impl Reassembly {
    /// An empty pool.
    pub fn new() -> Self {
        Self::default()
    }

    /// What became of the fragments so far.
    pub fn counts(&self) -> &FragmentCounts {
        &self.counts
    }

    /// Datagrams waiting and the bytes they hold.
    pub fn held(&self) -> (usize, usize) {
        (self.waiting.len(), self.bytes)
    }

    /// Adds a fragment captured at `time_ns`; the datagram's payload when it completes it.
    pub fn add(&mut self, key: Key, time_ns: u64, f: Fragment<'_>) -> Option<Whole> {
        self.counts.fragments += 1;
        self.seen += 1;
        let end = f.offset.checked_add(f.bytes.len());
        let aligned = !f.more || f.bytes.len() % 8 == 0;
        if f.bytes.is_empty() || !aligned || end.is_none_or(|e| e > MAX_DATAGRAM) {
            self.counts.malformed += 1;
            return None;
        }
        self.expire(time_ns);
        let fresh = |seen| {
            let mut w = Waiting::new(time_ns, seen);
            w.add(&f);
            w
        };
        let mut w = match self.waiting.remove(&key) {
            None => fresh(self.seen),
            Some(mut w) => {
                self.bytes -= w.data.len();
                match w.add(&f) {
                    Added::Taken => w,
                    Added::Duplicate => {
                        self.counts.duplicates += 1;
                        w.last_seen = self.seen;
                        self.bytes += w.data.len();
                        self.waiting.insert(key, w);
                        return None;
                    }
                    Added::Conflict => {
                        self.counts.replaced += 1;
                        fresh(self.seen)
                    }
                }
            }
        };
        w.last_seen = self.seen;
        if w.complete() {
            return self.finish(key, w);
        }
        self.make_room(w.data.len());
        self.bytes += w.data.len();
        self.waiting.insert(key, w);
        None
    }

    /// Counts the datagrams still waiting as unfinished (the capture ended) and drops them.
    pub fn end(&mut self) {
        self.counts.unfinished += self.waiting.len() as u64;
        self.waiting.clear();
        self.bytes = 0;
    }

    fn finish(&mut self, key: Key, w: Waiting) -> Option<Whole> {
        if key.protocol == UDP && !udp_checksum_holds(&key, &w.data) {
            self.counts.checksum += 1;
            return None;
        }
        self.counts.datagrams += 1;
        Some(Whole {
            protocol: key.protocol,
            payload: w.data,
        })
    }

    fn expire(&mut self, now_ns: u64) {
        let seen = self.seen;
        let before = self.waiting.len();
        let mut freed = 0;
        self.waiting.retain(|_, w| {
            let keep = now_ns.abs_diff(w.first_ns) <= MAX_AGE_NS
                && seen - w.last_seen <= MAX_AGE_FRAGMENTS;
            if !keep {
                freed += w.data.len();
            }
            keep
        });
        self.bytes -= freed;
        self.counts.expired += (before - self.waiting.len()) as u64;
    }

    /// Gives up the datagrams whose last fragment is oldest until `more` bytes and one more
    /// datagram fit.
    fn make_room(&mut self, more: usize) {
        while !self.waiting.is_empty()
            && (self.waiting.len() >= MAX_WAITING || self.bytes + more > MAX_BYTES)
        {
            let Some(oldest) = self
                .waiting
                .iter()
                .min_by_key(|(_, w)| w.last_seen)
                .map(|(k, _)| *k)
            else {
                break;
            };
            if let Some(w) = self.waiting.remove(&oldest) {
                self.bytes -= w.data.len();
                self.counts.evicted += 1;
            }
        }
    }
}

/// Whether a reassembled UDP datagram's checksum holds (a zero checksum is "none" in IPv4).
fn udp_checksum_holds(key: &Key, datagram: &[u8]) -> bool {
    let Ok((header, payload)) = etherparse::UdpHeader::from_slice(datagram) else {
        // Not even a UDP header: the caller's UDP parsing names it.
        return true;
    };
    if header.checksum == 0 {
        return true;
    }
    let payload = payload
        .get(..usize::from(header.length).saturating_sub(8))
        .unwrap_or(payload);
    let computed = match (key.source, key.destination) {
        (IpAddr::V4(s), IpAddr::V4(d)) => {
            header.calc_checksum_ipv4_raw(s.octets(), d.octets(), payload)
        }
        (IpAddr::V6(s), IpAddr::V6(d)) => {
            header.calc_checksum_ipv6_raw(s.octets(), d.octets(), payload)
        }
        _ => return true,
    };
    computed.is_ok_and(|c| c == header.checksum)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(id: u32) -> Key {
        Key {
            source: "10.0.0.1".parse().unwrap(),
            destination: "10.0.0.2".parse().unwrap(),
            protocol: 99,
            id,
            vlan: (0, 0),
            interface: 0,
        }
    }

    fn frag(offset: usize, more: bool, bytes: &[u8]) -> Fragment<'_> {
        Fragment {
            offset,
            more,
            bytes,
        }
    }

    #[test]
    fn fragments_in_any_order_make_the_datagram() {
        let a = [1u8; 16];
        let b = [2u8; 16];
        let c = [3u8; 5];
        let mut r = Reassembly::new();
        assert!(r.add(key(1), 0, frag(16, true, &b)).is_none());
        assert!(r.add(key(1), 0, frag(32, false, &c)).is_none());
        assert!(r.add(key(1), 0, frag(16, true, &b)).is_none(), "duplicate");
        let w = r.add(key(1), 0, frag(0, true, &a)).unwrap();
        assert_eq!(w.payload, [&a[..], &b[..], &c[..]].concat());
        assert_eq!(r.counts().duplicates, 1);
        assert_eq!(r.held(), (0, 0));
    }

    #[test]
    fn a_reused_id_never_completes_the_waiting_datagram() {
        // Datagram A lacks its middle fragment; B reuses the ID and is whole.
        let (a0, a2) = ([1u8; 8], [1u8; 3]);
        let (b0, b1, b2) = ([5u8; 8], [6u8; 8], [7u8; 3]);
        let mut r = Reassembly::new();
        r.add(key(9), 0, frag(0, true, &a0));
        r.add(key(9), 0, frag(16, false, &a2));
        assert!(r.add(key(9), 10, frag(0, true, &b0)).is_none());
        assert!(r.add(key(9), 10, frag(8, true, &b1)).is_none());
        let w = r.add(key(9), 10, frag(16, false, &b2)).unwrap();
        assert_eq!(w.payload, [&b0[..], &b1[..], &b2[..]].concat());
        assert_eq!(r.counts().replaced, 1);
    }

    #[test]
    fn waiting_datagrams_expire_by_time_by_fragments_since_and_by_room() {
        let mut r = Reassembly::new();
        r.add(key(1), 0, frag(0, true, &[0; 8]));
        r.add(key(2), MAX_AGE_NS + 1, frag(0, true, &[0; 8]));
        assert_eq!(r.counts().expired, 1);
        for id in 3..(3 + MAX_AGE_FRAGMENTS as u32 + 1) {
            r.add(key(id), MAX_AGE_NS + 1, frag(0, true, &[0; 8]));
        }
        assert!(r.held().0 <= MAX_WAITING);
        assert!(r.counts().evicted > 0);
        let held = r.held().0 as u64;
        r.end();
        let c = r.counts();
        assert_eq!(c.unfinished, held);
        assert_eq!(c.incomplete(), c.fragments, "{c:?}");
        assert_eq!(r.held(), (0, 0));
    }

    #[test]
    fn the_bytes_held_stay_bounded_and_are_accounted() {
        let mut r = Reassembly::new();
        let big = vec![0u8; 60_000];
        for id in 0..200 {
            r.add(key(id), 0, frag(0, true, &big));
            let (n, bytes) = r.held();
            let sum: usize = r.waiting.values().map(|w| w.data.len()).sum();
            assert_eq!(bytes, sum);
            assert!(n <= MAX_WAITING && bytes <= MAX_BYTES);
        }
    }

    #[test]
    fn malformed_fragments_are_counted_not_held() {
        let mut r = Reassembly::new();
        r.add(key(1), 0, frag(0, true, &[0; 7]));
        r.add(key(1), 0, frag(65_530, false, &[0; 8]));
        r.add(key(1), 0, frag(0, false, &[]));
        assert_eq!(r.counts().malformed, 3);
        assert_eq!(r.held(), (0, 0));
    }
}
