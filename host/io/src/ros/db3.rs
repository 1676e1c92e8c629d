//! ROS 2 bags in sqlite3 storage, as `ros2 bag record` writes them by default up to Humble: a
//! folder of `metadata.yaml` and one or more `.db3` files (a split bag's in the order the
//! metadata lists them), or one `.db3` file read alone.
//!
//! Each file is an SQLite database (read with `rusqlite`, read-only) whose `topics` table
//! names each topic's type and whose `messages` table holds every message's topic, receive
//! time and CDR bytes. Opening reads the topics and counts the messages, which
//! [`metadata`] compares with what `metadata.yaml` says (a difference is a dataset warning:
//! the storage is read as it is). A stream first lists the chosen topics' messages (id, time,
//! length: a few bytes each) in receive-time order, then reads each message when it is asked
//! for, so neither the bag nor more than one message of it is held in memory, and a message
//! larger than the limit the scan capacity sets ([`pointcloud2::record_limit`]) is refused
//! before it is read. A file that SQLite finds damaged ends the stream with its error after
//! the messages listed before the damage. rosbag2's zstd compression is read, of whole files
//! (decompressed to a temporary file) or of each message.

pub mod metadata;

use super::frames;
use super::pointcloud2;
use super::recording::{Message, MessageStream, Recording};
use crate::dataset::{Dataset, Format, OpenOptions};
use anyhow::{anyhow, bail, Context, Result};
use metadata::{Compression, Metadata};
use rusqlite::{Connection, OpenFlags};
use std::collections::{BTreeMap, HashMap};
use std::io::Read;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

/// Opens a ROS 2 sqlite3 bag (a folder, its `metadata.yaml` or one `.db3` file) and streams
/// the frames of `opts.topic` or of the only topic that has frames.
pub fn open(path: &Path, opts: &OpenOptions) -> Result<Dataset> {
    let bag = Db3::open(path, pointcloud2::record_limit(opts.scan_points))?;
    frames::open(Box::new(bag), opts)
}

/// Whether `path` is a sqlite3 bag: a `.db3` file, a `metadata.yaml`, or a folder with either.
pub fn detect(path: &Path) -> bool {
    let is_db3 = |p: &Path| {
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
        let name = name.to_ascii_lowercase();
        name.ends_with(".db3") || name.ends_with(".db3.zstd")
    };
    if path.is_dir() {
        if path.join(metadata::NAME).is_file() {
            return true;
        }
        return std::fs::read_dir(path)
            .map(|d| d.flatten().any(|e| is_db3(&e.path())))
            .unwrap_or(false);
    }
    is_db3(path) || path.file_name().is_some_and(|n| n == metadata::NAME)
}

/// One storage file.
struct Db3File {
    /// As shown in messages.
    shown: String,
    conn: Connection,
    /// Topic ids: name and type.
    topics: HashMap<i64, (String, String)>,
    /// The decompressed copy `conn` reads, removed when the bag is dropped.
    copy: Option<tempfile::TempPath>,
}

/// A sqlite3 bag opened for reading.
pub struct Db3 {
    label: String,
    files: Vec<Db3File>,
    /// Messages per topic, counted in the storage.
    counts: BTreeMap<String, u64>,
    compression: Compression,
    limit: u64,
    warnings: Vec<String>,
    /// The first SQLite error met while counting, naming the file.
    damage: Option<String>,
}

/// Which files a path stands for, what the metadata says of them, and warnings.
fn resolve(path: &Path) -> Result<(Vec<PathBuf>, Option<Metadata>, Vec<String>)> {
    let dir = if path.is_dir() {
        Some(path)
    } else if path.file_name().is_some_and(|n| n == metadata::NAME) {
        path.parent()
    } else {
        None
    };
    let Some(dir) = dir else {
        if !path.is_file() {
            bail!("{}: no such file", path.display());
        }
        return Ok((vec![path.to_path_buf()], None, Vec::new()));
    };
    if let Some(meta) = Metadata::read(dir)? {
        if meta.files.is_empty() {
            bail!("{}: lists no storage files", meta.path.display());
        }
        return Ok((meta.files.clone(), Some(meta), Vec::new()));
    }
    // Not closed (rosbag2 writes the metadata last), or copied without it: the `.db3` files
    // in the order their split numbers give.
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("{}: cannot list", dir.display()))?
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "db3"))
        .collect();
    files.sort_by_key(|p| split_number(p));
    if files.is_empty() {
        bail!(
            "{}: no {} and no .db3 files: not a ROS 2 sqlite3 bag",
            dir.display(),
            metadata::NAME
        );
    }
    let warning = format!(
        "{}: no {}: its {} .db3 file(s) are read in the order of their numbers (a bag not \
         closed?)",
        dir.display(),
        metadata::NAME,
        files.len()
    );
    Ok((files, None, vec![warning]))
}

/// The split number of `name_N.db3`, then the name.
fn split_number(p: &Path) -> (u64, String) {
    let stem = p.file_stem().and_then(|s| s.to_str()).unwrap_or("");
    let n = stem.rsplit('_').next().and_then(|n| n.parse().ok());
    (n.unwrap_or(u64::MAX), stem.to_string())
}

/// The zstd-compressed `path` decompressed to a temporary file.
fn decompress_file(path: &Path) -> Result<tempfile::TempPath> {
    let shown = path.display();
    let input = std::fs::File::open(path).with_context(|| format!("{shown}: cannot open"))?;
    let mut out = tempfile::NamedTempFile::new().context("cannot create a temporary file")?;
    let mut decoder =
        zstd::stream::read::Decoder::new(input).with_context(|| format!("{shown}: zstd"))?;
    std::io::copy(&mut decoder, out.as_file_mut())
        .with_context(|| format!("{shown}: cannot decompress (zstd)"))?;
    Ok(out.into_temp_path())
}

/// The SQLite file header: page size (1 means 65,536), the change counter, the page count
/// and the change counter that count is valid for.
mod header {
    use core::ops::Range;
    pub const MAGIC: &[u8] = b"SQLite format 3\0";
    pub const PAGE_SIZE: Range<usize> = 16..18;
    pub const CHANGE_COUNTER: Range<usize> = 24..28;
    pub const PAGES: Range<usize> = 28..32;
    pub const VALID_FOR: Range<usize> = 92..96;
    pub const LEN: usize = 100;
}

/// Why the SQLite file `path` is shorter than its header says, if it is (cut short in a copy
/// or a crash): SQLite reads the missing pages as zeros, so what it finds there is not there.
fn cut_short(path: &Path) -> Option<String> {
    let mut head = [0u8; header::LEN];
    let mut file = std::fs::File::open(path).ok()?;
    file.read_exact(&mut head).ok()?;
    let len = file.metadata().ok()?.len();
    let word = |r: std::ops::Range<usize>| u32::from_be_bytes(head[r].try_into().unwrap_or([0; 4]));
    let page = match u16::from_be_bytes([
        head[header::PAGE_SIZE.start],
        head[header::PAGE_SIZE.end - 1],
    ]) {
        1 => 65_536,
        n => u64::from(n),
    };
    let valid = word(header::CHANGE_COUNTER) == word(header::VALID_FOR);
    let want = u64::from(word(header::PAGES)) * page;
    (head.starts_with(header::MAGIC) && valid && len < want)
        .then(|| format!("{len} bytes where its header says {want}: the file is cut short"))
}

fn open_file(path: &Path, compression: Compression) -> Result<Db3File> {
    let shown = path.display().to_string();
    let copy = match compression {
        Compression::Files => Some(decompress_file(path)?),
        _ => None,
    };
    let read = copy.as_deref().unwrap_or(path);
    let flags = OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX;
    let conn = Connection::open_with_flags(read, flags)
        .map_err(|e| anyhow!("{shown}: cannot open ({e})"))?;
    let not_a_bag = |e: rusqlite::Error| anyhow!("{shown}: not a ROS 2 bag's sqlite3 file ({e})");
    let mut topics = HashMap::new();
    {
        let mut stmt = conn
            .prepare("SELECT id, name, type, serialization_format FROM topics")
            .map_err(not_a_bag)?;
        let mut rows = stmt.query([]).map_err(not_a_bag)?;
        while let Some(row) = rows.next().map_err(not_a_bag)? {
            let id: i64 = row.get(0).map_err(not_a_bag)?;
            let name: String = row.get(1).map_err(not_a_bag)?;
            let tp: String = row.get(2).map_err(not_a_bag)?;
            let format: String = row.get(3).map_err(not_a_bag)?;
            // Unset in early bags; anything else is not CDR and cannot be read.
            let tp = match format.as_str() {
                "" | "cdr" => tp,
                other => format!("{tp} (serialized as {other})"),
            };
            topics.insert(id, (name, tp));
        }
    }
    conn.prepare("SELECT id, topic_id, timestamp, data FROM messages LIMIT 0")
        .map_err(not_a_bag)?;
    Ok(Db3File {
        shown,
        conn,
        topics,
        copy,
    })
}

/// Messages per topic id of one file.
fn count(file: &Db3File) -> rusqlite::Result<HashMap<i64, u64>> {
    let mut stmt = file
        .conn
        .prepare("SELECT topic_id, COUNT(*) FROM messages GROUP BY topic_id")?;
    let rows = stmt.query_map([], |r| Ok((r.get::<_, i64>(0)?, r.get::<_, i64>(1)?)))?;
    rows.map(|r| r.map(|(id, n)| (id, n.max(0) as u64)))
        .collect()
}

impl Db3 {
    /// Opens the bag at `path` (see [`open`]); messages larger than `limit` bytes are refused.
    pub fn open(path: &Path, limit: u64) -> Result<Self> {
        let (paths, meta, mut warnings) = resolve(path)?;
        let compression = match (&meta, path.extension()) {
            (Some(m), _) => m.compression,
            (None, Some(e)) if e == "zstd" => Compression::Files,
            _ => Compression::None,
        };
        let mut files = Vec::new();
        for p in &paths {
            if !p.exists() {
                let listed = meta
                    .as_ref()
                    .map_or(String::new(), |m| format!("{} lists ", m.path.display()));
                bail!(
                    "{listed}{}, which does not exist (open one .db3 file to read it alone)",
                    p.display()
                );
            }
            files.push(open_file(p, compression)?);
        }
        let mut counts = BTreeMap::new();
        let mut types = BTreeMap::new();
        let mut file_counts = BTreeMap::new();
        let mut damage = None;
        for (f, p) in files.iter().zip(&paths) {
            let read = f.copy.as_deref().unwrap_or(p);
            if let Some(reason) = cut_short(read) {
                warnings.push(format!(
                    "{}: {reason}; the messages past the cut are lost",
                    f.shown
                ));
            }
            for (name, tp) in f.topics.values() {
                if let Some(first) = types.get(name).filter(|t| *t != tp) {
                    warnings.push(format!(
                        "{}: topic {name} carries {tp} here, {first} in an earlier file",
                        f.shown
                    ));
                }
                types.entry(name.clone()).or_insert_with(|| tp.clone());
                counts.entry(name.clone()).or_insert(0);
            }
            match count(f) {
                Ok(per_id) => {
                    let mut total = 0;
                    for (id, n) in per_id {
                        if let Some((name, _)) = f.topics.get(&id) {
                            *counts.entry(name.clone()).or_insert(0) += n;
                        }
                        total += n;
                    }
                    let name = Path::new(&f.shown).file_name().and_then(|n| n.to_str());
                    file_counts.insert(name.unwrap_or_default().to_string(), total);
                }
                Err(e) => {
                    damage.get_or_insert_with(|| format!("{}: {e}", f.shown));
                }
            }
        }
        if let Some(m) = &meta {
            if damage.is_none() {
                warnings.extend(m.disagreements(&types, &counts, &file_counts));
            }
        }
        Ok(Self {
            label: path.display().to_string(),
            files,
            counts,
            compression,
            limit,
            warnings,
            damage,
        })
    }

    /// The ids of `topics` in file `f`, and for each id its place in `topics`.
    fn ids(&self, f: usize, topics: &[String]) -> HashMap<i64, usize> {
        self.files[f]
            .topics
            .iter()
            .filter_map(|(&id, (name, _))| Some((id, topics.iter().position(|t| t == name)?)))
            .collect()
    }

    /// `data` as the bag stores it, decompressed into `out` if messages are compressed.
    fn unpack(&self, data: &[u8], out: &mut Vec<u8>) -> Result<(), String> {
        out.clear();
        match self.compression {
            Compression::Messages => {
                let decoder =
                    zstd::stream::read::Decoder::new(data).map_err(|e| format!("zstd: {e}"))?;
                decoder
                    .take(self.limit.saturating_add(1))
                    .read_to_end(out)
                    .map_err(|e| format!("cannot decompress (zstd): {e}"))?;
                if out.len() as u64 > self.limit {
                    return Err(format!(
                        "decompresses to more than the {}-byte limit",
                        self.limit
                    ));
                }
            }
            _ => out.extend_from_slice(data),
        }
        Ok(())
    }
}

/// One message of a stream's plan.
#[derive(Clone, Copy, Debug)]
struct Entry {
    file: usize,
    id: i64,
    topic_id: i64,
    topic: usize,
    time_ns: u64,
    len: u64,
}

/// `SELECT columns FROM messages` of the topic ids `ids`, in receive-time order.
fn select(columns: &str, ids: &HashMap<i64, usize>) -> String {
    let list: Vec<String> = ids.keys().map(i64::to_string).collect();
    format!(
        "SELECT {columns} FROM messages WHERE topic_id IN ({}) ORDER BY timestamp, id",
        list.join(",")
    )
}

impl Recording for Db3 {
    fn label(&self) -> &str {
        &self.label
    }

    fn format(&self) -> Format {
        Format::Db3
    }

    fn ros1(&self) -> bool {
        false
    }

    fn topics(&self) -> Vec<(String, String)> {
        let mut out: Vec<(String, String)> = self
            .files
            .iter()
            .flat_map(|f| f.topics.values().cloned())
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    fn count(&self, topic: &str) -> Option<usize> {
        if self.damage.is_some() {
            return None;
        }
        self.counts.get(topic).map(|&n| n as usize)
    }

    fn take_warnings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.warnings)
    }

    fn damage(&self) -> Option<String> {
        self.damage.clone()
    }

    fn scan(
        &mut self,
        topics: &[String],
        f: &mut dyn FnMut(Message<'_>) -> ControlFlow<()>,
    ) -> Result<()> {
        let mut buf = Vec::new();
        for k in 0..self.files.len() {
            let ids = self.ids(k, topics);
            if ids.is_empty() {
                continue;
            }
            let file = &self.files[k];
            let damaged = |e: rusqlite::Error| anyhow!("{}: {e}", file.shown);
            let mut stmt = file
                .conn
                .prepare(&select("topic_id, timestamp, data", &ids))
                .map_err(damaged)?;
            let mut rows = stmt.query([]).map_err(damaged)?;
            while let Some(row) = rows.next().map_err(damaged)? {
                let topic_id: i64 = row.get(0).map_err(damaged)?;
                let time: i64 = row.get(1).map_err(damaged)?;
                let data = row.get_ref(2).map_err(damaged)?;
                let data = data.as_blob().map_err(|e| anyhow!("{}: {e}", file.shown))?;
                if data.len() as u64 > self.limit {
                    bail!(
                        "{}: a message of {} bytes, more than the {}-byte limit",
                        file.shown,
                        data.len(),
                        self.limit
                    );
                }
                self.unpack(data, &mut buf)
                    .map_err(|e| anyhow!("{}: {e}", file.shown))?;
                let (Some(&topic), Some((_, tp))) =
                    (ids.get(&topic_id), file.topics.get(&topic_id))
                else {
                    continue;
                };
                let message = Message {
                    topic,
                    time_ns: time.max(0) as u64,
                    data: &buf,
                    tp,
                    md5: None,
                    warning: None,
                };
                if f(message).is_break() {
                    return Ok(());
                }
            }
        }
        Ok(())
    }

    fn stream(self: Box<Self>, topics: &[String]) -> Result<Box<dyn MessageStream>> {
        let mut plan = Vec::new();
        let mut damage = None;
        'files: for k in 0..self.files.len() {
            let ids = self.ids(k, topics);
            if ids.is_empty() {
                continue;
            }
            let file = &self.files[k];
            let mut list = || -> rusqlite::Result<()> {
                let mut stmt = file
                    .conn
                    .prepare(&select("id, topic_id, timestamp, length(data)", &ids))?;
                let mut rows = stmt.query([])?;
                while let Some(row) = rows.next()? {
                    let topic_id: i64 = row.get(1)?;
                    plan.push(Entry {
                        file: k,
                        id: row.get(0)?,
                        topic_id,
                        topic: ids.get(&topic_id).copied().unwrap_or(0),
                        time_ns: row.get::<_, i64>(2)?.max(0) as u64,
                        len: row.get::<_, i64>(3)?.max(0) as u64,
                    });
                }
                Ok(())
            };
            if let Err(e) = list() {
                damage = Some(format!("{}: {e}", file.shown));
                break 'files;
            }
        }
        let names = topics.join(", ");
        let order = pointcloud2::time_order(&self.label, &names, &mut plan, |e| e.time_ns);
        Ok(Box::new(Db3Stream {
            bag: *self,
            plan,
            next: 0,
            buf: Vec::new(),
            damage,
            warnings: order.into_iter().collect(),
        }))
    }
}

/// The messages of some topics of an open sqlite3 bag.
struct Db3Stream {
    bag: Db3,
    /// The messages, in receive-time order.
    plan: Vec<Entry>,
    next: usize,
    buf: Vec<u8>,
    /// Where listing the messages stopped, if a file is damaged.
    damage: Option<String>,
    /// That the files are out of time order, for the dataset's warnings.
    warnings: Vec<String>,
}

impl MessageStream for Db3Stream {
    fn len_hint(&self) -> Option<usize> {
        Some(self.plan.len())
    }

    fn next_message(&mut self) -> Result<Option<Message<'_>>> {
        let Some(&e) = self.plan.get(self.next) else {
            return match self.damage.take() {
                Some(d) => Err(anyhow!("{d}")),
                None => Ok(None),
            };
        };
        self.next += 1;
        let file = &self.bag.files[e.file];
        if e.len > self.bag.limit {
            bail!(
                "{}: message {} holds {} bytes, more than the {}-byte limit",
                file.shown,
                e.id,
                e.len,
                self.bag.limit
            );
        }
        let mut stmt = file
            .conn
            .prepare_cached("SELECT data FROM messages WHERE id = ?1")
            .map_err(|err| anyhow!("{}: {err}", file.shown))?;
        let (bag, buf) = (&self.bag, &mut self.buf);
        let unpacked = stmt
            .query_row(
                [e.id],
                |row| Ok(bag.unpack(row.get_ref(0)?.as_blob()?, buf)),
            )
            .map_err(|err| err.to_string())
            .and_then(|r| r);
        unpacked.map_err(|err| anyhow!("{}: message {}: {err}", file.shown, e.id))?;
        let tp = file
            .topics
            .get(&e.topic_id)
            .map_or("", |(_, tp)| tp.as_str());
        Ok(Some(Message {
            topic: e.topic,
            time_ns: e.time_ns,
            data: &self.buf,
            tp,
            md5: None,
            warning: None,
        }))
    }

    fn take_warnings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.warnings)
    }

    fn seek(&mut self, k: usize) -> bool {
        self.next = k.min(self.plan.len());
        true
    }
}

#[cfg(test)]
mod tests;
