//! The files of a sqlite3 bag: which ones a path stands for (a folder's `metadata.yaml` or its
//! `.db3` files by number), each opened read-only (decompressed first if zstd-compressed
//! whole), its topics read and its messages counted, and whether it is shorter than its SQLite
//! header says.

use super::metadata::{self, Compression, Metadata};
use anyhow::{anyhow, bail, Context, Result};
use rusqlite::{Connection, OpenFlags};
use std::collections::HashMap;
use std::io::Read;
use std::path::{Path, PathBuf};

/// One storage file.
pub(super) struct Db3File {
    /// As shown in messages.
    pub(super) shown: String,
    pub(super) conn: Connection,
    /// Topic ids: name and type.
    pub(super) topics: HashMap<i64, (String, String)>,
    /// The decompressed copy `conn` reads, removed when the bag is dropped.
    pub(super) copy: Option<tempfile::TempPath>,
}

/// Which files a path stands for, what the metadata says of them, and warnings.
pub(super) fn resolve(path: &Path) -> Result<(Vec<PathBuf>, Option<Metadata>, Vec<String>)> {
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
pub(super) fn cut_short(path: &Path) -> Option<String> {
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

pub(super) fn open_file(path: &Path, compression: Compression) -> Result<Db3File> {
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
pub(super) fn count(file: &Db3File) -> rusqlite::Result<HashMap<i64, u64>> {
    let mut stmt = file
        .conn
        .prepare("SELECT topic_id, COUNT(*) FROM messages GROUP BY topic_id")?;
    let rows = stmt.query_map([], |r| Ok((r.get::<_, i64>(0)?, r.get::<_, i64>(1)?)))?;
    rows.map(|r| r.map(|(id, n)| (id, n.max(0) as u64)))
        .collect()
}
