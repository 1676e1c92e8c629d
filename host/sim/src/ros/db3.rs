//! A ROS 2 bag in sqlite3 storage as `ros2 bag record` (Humble) writes it: a folder holding
//! `NAME_0.db3` (the tables `schema`, `metadata`, `topics` and `messages`, and the index on
//! the messages' time) and, once closed, `metadata.yaml` saying what the file holds.

use super::Topic;
use anyhow::{Context, Result};
use rusqlite::{params, Connection};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A bag being written.
pub struct Db3Writer {
    dir: PathBuf,
    file: String,
    conn: Connection,
    topics: Vec<Topic>,
    /// Messages per topic, first and last receive time.
    counts: Vec<u64>,
    span: Option<(u64, u64)>,
}

impl Db3Writer {
    /// Creates the bag folder `dir` (its file `NAME_0.db3`, NAME the folder's name) for
    /// messages on `topics` (topic id = position + 1).
    pub fn create(dir: &Path, topics: &[Topic]) -> Result<Self> {
        let shown = dir.display();
        std::fs::create_dir_all(dir).with_context(|| format!("creating {shown}"))?;
        let name = dir.file_name().and_then(|n| n.to_str()).unwrap_or("bag");
        let file = format!("{name}_0.db3");
        let conn =
            Connection::open(dir.join(&file)).with_context(|| format!("creating {shown}"))?;
        conn.execute_batch(
            "PRAGMA journal_mode = MEMORY;
             PRAGMA synchronous = OFF;
             CREATE TABLE schema(schema_version INTEGER PRIMARY KEY,ros_distro TEXT NOT NULL);
             CREATE TABLE metadata(id INTEGER PRIMARY KEY,metadata_version INTEGER NOT NULL,
                                   metadata TEXT NOT NULL);
             CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type TEXT NOT NULL,
                                 serialization_format TEXT NOT NULL,
                                 offered_qos_profiles TEXT NOT NULL);
             CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER NOT NULL,
                                   timestamp INTEGER NOT NULL, data BLOB NOT NULL);
             CREATE INDEX timestamp_idx ON messages (timestamp ASC);
             INSERT INTO schema VALUES (3, 'humble');
             BEGIN;",
        )
        .with_context(|| format!("writing {shown}"))?;
        for (k, t) in topics.iter().enumerate() {
            conn.execute(
                "INSERT INTO topics VALUES (?1, ?2, ?3, 'cdr', '')",
                params![k as i64 + 1, t.name, t.ros2],
            )
            .with_context(|| format!("writing {shown}"))?;
        }
        Ok(Self {
            dir: dir.to_path_buf(),
            file,
            conn,
            topics: topics.to_vec(),
            counts: vec![0; topics.len()],
            span: None,
        })
    }

    /// Writes message `body` on topic `topic` (its position), received at `ns`.
    pub fn write(&mut self, topic: usize, ns: u64, body: &[u8]) -> Result<()> {
        self.conn
            .prepare_cached("INSERT INTO messages (topic_id, timestamp, data) VALUES (?1, ?2, ?3)")
            .and_then(|mut s| s.execute(params![topic as i64 + 1, ns as i64, body]))
            .with_context(|| format!("writing {}", self.dir.display()))?;
        self.counts[topic] += 1;
        self.span = Some(match self.span {
            Some((a, b)) => (a.min(ns), b.max(ns)),
            None => (ns, ns),
        });
        Ok(())
    }

    /// Commits the messages and writes `metadata.yaml`.
    pub fn finish(self) -> Result<()> {
        let shown = self.dir.display();
        self.conn
            .execute_batch("COMMIT;")
            .with_context(|| format!("writing {shown}"))?;
        self.conn
            .close()
            .map_err(|(_, e)| e)
            .with_context(|| format!("writing {shown}"))?;
        let (start, end) = self.span.unwrap_or((0, 0));
        let total: u64 = self.counts.iter().sum();
        let mut y = String::new();
        let _ = write!(
            y,
            "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n  \
             duration:\n    nanoseconds: {}\n  starting_time:\n    nanoseconds_since_epoch: \
             {start}\n  message_count: {total}\n  topics_with_message_count:\n",
            end - start
        );
        for (t, n) in self.topics.iter().zip(&self.counts) {
            let _ = write!(
                y,
                "    - topic_metadata:\n        name: {}\n        type: {}\n        \
                 serialization_format: cdr\n        offered_qos_profiles: \"\"\n      \
                 message_count: {n}\n",
                t.name, t.ros2
            );
        }
        let _ = write!(
            y,
            "  compression_format: \"\"\n  compression_mode: \"\"\n  relative_file_paths:\n    \
             - {file}\n  files:\n    - path: {file}\n      starting_time:\n        \
             nanoseconds_since_epoch: {start}\n      duration:\n        nanoseconds: {}\n      \
             message_count: {total}\n",
            end - start,
            file = self.file
        );
        let path = self.dir.join("metadata.yaml");
        std::fs::write(&path, y).with_context(|| format!("writing {}", path.display()))
    }
}
