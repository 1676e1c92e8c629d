//! The messages of some topics of an open sqlite3 bag: first listed (id, topic, time, length:
//! a few bytes each) in receive-time order, then read one by one when asked for. A file SQLite
//! finds damaged while listing ends the stream with its error after the messages listed
//! before the damage.

use super::Db3;
use crate::ros::pointcloud2;
use crate::ros::recording::{Message, MessageStream};
use anyhow::{anyhow, bail, Result};
use std::collections::HashMap;

/// The messages of `topics` of `bag`, listed in receive-time order, read one by one.
pub(super) fn open(bag: Db3, topics: &[String]) -> Result<Box<dyn MessageStream>> {
    let mut plan = Vec::new();
    let mut damage = None;
    'files: for k in 0..bag.files.len() {
        let ids = bag.ids(k, topics);
        if ids.is_empty() {
            continue;
        }
        let file = &bag.files[k];
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
    let order = pointcloud2::time_order(&bag.label, &names, &mut plan, |e| e.time_ns);
    Ok(Box::new(Db3Stream {
        bag,
        plan,
        next: 0,
        buf: Vec::new(),
        damage,
        warnings: order.into_iter().collect(),
    }))
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
pub(super) fn select(columns: &str, ids: &HashMap<i64, usize>) -> String {
    let list: Vec<String> = ids.keys().map(i64::to_string).collect();
    format!(
        "SELECT {columns} FROM messages WHERE topic_id IN ({}) ORDER BY timestamp, id",
        list.join(",")
    )
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
