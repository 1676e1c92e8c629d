//! Packet captures and IP reassembly (`io::capture::pcap`). The first byte picks what the rest is:
//! fragments fed straight to the reassembly pool; the blocks of a pcapng whose interfaces
//! (1 to 4) have link types, snap lengths, `if_tsresol` and `if_tsoffset` from the input and
//! whose packets name any interface, even one never described; or the records of a pcap of a
//! link type from the input. Captures are read to the end through a scratch file. Asserts
//! that nothing panics, that the pool never holds more than its bounds, that a datagram it
//! completes holds only its own key's bytes, and that no datagram is longer than UDP allows.
#![no_main]

mod common;

use kiss_odom_io::capture::pcap::{self, Record};
use kiss_odom_io::capture::reassembly::{Fragment, Key, Reassembly, MAX_BYTES, MAX_WAITING};
use libfuzzer_sys::fuzz_target;

/// Link types tried: read ones (Ethernet, SLL, SLL2, raw IP as 101/12/228/229, BSD
/// loopback) and one that is not (IEEE 802.11).
const LINKS: [u32; 9] = [1, 113, 276, 101, 12, 228, 229, 0, 105];
/// Records read from a capture, at most.
const MAX_RECORDS: usize = 4096;

fuzz_target!(|data: &[u8]| {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    match mode % 3 {
        0 => reassemble(rest),
        1 => read(&pcapng(rest)),
        _ => read(&pcap(LINKS[usize::from(mode / 3) % LINKS.len()], rest)),
    }
});

/// Ops of 6 bytes: key, offset (2, in units of 8 bytes), more-fragments flag and length,
/// capture time (2, ms). A fragment's bytes are its key's tag.
fn reassemble(data: &[u8]) {
    let mut pool = Reassembly::new();
    let key = |k: u8| Key {
        source: std::net::IpAddr::from([10, 0, 0, k % 4]),
        destination: std::net::IpAddr::from([10, 0, 0, 9]),
        protocol: if k & 0x80 != 0 { 17 } else { 99 },
        id: u32::from(k % 8),
        vlan: (0, 0),
        interface: 0,
    };
    for op in data.chunks_exact(6) {
        let k = key(op[0]);
        let tag = op[0] % 8;
        let offset = usize::from(u16::from_le_bytes([op[1], op[2]])) * 8;
        let more = op[3] & 0x80 != 0;
        let len = usize::from(op[3] & 0x7F) * 37 % 2000;
        let time_ns = u64::from(u16::from_le_bytes([op[4], op[5]])) * 1_000_000;
        let bytes = vec![tag; len];
        let whole = pool.add(
            k,
            time_ns,
            Fragment {
                offset,
                more,
                bytes: &bytes,
            },
        );
        let (waiting, held) = pool.held();
        assert!(waiting <= MAX_WAITING && held <= MAX_BYTES);
        if let Some(w) = whole.filter(|w| w.protocol != 17) {
            assert!(w.payload.iter().all(|&b| b == tag), "bytes of another key");
        }
    }
    pool.end();
    assert_eq!(pool.held(), (0, 0));
}

fn block(kind: u32, body: &[u8]) -> Vec<u8> {
    let padded = body.len().div_ceil(4) * 4;
    let len = (12 + padded) as u32;
    let mut b = kind.to_le_bytes().to_vec();
    b.extend_from_slice(&len.to_le_bytes());
    b.extend_from_slice(body);
    b.resize(8 + padded, 0);
    b.extend_from_slice(&len.to_le_bytes());
    b
}

/// A little-endian pcapng: a section header, interfaces described by the first byte and
/// those after it, then enhanced packet blocks of 14-byte headers (interface, timestamp 8,
/// captured length 2, original length 2, the original-length's padding byte) and data.
fn pcapng(data: &[u8]) -> Vec<u8> {
    let mut shb = 0x1A2B_3C4Du32.to_le_bytes().to_vec();
    shb.extend_from_slice(&[1, 0, 0, 0]);
    shb.extend_from_slice(&u64::MAX.to_le_bytes());
    let mut out = block(0x0A0D_0D0A, &shb);
    let Some((&n, mut rest)) = data.split_first() else {
        return out;
    };
    for _ in 0..=(n % 4) {
        let Some((idb, tail)) = rest.split_first_chunk::<4>() else {
            return out;
        };
        rest = tail;
        let link = LINKS[usize::from(idb[0]) % LINKS.len()] as u16;
        let mut body = link.to_le_bytes().to_vec();
        body.extend_from_slice(&[0, 0]);
        body.extend_from_slice(&(u32::from(idb[1]) * 64).to_le_bytes());
        // if_tsresol, then (sometimes) if_tsoffset, then the end of options.
        body.extend_from_slice(&[9, 0, 1, 0, idb[2], 0, 0, 0]);
        if idb[3] & 1 != 0 {
            body.extend_from_slice(&[14, 0, 8, 0]);
            body.extend_from_slice(&(i64::from(idb[3] as i8) * 1000).to_le_bytes());
        }
        body.extend_from_slice(&[0, 0, 0, 0]);
        out.extend(block(1, &body));
    }
    while let Some((h, tail)) = rest.split_first_chunk::<14>() {
        let captured = usize::from(u16::from_le_bytes([h[9], h[10]])).min(tail.len());
        let (packet, tail) = tail.split_at(captured);
        rest = tail;
        let mut body = u32::from(h[0] % 5).to_le_bytes().to_vec();
        body.extend_from_slice(&h[5..9]);
        body.extend_from_slice(&h[1..5]);
        body.extend_from_slice(&(captured as u32).to_le_bytes());
        let original = captured + usize::from(u16::from_le_bytes([h[11], h[12]])) % 64;
        body.extend_from_slice(&(original as u32).to_le_bytes());
        body.extend_from_slice(packet);
        out.extend(block(6, &body));
    }
    out
}

/// A microsecond pcap of link type `link`: records of a 2-byte length and that many bytes.
fn pcap(link: u32, data: &[u8]) -> Vec<u8> {
    let mut out = 0xA1B2_C3D4u32.to_le_bytes().to_vec();
    out.extend_from_slice(&[2, 0, 4, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
    out.extend_from_slice(&65535u32.to_le_bytes());
    out.extend_from_slice(&link.to_le_bytes());
    let mut rest = data;
    let mut t = 0u32;
    while let Some((h, tail)) = rest.split_first_chunk::<2>() {
        let n = usize::from(u16::from_le_bytes(*h)).min(tail.len());
        let (packet, tail) = tail.split_at(n);
        rest = tail;
        t += 1;
        out.extend_from_slice(&t.to_le_bytes());
        out.extend_from_slice(&0u32.to_le_bytes());
        out.extend_from_slice(&(n as u32).to_le_bytes());
        out.extend_from_slice(&(n as u32 + u32::from(h[0] & 1) * 10).to_le_bytes());
        out.extend_from_slice(packet);
    }
    out
}

fn read(bytes: &[u8]) {
    let path = common::scratch_file("capture.pcap", bytes);
    let Ok(mut capture) = pcap::open(&path) else {
        return;
    };
    for _ in 0..MAX_RECORDS {
        match capture.next_record() {
            Ok(Some(Record::Datagram(d))) => assert!(d.payload.len() <= 65_535 - 8),
            Ok(Some(Record::Damaged { .. })) => {}
            Ok(None) | Err(_) => break,
        }
    }
    let c = capture.counts();
    assert!(c.datagrams + c.damaged <= c.frames);
    let _ = c.warnings();
}
