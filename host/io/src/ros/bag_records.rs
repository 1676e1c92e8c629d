//! The ROS 1 bag container (format 2.0, <http://wiki.ros.org/Bags/Format/2.0>): records, the
//! bag header, connections, chunks and the index, read from the file with every length checked
//! against the file before it is trusted.
//!
//! This is read here rather than with the `rosbag` crate because that crate maps the whole
//! file and slices it by the header's `index_pos`, which panics on a bag cut short or never
//! closed; reading it needed a full temporary copy of the bag, left behind in `/tmp` when a run
//! was interrupted. Here a damaged bag is read in place: [`Bag::open`] learns where every
//! message is (from the index, or by walking the chunks when there is none), and a chunk is
//! read and decompressed only when one of its messages is asked for, never beyond
//! [`Bag::open`]'s record limit. The messages of one topic can then be visited in receive-time
//! order whatever order they were written in.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

/// First line of every bag of format 2.0.
pub const MAGIC: &[u8] = b"#ROSBAG V2.0\n";

/// Record opcodes (the `op` header field).
pub mod op {
    /// A message: `conn`, `time`; data = the serialized message.
    pub const MESSAGE_DATA: u8 = 0x02;
    /// The bag header: `index_pos`, `conn_count`, `chunk_count`.
    pub const BAG_HEADER: u8 = 0x03;
    /// Message times and offsets of one connection in the chunk before it.
    pub const INDEX_DATA: u8 = 0x04;
    /// Compressed records: `compression`, `size` (uncompressed).
    pub const CHUNK: u8 = 0x05;
    /// Where a chunk is and how many messages of each connection it holds.
    pub const CHUNK_INFO: u8 = 0x06;
    /// A connection: `conn`, `topic`; data = fields `type`, `md5sum`, ...
    pub const CONNECTION: u8 = 0x07;
}

/// Largest record header accepted; real headers take tens of bytes.
const HEADER_LIMIT: u32 = 1 << 20;

/// The `name=value` fields of a record header (or of a connection record's data).
#[derive(Clone, Debug, Default)]
pub struct Fields(BTreeMap<String, Vec<u8>>);

impl Fields {
    /// Parses `len:u32, name=value` entries filling `bytes` exactly.
    pub fn parse(bytes: &[u8]) -> Result<Self, String> {
        let mut map = BTreeMap::new();
        let mut rest = bytes;
        while !rest.is_empty() {
            let (len, tail) = rest
                .split_first_chunk::<4>()
                .ok_or("record header field cut short")?;
            let len = u32::from_le_bytes(*len) as usize;
            let field = tail.get(..len).ok_or("record header field cut short")?;
            let eq = field
                .iter()
                .position(|&b| b == b'=')
                .ok_or("record header field without '='")?;
            let name = String::from_utf8_lossy(&field[..eq]).into_owned();
            map.insert(name, field[eq + 1..].to_vec());
            rest = &tail[len..];
        }
        Ok(Self(map))
    }

    fn bytes(&self, name: &str) -> Result<&[u8], String> {
        self.0
            .get(name)
            .map(Vec::as_slice)
            .ok_or_else(|| format!("record has no `{name}` field"))
    }

    /// The record's opcode.
    pub fn op(&self) -> Result<u8, String> {
        match self.bytes("op")? {
            [op] => Ok(*op),
            other => Err(format!("`op` field of {} bytes", other.len())),
        }
    }

    /// A little-endian `u32` field.
    pub fn u32(&self, name: &str) -> Result<u32, String> {
        let b = self.bytes(name)?;
        let b: [u8; 4] = b
            .try_into()
            .map_err(|_| format!("`{name}` field of {} bytes, expected 4", b.len()))?;
        Ok(u32::from_le_bytes(b))
    }

    /// A little-endian `u64` field.
    pub fn u64(&self, name: &str) -> Result<u64, String> {
        let b = self.bytes(name)?;
        let b: [u8; 8] = b
            .try_into()
            .map_err(|_| format!("`{name}` field of {} bytes, expected 8", b.len()))?;
        Ok(u64::from_le_bytes(b))
    }

    /// A ROS time field (`sec:u32`, `nsec:u32`) in nanoseconds.
    pub fn time(&self, name: &str) -> Result<u64, String> {
        let t = self.u64(name)?;
        Ok((t & 0xffff_ffff) * 1_000_000_000 + (t >> 32))
    }

    /// A text field.
    pub fn text(&self, name: &str) -> Result<String, String> {
        Ok(String::from_utf8_lossy(self.bytes(name)?).into_owned())
    }
}

/// A record read from the file: its header and where its data is.
#[derive(Clone, Debug)]
struct FileRecord {
    fields: Fields,
    data_pos: u64,
    data_len: u32,
}

impl FileRecord {
    fn end(&self) -> u64 {
        self.data_pos + u64::from(self.data_len)
    }
}

fn read_u32(file: &mut File) -> std::io::Result<u32> {
    let mut b = [0u8; 4];
    file.read_exact(&mut b)?;
    Ok(u32::from_le_bytes(b))
}

/// Reads the header of the record at `pos`; its data must lie inside the `len`-byte file.
fn read_record(file: &mut File, pos: u64, len: u64) -> Result<FileRecord, String> {
    let cut = || format!("the record at byte {pos} runs past the end of the file ({len} bytes)");
    if pos.saturating_add(8) > len {
        return Err(cut());
    }
    file.seek(SeekFrom::Start(pos)).map_err(|e| e.to_string())?;
    let header_len = read_u32(file).map_err(|e| e.to_string())?;
    if header_len > HEADER_LIMIT {
        return Err(format!(
            "the record at byte {pos} claims a {header_len}-byte header"
        ));
    }
    if pos + 8 + u64::from(header_len) > len {
        return Err(cut());
    }
    let mut header = vec![0u8; header_len as usize];
    file.read_exact(&mut header).map_err(|e| e.to_string())?;
    let data_len = read_u32(file).map_err(|e| e.to_string())?;
    let data_pos = pos + 8 + u64::from(header_len);
    if data_pos + u64::from(data_len) > len {
        return Err(cut());
    }
    let fields = Fields::parse(&header).map_err(|e| format!("record at byte {pos}: {e}"))?;
    Ok(FileRecord {
        fields,
        data_pos,
        data_len,
    })
}

fn read_data(file: &mut File, record: &FileRecord) -> Result<Vec<u8>, String> {
    file.seek(SeekFrom::Start(record.data_pos))
        .map_err(|e| e.to_string())?;
    let mut data = vec![0u8; record.data_len as usize];
    file.read_exact(&mut data).map_err(|e| e.to_string())?;
    Ok(data)
}

/// A record inside a decompressed chunk: its header and data.
pub struct SliceRecord<'a> {
    /// Header fields.
    pub fields: Fields,
    /// The record's data.
    pub data: &'a [u8],
    /// Offset of the next record.
    pub next: usize,
}

/// The record at `at` in `buf` (a decompressed chunk).
pub fn slice_record(buf: &[u8], at: usize) -> Result<SliceRecord<'_>, String> {
    let cut = || {
        format!(
            "chunk record at offset {at} runs past the chunk ({} bytes)",
            buf.len()
        )
    };
    let take = |from: usize, n: usize| from.checked_add(n).and_then(|e| buf.get(from..e));
    let header_len = take(at, 4).ok_or_else(cut)?;
    let header_len =
        u32::from_le_bytes([header_len[0], header_len[1], header_len[2], header_len[3]]) as usize;
    let header = take(at + 4, header_len).ok_or_else(cut)?;
    let data_at = at + 4 + header_len;
    let data_len = take(data_at, 4).ok_or_else(cut)?;
    let data_len =
        u32::from_le_bytes([data_len[0], data_len[1], data_len[2], data_len[3]]) as usize;
    let data = take(data_at + 4, data_len).ok_or_else(cut)?;
    Ok(SliceRecord {
        fields: Fields::parse(header)?,
        data,
        next: data_at + 4 + data_len,
    })
}

/// A connection record: which topic and type its messages have.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Connection {
    /// Topic.
    pub topic: String,
    /// Message type, e.g. `sensor_msgs/PointCloud2`.
    pub tp: String,
    /// MD5 sum of the message definition.
    pub md5: String,
}

impl Connection {
    fn parse(fields: &Fields, data: &[u8]) -> Result<(u32, Self), String> {
        let id = fields.u32("conn")?;
        let inner = Fields::parse(data)?;
        Ok((
            id,
            Connection {
                topic: fields.text("topic")?,
                tp: inner.text("type")?,
                md5: inner.text("md5sum")?,
            },
        ))
    }
}

/// Where one message is: its receive time, connection, chunk and offset in the chunk.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MessageRef {
    /// Receive time, nanoseconds since the epoch.
    pub time: u64,
    /// Connection id.
    pub conn: u32,
    /// Position of the chunk in [`Bag::chunks`].
    pub chunk: u32,
    /// Offset of the message record in the decompressed chunk.
    pub offset: u32,
}

/// A bag opened for reading: its connections, its chunks and where every message is.
pub struct Bag {
    file: File,
    len: u64,
    /// Largest chunk (compressed or not) read.
    record_limit: u64,
    /// Connections by id.
    pub connections: BTreeMap<u32, Connection>,
    /// File offset of every chunk record, in file order.
    pub chunks: Vec<u64>,
    /// Every message, in file order (chunk by chunk, by offset).
    pub messages: Vec<MessageRef>,
    /// Whether the index section was used (otherwise the chunks were walked).
    pub indexed: bool,
    /// Why the chunk section ends early, if it does.
    pub damage: Option<String>,
    /// The last chunk read and decompressed, by position in `chunks`.
    cache: Option<(u32, Vec<u8>)>,
}

impl Bag {
    /// Opens the bag at `path`. Chunks larger than `record_limit` bytes (compressed or not)
    /// are not read. Fails when the file is not a bag; a bag damaged after its header opens
    /// with [`Bag::damage`] saying where it stops.
    pub fn open(path: &Path, record_limit: u64) -> Result<Self, String> {
        let mut file = File::open(path).map_err(|e| format!("cannot open ({e})"))?;
        let len = file
            .metadata()
            .map_err(|e| format!("cannot stat ({e})"))?
            .len();
        let mut magic = [0u8; MAGIC.len()];
        if file.read_exact(&mut magic).is_err() || magic != MAGIC {
            return Err("not a ROS bag v2.0 (no `#ROSBAG V2.0` line)".into());
        }
        let header = read_record(&mut file, MAGIC.len() as u64, len)
            .map_err(|e| format!("bag header: {e}"))?;
        if header.fields.op() != Ok(op::BAG_HEADER) {
            return Err("the first record is not a bag header".into());
        }
        let index_pos = header
            .fields
            .u64("index_pos")
            .map_err(|e| format!("bag header: {e}"))?;
        let mut bag = Bag {
            file,
            len,
            record_limit,
            connections: BTreeMap::new(),
            chunks: Vec::new(),
            messages: Vec::new(),
            indexed: false,
            damage: None,
            cache: None,
        };
        let start = header.end();
        let from_index = (start..len)
            .contains(&index_pos)
            .then(|| bag.read_index(index_pos, &header.fields))
            .and_then(Result::ok);
        match from_index {
            Some(()) => bag.indexed = true,
            None => {
                bag.connections.clear();
                bag.chunks.clear();
                bag.messages.clear();
                bag.walk_chunks(start, index_pos);
            }
        }
        Ok(bag)
    }

    /// Reads connections and chunk positions from the index section at `index_pos`, and the
    /// message times and offsets from the index data after each chunk; `Err` if anything is
    /// missing or unreadable.
    fn read_index(&mut self, index_pos: u64, header: &Fields) -> Result<(), String> {
        let (conn_count, chunk_count) = (header.u32("conn_count")?, header.u32("chunk_count")?);
        let mut pos = index_pos;
        while pos < self.len {
            let record = read_record(&mut self.file, pos, self.len)?;
            match record.fields.op()? {
                op::CONNECTION => {
                    let data = read_data(&mut self.file, &record)?;
                    let (id, c) = Connection::parse(&record.fields, &data)?;
                    self.connections.insert(id, c);
                }
                op::CHUNK_INFO => self.chunks.push(record.fields.u64("chunk_pos")?),
                _ => {}
            }
            pos = record.end();
        }
        if self.chunks.len() != chunk_count as usize
            || self.connections.len() != conn_count as usize
        {
            return Err("index does not list every chunk and connection".into());
        }
        self.chunks.sort_unstable();
        for k in 0..self.chunks.len() {
            let chunk = read_record(&mut self.file, self.chunks[k], self.len)?;
            if chunk.fields.op()? != op::CHUNK {
                return Err(format!(
                    "no chunk at byte {} where the index says",
                    self.chunks[k]
                ));
            }
            let first = self.messages.len();
            let mut pos = chunk.end();
            while pos < self.len {
                let record = read_record(&mut self.file, pos, self.len)?;
                if record.fields.op()? != op::INDEX_DATA {
                    break;
                }
                let conn = record.fields.u32("conn")?;
                let data = read_data(&mut self.file, &record)?;
                if record.fields.u32("ver")? != 1 || data.len() % 12 != 0 {
                    return Err(format!("index data at byte {pos} is not version 1"));
                }
                for e in data.chunks_exact(12) {
                    let sec = u64::from(u32::from_le_bytes([e[0], e[1], e[2], e[3]]));
                    let nsec = u64::from(u32::from_le_bytes([e[4], e[5], e[6], e[7]]));
                    self.messages.push(MessageRef {
                        time: sec * 1_000_000_000 + nsec,
                        conn,
                        chunk: k as u32,
                        offset: u32::from_le_bytes([e[8], e[9], e[10], e[11]]),
                    });
                }
                pos = record.end();
            }
            self.messages[first..].sort_by_key(|m| m.offset);
        }
        Ok(())
    }

    /// Walks the chunk section from `start` record by record (up to `index_pos` if that is a
    /// sane end, else to the end of the file), decompressing each chunk once to learn its
    /// connections and messages; stops at the first unreadable record and says why.
    fn walk_chunks(&mut self, start: u64, index_pos: u64) {
        let end = if (start..=self.len).contains(&index_pos) && index_pos > start {
            index_pos
        } else {
            self.len
        };
        let mut pos = start;
        while pos < end {
            let record = match read_record(&mut self.file, pos, self.len) {
                Ok(r) => r,
                Err(e) => {
                    self.damage = Some(format!(
                        "cannot read the record at byte {pos} ({e}); the bag looks cut short"
                    ));
                    return;
                }
            };
            if record.fields.op() == Ok(op::CHUNK) {
                let k = self.chunks.len() as u32;
                self.chunks.push(pos);
                if let Err(e) = self.learn_chunk(k) {
                    self.chunks.pop();
                    self.damage = Some(format!("chunk at byte {pos}: {e}"));
                    return;
                }
            }
            pos = record.end();
        }
    }

    /// Records the connections and messages of chunk `k`.
    fn learn_chunk(&mut self, k: u32) -> Result<(), String> {
        let (mut conns, mut msgs) = (Vec::new(), Vec::new());
        let buf = self.chunk(k)?;
        let mut at = 0;
        while at < buf.len() {
            let r = slice_record(buf, at)?;
            match r.fields.op()? {
                op::CONNECTION => conns.push(Connection::parse(&r.fields, r.data)?),
                op::MESSAGE_DATA => msgs.push(MessageRef {
                    time: r.fields.time("time")?,
                    conn: r.fields.u32("conn")?,
                    chunk: k,
                    offset: at as u32,
                }),
                _ => {}
            }
            at = r.next;
        }
        for (id, c) in conns {
            self.connections.entry(id).or_insert(c);
        }
        self.messages.extend(msgs);
        Ok(())
    }

    /// Chunk `k`, decompressed (the last one is kept for the next message).
    pub fn chunk(&mut self, k: u32) -> Result<&[u8], String> {
        if self.cache.as_ref().is_none_or(|(c, _)| *c != k) {
            self.cache = None;
            let pos = *self.chunks.get(k as usize).ok_or("no such chunk")?;
            let data = self.read_chunk(pos)?;
            self.cache = Some((k, data));
        }
        Ok(self.cache.as_ref().map_or(&[][..], |(_, d)| d.as_slice()))
    }

    fn read_chunk(&mut self, pos: u64) -> Result<Vec<u8>, String> {
        let record = read_record(&mut self.file, pos, self.len)?;
        if record.fields.op()? != op::CHUNK {
            return Err(format!("no chunk at byte {pos}"));
        }
        let size = record.fields.u32("size")?;
        let limit = self.record_limit;
        if u64::from(size) > limit || u64::from(record.data_len) > limit {
            return Err(format!(
                "chunk at byte {pos} holds {size} bytes, more than the {limit}-byte limit"
            ));
        }
        let data = read_data(&mut self.file, &record)?;
        let compression = record.fields.text("compression")?;
        let out = match compression.as_str() {
            "none" => data,
            "bz2" => inflate(bzip2::read::BzDecoder::new(data.as_slice()), size)?,
            "lz4" => inflate(
                lz4::Decoder::new(data.as_slice()).map_err(|e| format!("lz4: {e}"))?,
                size,
            )?,
            other => {
                return Err(format!(
                    "chunk compression `{other}` is not none, bz2 or lz4"
                ))
            }
        };
        if out.len() != size as usize {
            return Err(format!(
                "chunk at byte {pos} holds {} bytes, its header says {size}",
                out.len()
            ));
        }
        Ok(out)
    }

    /// The message `m`: its connection and serialized body.
    pub fn message(&mut self, m: MessageRef) -> Result<&[u8], String> {
        let buf = self.chunk(m.chunk)?;
        let r = slice_record(buf, m.offset as usize)?;
        if r.fields.op()? != op::MESSAGE_DATA || r.fields.u32("conn")? != m.conn {
            return Err(format!(
                "no message of connection {} at offset {} of its chunk",
                m.conn, m.offset
            ));
        }
        Ok(r.data)
    }
}

/// Decompresses at most `size` bytes (plus one, to notice a chunk larger than it says).
fn inflate(reader: impl Read, size: u32) -> Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(size as usize);
    reader
        .take(u64::from(size) + 1)
        .read_to_end(&mut out)
        .map_err(|e| format!("cannot decompress: {e}"))?;
    Ok(out)
}
