//! A ROS 1 bag (format 2.0, <http://wiki.ros.org/Bags/Format/2.0>) written as a stream: the
//! bag header record (4096 bytes, rewritten at the end with where the index is), then one
//! uncompressed chunk per call of [`BagWriter::chunk`] followed by its index data, then the
//! connection and chunk info records `rosbag` reads to find the messages.

use anyhow::{Context, Result};
use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

const MAGIC: &[u8] = b"#ROSBAG V2.0\n";
/// The bag header record's length, padding included.
const HEADER_LEN: usize = 4096;

/// Record opcodes.
const OP_MESSAGE: u8 = 2;
const OP_HEADER: u8 = 3;
const OP_INDEX: u8 = 4;
const OP_CHUNK: u8 = 5;
const OP_CHUNK_INFO: u8 = 6;
const OP_CONNECTION: u8 = 7;

/// A connection: topic, message type, MD5 of the definition, the definition.
#[derive(Clone, Copy, Debug)]
pub struct Connection {
    /// The topic.
    pub topic: &'static str,
    /// The message type, e.g. `sensor_msgs/Imu`.
    pub tp: &'static str,
    /// Its definition's MD5 sum.
    pub md5: &'static str,
    /// Its definition.
    pub definition: &'static str,
}

/// A record: its header fields, then its data.
fn record(out: &mut Vec<u8>, fields: &[(&str, &[u8])], data: &[u8]) {
    let header = header_fields(fields);
    out.extend_from_slice(&(header.len() as u32).to_le_bytes());
    out.extend_from_slice(&header);
    out.extend_from_slice(&(data.len() as u32).to_le_bytes());
    out.extend_from_slice(data);
}

fn header_fields(fields: &[(&str, &[u8])]) -> Vec<u8> {
    let mut out = Vec::new();
    for (name, value) in fields {
        let len = (name.len() + 1 + value.len()) as u32;
        out.extend_from_slice(&len.to_le_bytes());
        out.extend_from_slice(name.as_bytes());
        out.push(b'=');
        out.extend_from_slice(value);
    }
    out
}

/// A time field: seconds and nanoseconds, u32 each.
fn time(ns: u64) -> [u8; 8] {
    let mut t = [0u8; 8];
    t[..4].copy_from_slice(&((ns / 1_000_000_000) as u32).to_le_bytes());
    t[4..].copy_from_slice(&((ns % 1_000_000_000) as u32).to_le_bytes());
    t
}

/// A bag being written.
pub struct BagWriter {
    path: PathBuf,
    file: BufWriter<File>,
    /// Bytes written so far.
    pos: u64,
    conns: Vec<Connection>,
    /// Per chunk: its position, first and last receive time, messages per connection.
    chunks: Vec<(u64, u64, u64, BTreeMap<u32, u32>)>,
}

impl BagWriter {
    /// Creates `path` for messages on `conns` (connection id = position).
    pub fn create(path: &Path, conns: &[Connection]) -> Result<Self> {
        let file = File::create(path).with_context(|| format!("creating {}", path.display()))?;
        let mut w = Self {
            path: path.to_path_buf(),
            file: BufWriter::new(file),
            pos: 0,
            conns: conns.to_vec(),
            chunks: Vec::new(),
        };
        w.put(MAGIC)?;
        let header = w.header(0);
        w.put(&header)?;
        Ok(w)
    }

    /// The bag header record, padded to `HEADER_LEN` bytes.
    fn header(&self, index_pos: u64) -> Vec<u8> {
        let fields = header_fields(&[
            ("op", &[OP_HEADER]),
            ("index_pos", &index_pos.to_le_bytes()),
            ("conn_count", &(self.conns.len() as u32).to_le_bytes()),
            ("chunk_count", &(self.chunks.len() as u32).to_le_bytes()),
        ]);
        let padding = HEADER_LEN - 8 - fields.len();
        let mut out = Vec::with_capacity(HEADER_LEN);
        out.extend_from_slice(&(fields.len() as u32).to_le_bytes());
        out.extend_from_slice(&fields);
        out.extend_from_slice(&(padding as u32).to_le_bytes());
        out.resize(HEADER_LEN, b' ');
        out
    }

    fn put(&mut self, bytes: &[u8]) -> Result<()> {
        self.file
            .write_all(bytes)
            .with_context(|| format!("writing {}", self.path.display()))?;
        self.pos += bytes.len() as u64;
        Ok(())
    }

    fn connection(&self, out: &mut Vec<u8>, id: u32) {
        let c = &self.conns[id as usize];
        let data = header_fields(&[
            ("topic", c.topic.as_bytes()),
            ("type", c.tp.as_bytes()),
            ("md5sum", c.md5.as_bytes()),
            ("message_definition", c.definition.as_bytes()),
        ]);
        let fields: [(&str, &[u8]); 3] = [
            ("op", &[OP_CONNECTION]),
            ("conn", &id.to_le_bytes()),
            ("topic", c.topic.as_bytes()),
        ];
        record(out, &fields, &data);
    }

    /// Writes one chunk of `messages`: (connection id, receive time ns, body), in time order.
    pub fn chunk(&mut self, messages: &[(u32, u64, Vec<u8>)]) -> Result<()> {
        let (Some(first), Some(last)) = (messages.first(), messages.last()) else {
            return Ok(());
        };
        let mut data = Vec::new();
        let mut index: BTreeMap<u32, Vec<(u64, u32)>> = BTreeMap::new();
        for (conn, t, body) in messages {
            if !index.contains_key(conn) {
                self.connection(&mut data, *conn);
            }
            index
                .entry(*conn)
                .or_default()
                .push((*t, data.len() as u32));
            let fields: [(&str, &[u8]); 3] = [
                ("op", &[OP_MESSAGE]),
                ("conn", &conn.to_le_bytes()),
                ("time", &time(*t)),
            ];
            record(&mut data, &fields, body);
        }
        let mut out = Vec::with_capacity(data.len() + 256);
        let fields: [(&str, &[u8]); 3] = [
            ("op", &[OP_CHUNK]),
            ("compression", b"none"),
            ("size", &(data.len() as u32).to_le_bytes()),
        ];
        record(&mut out, &fields, &data);
        for (conn, entries) in &index {
            let mut d = Vec::with_capacity(entries.len() * 12);
            for (t, offset) in entries {
                d.extend_from_slice(&time(*t));
                d.extend_from_slice(&offset.to_le_bytes());
            }
            let fields: [(&str, &[u8]); 4] = [
                ("op", &[OP_INDEX]),
                ("ver", &1u32.to_le_bytes()),
                ("conn", &conn.to_le_bytes()),
                ("count", &(entries.len() as u32).to_le_bytes()),
            ];
            record(&mut out, &fields, &d);
        }
        let counts = index.iter().map(|(c, e)| (*c, e.len() as u32)).collect();
        let at = self.pos;
        self.chunks.push((at, first.1, last.1, counts));
        self.put(&out)
    }

    /// Writes the index section and the header that points to it.
    pub fn finish(mut self) -> Result<()> {
        let index_pos = self.pos;
        let mut out = Vec::new();
        for id in 0..self.conns.len() as u32 {
            self.connection(&mut out, id);
        }
        for (at, t0, t1, counts) in &self.chunks {
            let mut d = Vec::new();
            for (c, n) in counts {
                d.extend_from_slice(&c.to_le_bytes());
                d.extend_from_slice(&n.to_le_bytes());
            }
            let fields: [(&str, &[u8]); 6] = [
                ("op", &[OP_CHUNK_INFO]),
                ("ver", &1u32.to_le_bytes()),
                ("chunk_pos", &at.to_le_bytes()),
                ("start_time", &time(*t0)),
                ("end_time", &time(*t1)),
                ("count", &(counts.len() as u32).to_le_bytes()),
            ];
            record(&mut out, &fields, &d);
        }
        self.put(&out)?;
        let header = self.header(index_pos);
        let file = &mut self.file;
        file.seek(SeekFrom::Start(MAGIC.len() as u64))
            .and_then(|_| file.write_all(&header))
            .and_then(|_| file.flush())
            .with_context(|| format!("writing {}", self.path.display()))
    }
}
