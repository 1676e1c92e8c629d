//! Tests of `pcap`.

use super::*;

fn datagrams() -> Vec<Datagram> {
    (0..3)
        .map(|i| Datagram {
            time_ns: 1_000_000_000 + i * 1000,
            source: "192.168.1.201:2368".parse().unwrap(),
            port: 2368 + i as u16,
            payload: (0..3000u32).map(|b| (b * (i as u32 + 1)) as u8).collect(),
        })
        .collect()
}

#[test]
fn written_datagrams_read_back_through_fragmentation() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.pcap");
    write(&path, &datagrams(), 1500).unwrap();
    let mut cap = open(&path).unwrap();
    let back: Vec<_> = cap.by_ref().map(|d| d.unwrap()).collect();
    assert_eq!(back, datagrams());
    assert_eq!(cap.counts().reassembly.fragments, 9);
}

#[test]
fn pcapng_captures_read_like_pcap_ones() {
    use pcap_file::pcapng::blocks::enhanced_packet::EnhancedPacketBlock;
    use pcap_file::pcapng::blocks::interface_description::InterfaceDescriptionBlock;
    use pcap_file::pcapng::PcapNgWriter;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.pcapng");
    let mut w = PcapNgWriter::new(File::create(&path).unwrap()).unwrap();
    w.write_pcapng_block(InterfaceDescriptionBlock {
        linktype: DataLink::ETHERNET,
        snaplen: 65535,
        options: vec![],
    })
    .unwrap();
    for (i, d) in datagrams().iter().enumerate() {
        for f in ipv4_packets(d, i as u16, 1500).unwrap() {
            let f = ethernet(&f);
            w.write_pcapng_block(EnhancedPacketBlock {
                interface_id: 0,
                timestamp: std::time::Duration::from_nanos(d.time_ns),
                original_len: f.len() as u32,
                data: f.into(),
                options: vec![],
            })
            .unwrap();
        }
    }
    drop(w);
    let back: Vec<_> = open(&path).unwrap().map(|d| d.unwrap()).collect();
    assert_eq!(back.len(), 3);
    for (a, b) in back.iter().zip(datagrams()) {
        assert_eq!(
            (a.source, a.port, &a.payload),
            (b.source, b.port, &b.payload)
        );
    }
}

#[test]
fn a_cut_capture_yields_what_came_before_then_names_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cut.pcap");
    write(&path, &datagrams(), 9000).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..bytes.len() - 100]).unwrap();
    let mut cap = open(&path).unwrap();
    assert!(cap.next_datagram().unwrap().is_some());
    assert!(cap.next_datagram().unwrap().is_some());
    let e = cap.next_datagram().unwrap_err().to_string();
    assert!(
        e.contains("cut.pcap") && e.contains("cut in the middle"),
        "{e}"
    );
}

#[test]
fn non_captures_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("notes.txt");
    std::fs::write(&path, "hello world").unwrap();
    let e = open(&path).err().unwrap().to_string();
    assert!(e.contains("notes.txt") && e.contains("not a pcap"), "{e}");
}

#[test]
fn pcapng_clocks_read_every_resolution_and_offset() {
    let clock = |resolution, offset_s| Clock {
        resolution,
        offset_s,
    };
    assert_eq!(Clock::DEFAULT.ns(1_500_000), 1_500_000_000, "microseconds");
    assert_eq!(clock(9, 0).ns(7), 7);
    assert_eq!(clock(3, -1).ns(2500), 1_500_000_000);
    assert_eq!(clock(12, 0).ns(5_000), 5);
    assert_eq!(clock(0x80 | 10, 0).ns(1024), 1_000_000_000, "2^-10 s");
    // Beyond what u64 nanoseconds hold, or before the epoch: saturated, never wrapped.
    assert_eq!(clock(0, 0).ns(u64::MAX), u64::MAX);
    assert_eq!(clock(6, -10).ns(1), 0);
    assert_eq!(clock(127, 0).ns(u64::MAX), 0);
    assert_eq!(clock(0xFF, 0).ns(u64::MAX), 0);
}

/// `d` as IPv6 fragments of at most `mtu` bytes of payload (a multiple of 8).
fn ipv6_fragments(d: &Datagram, mtu: usize) -> Vec<Vec<u8>> {
    use etherparse::{IpNumber, Ipv6Header, UdpHeader};
    let (src, dst) = ([0xfe, 0x80].repeat(8), [0xfe, 0x81].repeat(8));
    let (src, dst): ([u8; 16], [u8; 16]) = (src.try_into().unwrap(), dst.try_into().unwrap());
    let udp = UdpHeader::with_ipv6_checksum(
        d.source.port(),
        d.port,
        &Ipv6Header {
            source: src,
            destination: dst,
            ..Default::default()
        },
        &d.payload,
    )
    .unwrap();
    let mut body = udp.to_bytes().to_vec();
    body.extend_from_slice(&d.payload);
    body.chunks(mtu)
        .enumerate()
        .map(|(k, piece)| {
            // RFC 8200: offset (8-byte units) in the top 13 bits, M the lowest bit (written
            // here by hand: etherparse 0.16 puts them elsewhere).
            let units = (k * mtu / 8) as u16;
            let more = u16::from((k + 1) * mtu < body.len());
            let mut frag = vec![17, 0];
            frag.extend_from_slice(&(units << 3 | more).to_be_bytes());
            frag.extend_from_slice(&77u32.to_be_bytes());
            let ip = Ipv6Header {
                payload_length: (8 + piece.len()) as u16,
                next_header: IpNumber::IPV6_FRAGMENTATION_HEADER,
                hop_limit: 64,
                source: src,
                destination: dst,
                ..Default::default()
            };
            let mut f = ip.to_bytes().to_vec();
            f.extend_from_slice(&frag);
            f.extend_from_slice(piece);
            f
        })
        .collect()
}

#[test]
fn cooked_raw_and_ipv6_fragmented_frames_read_back() {
    let dir = tempfile::tempdir().unwrap();
    let d = datagrams();
    let sll = |ip: &[u8], proto: [u8; 2]| {
        let mut f = vec![0, 0, 0, 1, 0, 6, 2, 0, 0, 0, 0, 1, 0, 0];
        f.extend_from_slice(&proto);
        f.extend_from_slice(ip);
        f
    };
    for (link, wrap) in [
        (
            DataLink::LINUX_SLL,
            &(|ip: &[u8]| sll(ip, [0x08, 0x00])) as &dyn Fn(&[u8]) -> Vec<u8>,
        ),
        (DataLink::Unknown(12), &|ip: &[u8]| ip.to_vec()),
        (DataLink::NULL, &|ip: &[u8]| [&[2, 0, 0, 0], ip].concat()),
    ] {
        let frames: Vec<(u64, Vec<u8>)> = d
            .iter()
            .enumerate()
            .flat_map(|(k, d)| {
                ipv4_packets(d, k as u16, 1500)
                    .unwrap()
                    .into_iter()
                    .map(|ip| (d.time_ns, wrap(&ip)))
                    .collect::<Vec<_>>()
            })
            .collect();
        let path = dir.path().join("x.pcap");
        write_frames(&path, link, &frames).unwrap();
        let back: Vec<_> = open(&path).unwrap().map(|d| d.unwrap()).collect();
        assert_eq!(back, d, "{link:?}");
    }
    let frames: Vec<(u64, Vec<u8>)> = ipv6_fragments(&d[0], 1232)
        .into_iter()
        .rev()
        .map(|ip| (5, [&[0x86, 0xDD], &ip[..]].concat()))
        .map(|(t, f)| (t, sll(&f[2..], [0x86, 0xDD])))
        .collect();
    let path = dir.path().join("v6.pcap");
    write_frames(&path, DataLink::LINUX_SLL, &frames).unwrap();
    let mut cap = open(&path).unwrap();
    let back = cap.next_datagram().unwrap().unwrap();
    assert_eq!((back.payload.len(), back.port), (3000, 2368));
    assert_eq!(back.payload, d[0].payload);
    assert_eq!(cap.counts().reassembly.datagrams, 1);
}

#[test]
fn ipv6_extension_chains_are_walked_within_their_bytes() {
    use super::ipv6_fragment;
    // Hop-by-hop (8 bytes, next: fragment), then a fragment at 1480 bytes, more to come.
    let mut chain = vec![44, 0, 0, 0, 0, 0, 0, 0];
    chain.extend([17, 0, 0x05, 0xC9, 0, 0, 0x12, 0x34]);
    assert_eq!(ipv6_fragment(Some(0), &chain), Some((1480, true, 0x1234)));
    // The first fragment (offset 0, more) fragments; a lone fragment header (0, none) not.
    assert_eq!(
        ipv6_fragment(Some(44), &[17, 0, 0, 1, 0, 0, 0, 9]),
        Some((0, true, 9))
    );
    assert_eq!(ipv6_fragment(Some(44), &[17, 0, 0, 0, 0, 0, 0, 9]), None);
    // An authentication header counts in 4-byte units, plus 2.
    let mut auth = vec![44, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0];
    auth.extend([17, 0, 0x00, 0x11, 0, 0, 0, 7]);
    assert_eq!(ipv6_fragment(Some(51), &auth), Some((16, true, 7)));
    // A chain that announces more than its bytes hold, or a header cut short: no fragment,
    // and no read beyond the slice (etherparse 0.16's iterator reads past it here).
    assert_eq!(ipv6_fragment(Some(0), &chain[..8]), None);
    assert_eq!(ipv6_fragment(Some(0), &[44, 9, 0, 0]), None);
    assert_eq!(ipv6_fragment(Some(44), &[17, 0, 0]), None);
    assert_eq!(ipv6_fragment(Some(60), &[]), None);
    // UDP after the extensions, or none at all: not fragmented.
    assert_eq!(ipv6_fragment(Some(0), &[17, 0, 0, 0, 0, 0, 0, 0]), None);
    assert_eq!(ipv6_fragment(None, &chain), None);
}
