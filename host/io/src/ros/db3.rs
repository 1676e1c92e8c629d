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

mod files;
pub mod metadata;
mod stream;

use super::frames;
use super::pointcloud2;
use super::recording::{Message, MessageStream, Recording};
use crate::dataset::{Dataset, Format, OpenOptions};
use anyhow::{anyhow, bail, Result};
use files::{count, cut_short, open_file, resolve, Db3File};
use metadata::Compression;
use std::collections::{BTreeMap, HashMap};
use std::io::Read;
use std::ops::ControlFlow;
use std::path::Path;
use stream::select;

/// Opens a ROS 2 sqlite3 bag (a folder, its `metadata.yaml` or one `.db3` file) and streams
/// the frames of `opts.topic` or of the only topic that has frames.
pub fn open(path: &Path, opts: &OpenOptions) -> Result<Dataset> {
    let bag = Db3::open(path, pointcloud2::record_limit(opts.scan_points))?;
    frames::open(Box::new(bag), opts)
}

/// Whether `path` is a sqlite3 bag: a `.db3` file, a rosbag2 `metadata.yaml`, or a folder with
/// either.
pub fn detect(path: &Path) -> bool {
    let is_db3 = |p: &Path| {
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
        let name = name.to_ascii_lowercase();
        name.ends_with(".db3") || name.ends_with(".db3.zstd")
    };
    // Other datasets have a metadata.yaml too: only rosbag2's says what it is.
    let is_bag_metadata = |p: &Path| {
        let mut head = [0u8; 512];
        let n = std::fs::File::open(p)
            .and_then(|mut f| f.read(&mut head))
            .unwrap_or(0);
        String::from_utf8_lossy(&head[..n]).contains("rosbag2_bagfile_information")
    };
    if path.is_dir() {
        return is_bag_metadata(&path.join(metadata::NAME))
            || std::fs::read_dir(path)
                .map(|d| d.flatten().any(|e| is_db3(&e.path())))
                .unwrap_or(false);
    }
    is_db3(path) || (path.file_name().is_some_and(|n| n == metadata::NAME) && is_bag_metadata(path))
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
        stream::open(*self, topics)
    }
}

#[cfg(test)]
mod tests;
