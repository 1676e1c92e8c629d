//! Packet captures (pcap and pcapng, as Wireshark, tcpdump, VeloView and `ouster-cli` write
//! them) to UDP datagrams: the input side of sensor recordings.
//!
//! Frames are Ethernet (with VLAN tags), Linux cooked (SLL, and SLL2 as `tcpdump -i any`
//! writes), BSD loopback or raw IP (link types 12, 101, 228, 229); IPv4 and IPv6 fragments (an
//! Ouster packet is larger than a standard MTU) are reassembled with bounded memory
//! ([`reassembly`](super::reassembly)). pcapng timestamps are read in each interface's resolution
//! (`if_tsresol`, default microseconds) and offset (`if_tsoffset`). What cannot be handed on
//! is counted, never silent: frames of link types not read, frames cut by the snap length,
//! datagrams whose fragments never all came, headers that do not parse, and UDP datagrams the
//! capture holds damaged (cut by the snap length, a UDP length field longer than the IP
//! packet), which [`Capture::next_record`] hands on as [`Record::Damaged`] for the caller to
//! count against its port. A file cut in the middle yields the datagrams before the cut and
//! then an error naming the file.

use super::reassembly::{Fragment, FragmentCounts, Key, Reassembly};
use anyhow::{bail, Context, Result};
use etherparse::{EtherType, LaxNetSlice, LaxSlicedPacket, VlanSlice};
use pcap_file::pcap::PcapReader;
use pcap_file::pcapng::blocks::interface_description::{
    InterfaceDescriptionBlock, InterfaceDescriptionOption,
};
use pcap_file::pcapng::{Block, PcapNgReader};
use pcap_file::DataLink;
use std::collections::BTreeMap;
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

/// Why a UDP datagram in the capture cannot be handed on whole.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Damage {
    /// The capture kept `captured` of the frame's `original` bytes: its snap length is shorter
    /// than the packets. Capture again with a larger one (`tcpdump -s 0`).
    Cut {
        /// Bytes of the frame in the file.
        captured: usize,
        /// Bytes of the frame on the wire.
        original: usize,
    },
    /// The UDP header's length field says more than the IP packet carries: malformed.
    UdpLength {
        /// Bytes the UDP length field claims (header included).
        claimed: usize,
        /// Bytes the IP packet carries after the IP header.
        carried: usize,
    },
}

impl std::fmt::Display for Damage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Cut { captured, original } => write!(
                f,
                "cut by the capture's snap length ({captured} of {original} bytes kept): capture \
                 again with a larger snap length (tcpdump -s 0)"
            ),
            Self::UdpLength { claimed, carried } => write!(
                f,
                "UDP length field of {claimed} bytes longer than the {carried} bytes the IP \
                 packet carries (malformed)"
            ),
        }
    }
}

/// What a capture yields: a datagram, or one it holds damaged.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Record {
    /// A whole datagram.
    Datagram(Datagram),
    /// A UDP datagram the capture cannot hand on whole.
    Damaged {
        /// Capture time, ns since the Unix epoch.
        time_ns: u64,
        /// Sender.
        source: SocketAddr,
        /// Destination port.
        port: u16,
        /// What is wrong.
        damage: Damage,
    },
}

/// What a capture held besides UDP datagrams.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CaptureCounts {
    /// Link-layer frames read.
    pub frames: u64,
    /// UDP datagrams yielded whole (after reassembly).
    pub datagrams: u64,
    /// UDP datagrams yielded damaged ([`Record::Damaged`]).
    pub damaged: u64,
    /// Frames that are not UDP over IP (ARP, TCP, ...).
    pub skipped: u64,
    /// Frames whose IP or UDP header does not parse.
    pub malformed: u64,
    /// Frames of link types not read, by link type number.
    pub unread_links: BTreeMap<u32, u64>,
    /// pcapng packets of an interface the file never described.
    pub undescribed: u64,
    /// Frames cut by the snap length and not handed on (a fragment, or cut inside its
    /// headers); cut datagrams handed on are [`Self::damaged`].
    pub cut: u64,
    /// Largest number of bytes kept of a cut frame, and the largest original frame length.
    pub cut_sizes: (usize, usize),
    /// What became of IP fragments.
    pub reassembly: FragmentCounts,
}

impl CaptureCounts {
    /// One line per thing that was not handed on and not counted elsewhere.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        for (&link, n) in &self.unread_links {
            w.push(format!(
                "{n} frame(s) of link type {} not read (read: Ethernet, Linux cooked SLL and \
                 SLL2, BSD loopback, raw IP)",
                link_name(link)
            ));
        }
        if self.undescribed > 0 {
            w.push(format!(
                "{} packet(s) of a capture interface the file never describes: skipped",
                self.undescribed
            ));
        }
        if self.cut > 0 {
            let (kept, original) = self.cut_sizes;
            w.push(format!(
                "{} frame(s) cut by the capture's snap length ({kept} bytes kept of frames up \
                 to {original}): capture again with a larger snap length (tcpdump -s 0)",
                self.cut
            ));
        }
        if self.malformed > 0 {
            w.push(format!(
                "{} frame(s) whose IP or UDP header does not parse: skipped",
                self.malformed
            ));
        }
        w.extend(self.reassembly.warnings());
        w
    }
}

/// A link type by name and number, e.g. `LINUX_SLL2 (276)`.
pub fn link_name(link: u32) -> String {
    match DataLink::from(link) {
        DataLink::Unknown(n) => format!("{n}"),
        known => format!("{known:?} ({link})"),
    }
}

/// How an interface's timestamps read: pcapng `if_tsresol` and `if_tsoffset`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Clock {
    /// `if_tsresol`: units of 10^-v s, or of 2^-v s with the top bit set (default 6).
    resolution: u8,
    /// `if_tsoffset`: seconds added to every timestamp.
    offset_s: i64,
}

impl Clock {
    const DEFAULT: Self = Self {
        resolution: 6,
        offset_s: 0,
    };

    fn of(idb: &InterfaceDescriptionBlock<'_>) -> Self {
        let mut c = Self::DEFAULT;
        for o in &idb.options {
            match o {
                InterfaceDescriptionOption::IfTsResol(r) => c.resolution = *r,
                InterfaceDescriptionOption::IfTsOffset(s) => c.offset_s = *s as i64,
                _ => {}
            }
        }
        c
    }

    /// A raw timestamp in ns since the epoch (saturating: a clock beyond 2554 stops there).
    fn ns(self, raw: u64) -> u64 {
        let v = u32::from(self.resolution & 0x7F);
        let ns: u128 = if self.resolution & 0x80 != 0 {
            (u128::from(raw) * 1_000_000_000) >> v
        } else if v <= 9 {
            u128::from(raw) * 10u128.pow(9 - v)
        } else {
            10u128.checked_pow(v - 9).map_or(0, |d| u128::from(raw) / d)
        };
        let ns =
            i128::try_from(ns).unwrap_or(i128::MAX) + i128::from(self.offset_s) * 1_000_000_000;
        u64::try_from(ns.max(0)).unwrap_or(u64::MAX)
    }
}

enum Reader {
    Pcap(PcapReader<BufReader<File>>),
    PcapNg(PcapNgReader<BufReader<File>>),
}

/// A capture being read, datagram by datagram.
pub struct Capture {
    path: PathBuf,
    reader: Reader,
    defrag: Reassembly,
    counts: CaptureCounts,
    ended: bool,
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
        defrag: Reassembly::new(),
        counts: CaptureCounts::default(),
        ended: false,
    })
}

/// One link-layer frame as read from the file.
struct LinkFrame {
    time_ns: u64,
    link: DataLink,
    interface: u32,
    data: Vec<u8>,
    original: usize,
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

    /// The next whole UDP datagram (damaged ones are skipped and counted), `Ok(None)` at the
    /// end of the file, or an error naming the file when the capture is damaged (nothing
    /// after it can be read).
    pub fn next_datagram(&mut self) -> Result<Option<Datagram>> {
        loop {
            match self.next_record()? {
                None => return Ok(None),
                Some(Record::Datagram(d)) => return Ok(Some(d)),
                Some(Record::Damaged { .. }) => {}
            }
        }
    }

    /// The next UDP datagram, whole or damaged; otherwise as [`Self::next_datagram`].
    pub fn next_record(&mut self) -> Result<Option<Record>> {
        loop {
            let Some(frame) = self.next_frame()? else {
                if !self.ended {
                    self.ended = true;
                    self.defrag.end();
                    self.counts.reassembly = *self.defrag.counts();
                }
                return Ok(None);
            };
            self.counts.frames += 1;
            let record = self.udp(&frame);
            self.counts.reassembly = *self.defrag.counts();
            match &record {
                Some(Record::Datagram(_)) => self.counts.datagrams += 1,
                Some(Record::Damaged { .. }) => self.counts.damaged += 1,
                None => continue,
            }
            return Ok(record);
        }
    }

    /// The next frame of a described link, or `None` at the end of the file.
    fn next_frame(&mut self) -> Result<Option<LinkFrame>> {
        loop {
            let frame = match &mut self.reader {
                Reader::Pcap(r) => {
                    let link = r.header().datalink;
                    match r.next_packet() {
                        None => return Ok(None),
                        Some(Err(e)) => Err(e),
                        Some(Ok(p)) => Ok(Some(LinkFrame {
                            time_ns: u64::try_from(p.timestamp.as_nanos()).unwrap_or(u64::MAX),
                            link,
                            interface: 0,
                            original: p.orig_len as usize,
                            data: p.data.into_owned(),
                        })),
                    }
                }
                Reader::PcapNg(r) => {
                    // (interface, raw timestamp, original length, data)
                    let block = match r.next_block() {
                        None => return Ok(None),
                        Some(Err(e)) => Err(e),
                        Some(Ok(Block::EnhancedPacket(p))) => Ok(Some((
                            p.interface_id,
                            Some(u64::try_from(p.timestamp.as_nanos()).unwrap_or(u64::MAX)),
                            p.original_len as usize,
                            p.data.into_owned(),
                        ))),
                        Some(Ok(Block::SimplePacket(p))) => Ok(Some((
                            0,
                            None,
                            p.original_len as usize,
                            p.data.into_owned(),
                        ))),
                        Some(Ok(_)) => Ok(None),
                    };
                    match block {
                        Err(e) => Err(e),
                        Ok(None) => continue,
                        Ok(Some((id, raw, original, data))) => {
                            let Some(idb) = r.interfaces().get(id as usize) else {
                                self.counts.frames += 1;
                                self.counts.undescribed += 1;
                                continue;
                            };
                            Ok(Some(LinkFrame {
                                // A simple packet block has no timestamp.
                                time_ns: raw.map_or(0, |t| Clock::of(idb).ns(t)),
                                link: idb.linktype,
                                interface: id,
                                original,
                                data,
                            }))
                        }
                    }
                }
            };
            return frame.map_err(|e| {
                anyhow::anyhow!(
                    "{}: capture damaged after {} frames (cut in the middle?): {e}",
                    self.path.display(),
                    self.counts.frames
                )
            });
        }
    }

    /// The UDP datagram a frame carries or completes, if any; everything else is counted.
    fn udp(&mut self, frame: &LinkFrame) -> Option<Record> {
        let data = frame.data.as_slice();
        let cooked = |protocol: std::ops::Range<usize>, header: usize| {
            let p = data.get(protocol)?;
            let ether_type = EtherType(u16::from_be_bytes([p[0], p[1]]));
            Some(LaxSlicedPacket::from_ether_type(
                ether_type,
                data.get(header..)?,
            ))
        };
        let sliced = match frame.link {
            DataLink::ETHERNET => LaxSlicedPacket::from_ethernet(data).ok(),
            // SLL: the protocol in bytes 14..16 of a 16-byte header; SLL2: bytes 0..2 of 20.
            DataLink::LINUX_SLL => cooked(14..16, 16),
            DataLink::LINUX_SLL2 => cooked(0..2, 20),
            // Raw IP: 101 in files, 12 where writers use the DLT number, 228/229 per version.
            DataLink::RAW | DataLink::IPV4 | DataLink::IPV6 | DataLink::Unknown(12) => {
                LaxSlicedPacket::from_ip(data).ok()
            }
            // BSD loopback: a 4-byte address family, then IP.
            DataLink::NULL | DataLink::LOOP => {
                data.get(4..).and_then(|d| LaxSlicedPacket::from_ip(d).ok())
            }
            other => {
                *self
                    .counts
                    .unread_links
                    .entry(u32::from(other))
                    .or_insert(0) += 1;
                return None;
            }
        };
        let cut = (frame.original > data.len()).then_some(Damage::Cut {
            captured: data.len(),
            original: frame.original,
        });
        let record = sliced.and_then(|s| self.ip(frame, &s, cut));
        if record.is_none() {
            if let Some(Damage::Cut { captured, original }) = cut {
                self.counts.cut += 1;
                let (k, o) = self.counts.cut_sizes;
                self.counts.cut_sizes = (k.max(captured), o.max(original));
            }
        }
        record
    }

    /// The IP layer: a UDP datagram, or a fragment for reassembly.
    fn ip(
        &mut self,
        frame: &LinkFrame,
        s: &LaxSlicedPacket<'_>,
        cut: Option<Damage>,
    ) -> Option<Record> {
        let (source, destination, payload, fragment) = match &s.net {
            Some(LaxNetSlice::Ipv4(v4)) => {
                let h = v4.header();
                let fragment = v4.is_payload_fragmented().then(|| {
                    (
                        usize::from(h.fragments_offset().byte_offset()),
                        h.more_fragments(),
                        u32::from(h.identification()),
                    )
                });
                let (src, dst): (IpAddr, IpAddr) =
                    (h.source_addr().into(), h.destination_addr().into());
                (src, dst, v4.payload(), fragment)
            }
            Some(LaxNetSlice::Ipv6(v6)) => {
                let h = v6.header();
                let ext = v6.extensions();
                let fragment = ipv6_fragment(ext.first_header().map(|n| n.0), ext.slice());
                let (src, dst): (IpAddr, IpAddr) =
                    (h.source_addr().into(), h.destination_addr().into());
                (src, dst, v6.payload(), fragment)
            }
            None => {
                // No IP header: another protocol (ARP), or one that does not parse.
                if s.stop_err.is_some() && cut.is_none() {
                    self.counts.malformed += 1;
                } else if cut.is_none() {
                    self.counts.skipped += 1;
                }
                return None;
            }
        };
        let protocol = payload.ip_number.0;
        let Some((offset, more, id)) = fragment else {
            if protocol != etherparse::IpNumber::UDP.0 {
                self.counts.skipped += 1;
                return None;
            }
            return self.datagram(frame.time_ns, source, payload.payload, cut);
        };
        if payload.incomplete {
            // A fragment cut short fits no datagram; a cut one is counted as cut.
            if cut.is_none() {
                self.counts.malformed += 1;
            }
            return None;
        }
        let vlan = match &s.vlan {
            Some(VlanSlice::SingleVlan(v)) => (v.vlan_identifier().value(), 0),
            Some(VlanSlice::DoubleVlan(v)) => (
                v.outer().vlan_identifier().value(),
                v.inner().vlan_identifier().value(),
            ),
            None => (0, 0),
        };
        let key = Key {
            source,
            destination,
            protocol,
            id,
            vlan,
            interface: frame.interface,
        };
        let bytes = payload.payload;
        let whole = self.defrag.add(
            key,
            frame.time_ns,
            Fragment {
                offset,
                more,
                bytes,
            },
        )?;
        if whole.protocol != etherparse::IpNumber::UDP.0 {
            self.counts.skipped += 1;
            return None;
        }
        self.datagram(frame.time_ns, source, &whole.payload, None)
    }

    /// A UDP header and payload (`bytes`, the IP payload) as a record.
    fn datagram(
        &mut self,
        time_ns: u64,
        ip: IpAddr,
        bytes: &[u8],
        cut: Option<Damage>,
    ) -> Option<Record> {
        let Some(h) = bytes.get(..8) else {
            if cut.is_none() {
                self.counts.malformed += 1;
            }
            return None;
        };
        let field = |k: usize| u16::from_be_bytes([h[k], h[k + 1]]);
        let (source, port, len) = (
            SocketAddr::new(ip, field(0)),
            field(2),
            usize::from(field(4)),
        );
        if len < 8 {
            self.counts.malformed += 1;
            return None;
        }
        if len > bytes.len() {
            let damage = cut.unwrap_or(Damage::UdpLength {
                claimed: len,
                carried: bytes.len(),
            });
            return Some(Record::Damaged {
                time_ns,
                source,
                port,
                damage,
            });
        }
        Some(Record::Datagram(Datagram {
            time_ns,
            source,
            port,
            payload: bytes[8..len].to_vec(),
        }))
    }
}

impl Iterator for Capture {
    type Item = Result<Datagram>;
    fn next(&mut self) -> Option<Self::Item> {
        self.next_datagram().transpose()
    }
}

/// Writes `datagrams` as a little-endian microsecond pcap of Ethernet/IPv4/UDP frames (IPv4
/// fragments above `mtu` bytes of IP packet, datagram `k` with IP ID `k`), for tests and
/// generated recordings.
pub fn write(path: &Path, datagrams: &[Datagram], mtu: usize) -> Result<()> {
    let mut frames = Vec::new();
    for (id, d) in datagrams.iter().enumerate() {
        for ip in ipv4_packets(d, id as u16, mtu)? {
            frames.push((d.time_ns, ethernet(&ip)));
        }
    }
    write_frames(path, DataLink::ETHERNET, &frames)
}

/// Writes link-layer frames `(time ns, bytes)` of one link type as a microsecond pcap (snap
/// length 65535), for tests.
pub fn write_frames(path: &Path, link: DataLink, frames: &[(u64, Vec<u8>)]) -> Result<()> {
    use pcap_file::pcap::{PcapHeader, PcapPacket, PcapWriter};
    let file =
        std::io::BufWriter::new(File::create(path).with_context(|| format!("{}", path.display()))?);
    let header = PcapHeader {
        snaplen: 65535,
        datalink: link,
        ..PcapHeader::default()
    };
    let mut w = PcapWriter::with_header(file, header)?;
    for (t, frame) in frames {
        let t = std::time::Duration::from_nanos(*t);
        w.write_packet(&PcapPacket::new(t, frame.len() as u32, frame))?;
    }
    Ok(())
}

/// IPv4 packets carrying `d` to 10.0.0.255 with a UDP checksum: one, or fragments of at most
/// `mtu` bytes, with IP ID `id`.
pub fn ipv4_packets(d: &Datagram, id: u16, mtu: usize) -> Result<Vec<Vec<u8>>> {
    use etherparse::{IpFragOffset, IpNumber, Ipv4Header, UdpHeader};
    let IpAddr::V4(src) = d.source.ip() else {
        bail!("only IPv4 senders are written");
    };
    let dst = [10, 0, 0, 255];
    let udp = UdpHeader::with_ipv4_checksum(
        d.source.port(),
        d.port,
        &Ipv4Header::new(0, 64, IpNumber::UDP, src.octets(), dst)?,
        &d.payload,
    )?;
    let mut body = udp.to_bytes().to_vec();
    body.extend_from_slice(&d.payload);
    let step = (mtu.saturating_sub(Ipv4Header::MIN_LEN) / 8).max(1) * 8;
    let mut packets = Vec::new();
    for (k, piece) in body.chunks(step).enumerate() {
        let mut ip = Ipv4Header::new(piece.len() as u16, 64, IpNumber::UDP, src.octets(), dst)?;
        ip.identification = id;
        ip.more_fragments = (k + 1) * step < body.len();
        ip.fragment_offset = IpFragOffset::try_new((k * step / 8) as u16)?;
        ip.header_checksum = ip.calc_header_checksum();
        let mut f = ip.to_bytes().to_vec();
        f.extend_from_slice(piece);
        packets.push(f);
    }
    Ok(packets)
}

/// An IPv4 packet in an Ethernet II frame (broadcast, from 02:00:00:00:00:01).
pub fn ethernet(ip: &[u8]) -> Vec<u8> {
    let eth = etherparse::Ethernet2Header {
        source: [2, 0, 0, 0, 0, 1],
        destination: [0xff; 6],
        ether_type: EtherType::IPV4,
    };
    let mut f = eth.to_bytes().to_vec();
    f.extend_from_slice(ip);
    f
}

/// The fragment header among the IPv6 extension headers `rest`, the first of type `next`:
/// (byte offset, more fragments, identification), if it fragments the payload. The chain is
/// walked here with every read checked, and the fragment header read as RFC 8200 lays it out
/// (offset in the top 13 bits of bytes 2-3, the M flag in the lowest): etherparse 0.16's
/// iterator reads past the end of a chain its lax parse cut short (an out-of-bounds
/// `get_unchecked` that fuzzing found), and its fragment header takes the offset's low bits
/// and the M flag from the wrong end of byte 3 (fixed in etherparse 0.21).
fn ipv6_fragment(mut next: Option<u8>, mut rest: &[u8]) -> Option<(usize, bool, u32)> {
    const FRAGMENT: u8 = 44;
    const AUTHENTICATION: u8 = 51;
    // Hop-by-hop, routing, destination options, mobility, HIP, shim6: (length + 1) x 8 bytes.
    const EIGHT_BYTE_UNITS: [u8; 6] = [0, 43, 60, 135, 139, 140];
    while let Some(header) = next {
        let len = match header {
            FRAGMENT => {
                let b = rest.get(..8)?;
                let field = u16::from_be_bytes([b[2], b[3]]);
                let (offset, more) = (usize::from(field >> 3) * 8, field & 1 != 0);
                let id = u32::from_be_bytes([b[4], b[5], b[6], b[7]]);
                return (offset != 0 || more).then_some((offset, more, id));
            }
            AUTHENTICATION => (usize::from(*rest.get(1)?) + 2) * 4,
            h if EIGHT_BYTE_UNITS.contains(&h) => (usize::from(*rest.get(1)?) + 1) * 8,
            _ => return None,
        };
        next = rest.first().copied();
        rest = rest.get(len..)?;
    }
    None
}

#[cfg(test)]
mod tests;
