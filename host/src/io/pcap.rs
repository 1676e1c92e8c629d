//! Packet captures (pcap and pcapng, as Wireshark, tcpdump, VeloView and `ouster-cli` write
//! them) to UDP datagrams: the input side of sensor recordings.
//!
//! Frames are Ethernet, Linux cooked (SLL), BSD loopback or raw IP; IPv4 fragments (an Ouster
//! packet is larger than a standard MTU) are reassembled; anything that is not UDP is
//! skipped and counted. A file cut in the middle yields the datagrams before the cut and then
//! an error naming the file.

use anyhow::{bail, Context, Result};
use etherparse::defrag::IpDefragPool;
use etherparse::{IpNumber, NetSlice, SlicedPacket, TransportSlice, UdpSlice};
use pcap_file::pcap::PcapReader;
use pcap_file::pcapng::{Block, PcapNgReader};
use pcap_file::DataLink;
use std::fs::File;
use std::io::BufReader;
use std::net::{IpAddr, SocketAddr};
use std::path::{Path, PathBuf};

/// One UDP datagram from a capture.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Datagram {
    /// Capture time, ns since the Unix epoch.
    pub time_ns: u64,
    /// Sender.
    pub source: SocketAddr,
    /// Destination port.
    pub port: u16,
    /// UDP payload.
    pub payload: Vec<u8>,
}

/// What a capture held besides UDP datagrams.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CaptureCounts {
    /// Link-layer frames read.
    pub frames: u64,
    /// UDP datagrams yielded (after reassembly).
    pub datagrams: u64,
    /// Frames that are not UDP, or whose headers do not parse (including frames cut by the
    /// capture's snap length).
    pub skipped: u64,
    /// IPv4/IPv6 fragments held for reassembly.
    pub fragments: u64,
}

enum Reader {
    Pcap(PcapReader<BufReader<File>>),
    PcapNg(PcapNgReader<BufReader<File>>),
}

/// A capture being read, datagram by datagram.
pub struct Capture {
    path: PathBuf,
    reader: Reader,
    defrag: IpDefragPool,
    counts: CaptureCounts,
}

/// Opens a pcap or pcapng file (told apart by its magic number).
pub fn open(path: &Path) -> Result<Capture> {
    let mut magic = [0u8; 4];
    {
        use std::io::Read;
        let mut f = File::open(path).with_context(|| format!("{}", path.display()))?;
        f.read_exact(&mut magic)
            .with_context(|| format!("{}: too short for a capture", path.display()))?;
    }
    let file = BufReader::new(File::open(path)?);
    let reader = match u32::from_le_bytes(magic) {
        0x0A0D_0D0A => Reader::PcapNg(
            PcapNgReader::new(file)
                .with_context(|| format!("{}: bad pcapng section header", path.display()))?,
        ),
        0xA1B2_C3D4 | 0xD4C3_B2A1 | 0xA1B2_3C4D | 0x4D3C_B2A1 => Reader::Pcap(
            PcapReader::new(file)
                .with_context(|| format!("{}: bad pcap header", path.display()))?,
        ),
        m => bail!(
            "{}: not a pcap or pcapng file (magic {m:#010x})",
            path.display()
        ),
    };
    Ok(Capture {
        path: path.to_path_buf(),
        reader,
        defrag: IpDefragPool::new(),
        counts: CaptureCounts::default(),
    })
}

impl Capture {
    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Counts so far.
    pub fn counts(&self) -> &CaptureCounts {
        &self.counts
    }

    /// The next UDP datagram, `Ok(None)` at the end of the file, or an error naming the file
    /// when the capture is damaged (nothing after it can be read).
    pub fn next_datagram(&mut self) -> Result<Option<Datagram>> {
        loop {
            let frame = match &mut self.reader {
                Reader::Pcap(r) => {
                    let link = r.header().datalink;
                    match r.next_packet() {
                        None => return Ok(None),
                        Some(p) => p.map(|p| (p.timestamp, link, p.data.into_owned())),
                    }
                }
                Reader::PcapNg(r) => {
                    let block = match r.next_block() {
                        None => return Ok(None),
                        Some(Ok(Block::EnhancedPacket(p))) => {
                            Ok(Some((p.timestamp, p.interface_id, p.data.into_owned())))
                        }
                        Some(Ok(Block::SimplePacket(p))) => {
                            Ok(Some((Default::default(), 0, p.data.into_owned())))
                        }
                        Some(Ok(_)) => Ok(None),
                        Some(Err(e)) => Err(e),
                    };
                    match block {
                        Ok(None) => continue,
                        Ok(Some((t, id, data))) => {
                            let link = r
                                .interfaces()
                                .get(id as usize)
                                .map(|i| i.linktype)
                                .unwrap_or(DataLink::ETHERNET);
                            Ok((t, link, data))
                        }
                        Err(e) => Err(e),
                    }
                }
            };
            let (time, link, data) = frame.map_err(|e| {
                anyhow::anyhow!(
                    "{}: capture damaged after {} frames (cut in the middle?): {e}",
                    self.path.display(),
                    self.counts.frames
                )
            })?;
            self.counts.frames += 1;
            if let Some(d) = self.udp(time.as_nanos() as u64, link, &data) {
                self.counts.datagrams += 1;
                return Ok(Some(d));
            }
        }
    }

    fn udp(&mut self, time_ns: u64, link: DataLink, data: &[u8]) -> Option<Datagram> {
        let sliced = match link {
            DataLink::ETHERNET => SlicedPacket::from_ethernet(data),
            DataLink::LINUX_SLL => SlicedPacket::from_linux_sll(data),
            DataLink::RAW | DataLink::IPV4 | DataLink::IPV6 => SlicedPacket::from_ip(data),
            // BSD loopback: a 4-byte address family, then IP.
            DataLink::NULL | DataLink::LOOP => SlicedPacket::from_ip(data.get(4..)?),
            _ => {
                self.counts.skipped += 1;
                return None;
            }
        };
        let Ok(sliced) = sliced else {
            self.counts.skipped += 1;
            return None;
        };
        let ip: IpAddr = match &sliced.net {
            Some(NetSlice::Ipv4(v4)) => v4.header().source_addr().into(),
            Some(NetSlice::Ipv6(v6)) => v6.header().source_addr().into(),
            None => {
                self.counts.skipped += 1;
                return None;
            }
        };
        if let Some(TransportSlice::Udp(u)) = &sliced.transport {
            return Some(Datagram {
                time_ns,
                source: SocketAddr::new(ip, u.source_port()),
                port: u.destination_port(),
                payload: u.payload().to_vec(),
            });
        }
        let fragmented = match &sliced.net {
            Some(NetSlice::Ipv4(v4)) => v4.is_payload_fragmented(),
            Some(NetSlice::Ipv6(v6)) => v6.is_payload_fragmented(),
            None => false,
        };
        if !fragmented {
            self.counts.skipped += 1;
            return None;
        }
        self.counts.fragments += 1;
        let whole = self.defrag.process_sliced_packet(&sliced, (), ()).ok()??;
        let datagram = (whole.ip_number == IpNumber::UDP)
            .then(|| UdpSlice::from_slice(&whole.payload).ok())
            .flatten()
            .map(|u| Datagram {
                time_ns,
                source: SocketAddr::new(ip, u.source_port()),
                port: u.destination_port(),
                payload: u.payload().to_vec(),
            });
        self.defrag.return_buf(whole);
        datagram
    }
}

impl Iterator for Capture {
    type Item = Result<Datagram>;
    fn next(&mut self) -> Option<Self::Item> {
        self.next_datagram().transpose()
    }
}

/// Writes `datagrams` as a little-endian microsecond pcap of Ethernet/IPv4/UDP frames (IPv4
/// fragments above `mtu` bytes of IP packet), for tests and generated recordings.
pub fn write(path: &Path, datagrams: &[Datagram], mtu: usize) -> Result<()> {
    use pcap_file::pcap::{PcapHeader, PcapPacket, PcapWriter};
    let file =
        std::io::BufWriter::new(File::create(path).with_context(|| format!("{}", path.display()))?);
    let header = PcapHeader {
        snaplen: 65535,
        ..PcapHeader::default()
    };
    let mut w = PcapWriter::with_header(file, header)?;
    for (id, d) in datagrams.iter().enumerate() {
        for frame in ethernet_frames(d, id as u16, mtu)? {
            let t = std::time::Duration::from_nanos(d.time_ns);
            w.write_packet(&PcapPacket::new(t, frame.len() as u32, &frame))?;
        }
    }
    Ok(())
}

/// Ethernet frames carrying `d` (one, or IPv4 fragments of at most `mtu` bytes).
fn ethernet_frames(d: &Datagram, id: u16, mtu: usize) -> Result<Vec<Vec<u8>>> {
    use etherparse::{EtherType, Ethernet2Header, IpFragOffset, Ipv4Header, UdpHeader};
    let IpAddr::V4(src) = d.source.ip() else {
        bail!("only IPv4 senders are written");
    };
    let udp = UdpHeader::without_ipv4_checksum(d.source.port(), d.port, d.payload.len())?;
    let mut body = udp.to_bytes().to_vec();
    body.extend_from_slice(&d.payload);
    let step = (mtu.saturating_sub(Ipv4Header::MIN_LEN) / 8).max(1) * 8;
    let mut frames = Vec::new();
    for (k, piece) in body.chunks(step).enumerate() {
        let mut ip = Ipv4Header::new(
            piece.len() as u16,
            64,
            IpNumber::UDP,
            src.octets(),
            [10, 0, 0, 255],
        )?;
        ip.identification = id;
        ip.more_fragments = (k + 1) * step < body.len();
        ip.fragment_offset = IpFragOffset::try_new((k * step / 8) as u16)?;
        ip.header_checksum = ip.calc_header_checksum();
        let eth = Ethernet2Header {
            source: [2, 0, 0, 0, 0, 1],
            destination: [0xff; 6],
            ether_type: EtherType::IPV4,
        };
        let mut f = eth.to_bytes().to_vec();
        f.extend_from_slice(&ip.to_bytes());
        f.extend_from_slice(piece);
        frames.push(f);
    }
    Ok(frames)
}

#[cfg(test)]
mod tests {
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
        assert_eq!(cap.counts().fragments, 9);
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
            for f in ethernet_frames(d, i as u16, 1500).unwrap() {
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
}
