//! Captures built for the sensor-path tests: simulated recordings (`kiss-odom simulate
//! --format pcap`, real packets of a moving VLP-16 or OS1-64), their datagrams edited and
//! written back as Ethernet, other link layers, pcapng with chosen interfaces, or IPv4
//! fragments with chosen IP IDs.

#![allow(dead_code)] // each test file uses its own share

use kiss_odom_io::capture::pcap::{self, Datagram};
use pcap_file::pcap::{PcapHeader, PcapPacket, PcapWriter};
use pcap_file::DataLink;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// `kiss-odom simulate --sensor SENSOR --format pcap --frames N` into `dir/name`: the
/// folder (`packets.pcap`, and `packets.json` for the OS1-64).
pub fn simulate(dir: &Path, name: &str, sensor: &str, frames: usize, seed: u64) -> PathBuf {
    let out = dir.join(name);
    let args: Vec<std::ffi::OsString> = [
        "simulate",
        "--sensor",
        sensor,
        "--format",
        "pcap",
        "--frames",
        &frames.to_string(),
        "--seed",
        &seed.to_string(),
        "--out",
        out.to_str().unwrap(),
    ]
    .map(Into::into)
    .to_vec();
    let r = kiss_odom_tests::kiss_odom(&args, &out);
    assert_eq!(r.code, 0, "simulate: {}", r.stderr);
    out
}

/// Every UDP datagram of a capture.
pub fn datagrams(path: &Path) -> Vec<Datagram> {
    pcap::open(path).unwrap().map(Result::unwrap).collect()
}

/// IPv4 packets carrying `d` to 192.168.1.2, fragments of at most `mtu` bytes with IP ID
/// `id`, the UDP checksum set as a sender's stack sets it.
pub fn ipv4(d: &Datagram, id: u16, mtu: usize) -> Vec<Vec<u8>> {
    use etherparse::{IpFragOffset, IpNumber, Ipv4Header, UdpHeader};
    let std::net::IpAddr::V4(src) = d.source.ip() else {
        panic!("IPv4 senders only")
    };
    let dst = [192, 168, 1, 2];
    let header = Ipv4Header::new(0, 64, IpNumber::UDP, src.octets(), dst).unwrap();
    let udp = UdpHeader::with_ipv4_checksum(d.source.port(), d.port, &header, &d.payload).unwrap();
    let mut body = udp.to_bytes().to_vec();
    body.extend_from_slice(&d.payload);
    let step = (mtu - Ipv4Header::MIN_LEN) / 8 * 8;
    body.chunks(step)
        .enumerate()
        .map(|(k, piece)| {
            let mut ip =
                Ipv4Header::new(piece.len() as u16, 64, IpNumber::UDP, src.octets(), dst).unwrap();
            ip.identification = id;
            ip.more_fragments = (k + 1) * step < body.len();
            ip.fragment_offset = IpFragOffset::try_new((k * step / 8) as u16).unwrap();
            ip.header_checksum = ip.calc_header_checksum();
            let mut f = ip.to_bytes().to_vec();
            f.extend_from_slice(piece);
            f
        })
        .collect()
}

/// An IPv4 packet in an Ethernet II frame.
pub fn ethernet(ip: &[u8]) -> Vec<u8> {
    let mut f = vec![0xff; 6];
    f.extend_from_slice(&[2, 0, 0, 0, 0, 1, 0x08, 0x00]);
    f.extend_from_slice(ip);
    f
}

/// One frame to write: capture time, the bytes kept, the length on the wire.
pub struct Frame {
    pub time_ns: u64,
    pub data: Vec<u8>,
    pub original: usize,
}

impl Frame {
    pub fn whole(time_ns: u64, data: Vec<u8>) -> Self {
        let original = data.len();
        Self {
            time_ns,
            data,
            original,
        }
    }
}

/// A microsecond pcap being written, frame by frame (so that a large one never sits in
/// memory).
pub struct PcapOut(PcapWriter<std::io::BufWriter<std::fs::File>>);

impl PcapOut {
    /// A pcap at `path` with link type `link` (its number, so unnamed ones too).
    pub fn create(path: &Path, link: u32) -> Self {
        let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
        let header = PcapHeader {
            snaplen: 65535,
            datalink: DataLink::from(link),
            ..PcapHeader::default()
        };
        Self(PcapWriter::with_header(file, header).unwrap())
    }

    pub fn push(&mut self, f: &Frame) {
        let t = Duration::from_nanos(f.time_ns);
        self.0
            .write_packet(&PcapPacket::new(t, f.original as u32, &f.data))
            .unwrap();
    }
}

/// A microsecond pcap of `frames` with link type `link`.
pub fn write_pcap(path: &Path, link: u32, frames: &[Frame]) {
    let mut w = PcapOut::create(path, link);
    for f in frames {
        w.push(f);
    }
}

/// The datagrams as Ethernet frames, one IPv4 packet each (IP ID = index).
pub fn ethernet_frames(d: &[Datagram]) -> Vec<Frame> {
    d.iter()
        .enumerate()
        .flat_map(|(k, d)| {
            ipv4(d, k as u16, 65_000)
                .into_iter()
                .map(move |ip| Frame::whole(d.time_ns, ethernet(&ip)))
        })
        .collect()
}

/// Velodyne packet fields (the 1206-byte data packet).
pub mod velodyne {
    /// Azimuth of block `b`, hundredths of a degree.
    pub fn azimuth(p: &[u8], b: usize) -> u16 {
        u16::from_le_bytes([p[100 * b + 2], p[100 * b + 3]])
    }
    pub fn set_azimuth(p: &mut [u8], b: usize, a: u16) {
        p[100 * b + 2..100 * b + 4].copy_from_slice(&a.to_le_bytes());
    }
    /// Microseconds past the hour.
    pub fn timestamp(p: &[u8]) -> u32 {
        u32::from_le_bytes(p[1200..1204].try_into().unwrap())
    }
    pub fn set_timestamp(p: &mut [u8], t: u32) {
        p[1200..1204].copy_from_slice(&t.to_le_bytes());
    }
    /// Whether the packet's last block wraps past azimuth 0 (with `--cut-angle 0` it ends
    /// its sweep).
    pub fn wraps(p: &[u8]) -> bool {
        azimuth(p, 11) < azimuth(p, 0)
    }
}

/// Ouster eUDP header fields.
pub mod ouster {
    pub fn frame_id(p: &[u8]) -> u16 {
        u16::from_le_bytes([p[2], p[3]])
    }
    pub fn set_frame_id(p: &mut [u8], f: u16) {
        p[2..4].copy_from_slice(&f.to_le_bytes());
    }
}
