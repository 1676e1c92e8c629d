//! `copper-dump hesai|livox FILE.pcap`: one CSV line per point the copper-rs parser decodes,
//! for the sensor tests to compare with ours. Only the parsers' public API is used; where the
//! crates turn it into points in code that is not public (cu-hesai's spherical-to-Cartesian
//! step), the same formula is applied to the parser's distance, azimuth and elevation.
//!
//! hesai: `packet,block,channel,x,y,z,reflectivity,block_ns` (metres in f32 as cu-hesai
//! computes them; the block's time by `Packet::block_ts`, ns since the Unix epoch).
//! livox: `packet,point,x,y,z,reflectivity,tag,packet_ns`.

use cu29::units::si::angle::radian;
use cu29::units::si::length::meter;
use std::io::Write;

/// UDP payloads of an Ethernet/IPv4 classic pcap, in order, with their destination port.
fn udp_payloads(bytes: &[u8]) -> Vec<(u16, &[u8])> {
    let mut out = Vec::new();
    let mut at = 24;
    while at + 16 <= bytes.len() {
        let caplen = u32::from_le_bytes(bytes[at + 8..at + 12].try_into().unwrap()) as usize;
        let frame = &bytes[at + 16..(at + 16 + caplen).min(bytes.len())];
        at += 16 + caplen;
        if frame.len() < 42 || frame[12..14] != [0x08, 0x00] || frame[23] != 17 {
            continue;
        }
        let ihl = usize::from(frame[14] & 0x0F) * 4;
        let udp = 14 + ihl;
        let port = u16::from_be_bytes([frame[udp + 2], frame[udp + 3]]);
        out.push((port, &frame[udp + 8..]));
    }
    out
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (Some(kind), Some(path)) = (args.get(1), args.get(2)) else {
        eprintln!("usage: copper-dump hesai|livox FILE.pcap");
        std::process::exit(2);
    };
    let bytes = std::fs::read(path).expect("read the pcap");
    let out = std::io::stdout();
    let mut out = std::io::BufWriter::new(out.lock());
    let mut refused = 0;
    match kind.as_str() {
        "hesai" => {
            let elevation = cu_hesai::parser::generate_default_elevation_calibration();
            let epoch = chrono::DateTime::<chrono::Utc>::UNIX_EPOCH;
            let reftime = (epoch, cu29::prelude::CuTime::from(0u64));
            let len = std::mem::size_of::<cu_hesai::parser::Packet>();
            for (n, (_, payload)) in udp_payloads(&bytes).iter().enumerate() {
                // cu-hesai's packet has no room for the UDP sequence number: its own test
                // hands it the first size_of::<Packet>() bytes, as here.
                let Ok(p) = cu_hesai::parser::parse_packet(&payload[..len.min(payload.len())])
                else {
                    refused += 1;
                    continue;
                };
                let times = p.block_ts(&reftime).expect("block times");
                for (b, block) in p.blocks.iter().enumerate() {
                    let az = block.azimuth().get::<radian>();
                    for (c, ch) in block.channels.iter().enumerate() {
                        let d = ch.distance().get::<meter>();
                        let e = elevation[c].get::<radian>();
                        let (x, y, z) = (d * e.cos() * az.cos(), d * e.cos() * az.sin(), d * e.sin());
                        let r = ch.reflectivity().value * 255.0;
                        writeln!(out, "{n},{b},{c},{x},{y},{z},{r},{}", times[b].0).unwrap();
                    }
                }
            }
        }
        "livox" => {
            for (n, (_, payload)) in udp_payloads(&bytes).iter().enumerate() {
                let Ok(f) = cu_livox::parser::parse_frame(payload) else {
                    refused += 1;
                    continue;
                };
                let t = f.header.timestamp().0;
                for (k, p) in f.points.iter().enumerate() {
                    let (x, y, z) = (p.x().get::<meter>(), p.y().get::<meter>(), p.z().get::<meter>());
                    let (r, tag) = (p.reflectivity, p.tag);
                    writeln!(out, "{n},{k},{x},{y},{z},{r},{tag},{t}").unwrap();
                }
            }
        }
        _ => {
            eprintln!("unknown kind {kind}: hesai or livox");
            std::process::exit(2);
        }
    }
    eprintln!("refused {refused}");
}
