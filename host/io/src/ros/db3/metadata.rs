//! A ROS 2 bag's `metadata.yaml` (`rosbag2_bagfile_information`, versions 1 to 9): which
//! storage it uses, its files in order, and what it says each topic and file holds. The files
//! themselves are the truth; what the metadata says is kept to compare with them
//! ([`Metadata::disagreements`]), since a bag copied in part or edited by hand says more than
//! it holds.

use anyhow::{bail, Context, Result};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The file's name in a bag folder.
pub const NAME: &str = "metadata.yaml";

#[derive(Deserialize)]
struct Raw {
    rosbag2_bagfile_information: Info,
}

#[derive(Deserialize)]
struct Info {
    version: Option<u32>,
    #[serde(default)]
    storage_identifier: String,
    #[serde(default)]
    relative_file_paths: Vec<String>,
    message_count: Option<u64>,
    #[serde(default)]
    topics_with_message_count: Vec<TopicCount>,
    #[serde(default)]
    compression_format: String,
    #[serde(default)]
    compression_mode: String,
    #[serde(default)]
    files: Vec<FileInfo>,
}

#[derive(Deserialize)]
struct TopicCount {
    topic_metadata: TopicMeta,
    #[serde(default)]
    message_count: u64,
}

#[derive(Deserialize)]
struct TopicMeta {
    name: String,
    #[serde(rename = "type")]
    tp: String,
    #[serde(default)]
    serialization_format: String,
}

#[derive(Deserialize)]
struct FileInfo {
    path: String,
    message_count: Option<u64>,
}

/// How the bag's files or messages are compressed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compression {
    /// Not compressed.
    None,
    /// Each file is zstd-compressed whole (`.db3.zstd`).
    Files,
    /// Each message's data is zstd-compressed.
    Messages,
}

/// What `metadata.yaml` says.
#[derive(Clone, Debug, PartialEq)]
pub struct Metadata {
    /// Where it was read from.
    pub path: PathBuf,
    /// The storage files, in order, as paths that exist where the metadata can tell.
    pub files: Vec<PathBuf>,
    /// How they are compressed.
    pub compression: Compression,
    /// Messages in the whole bag, if it says.
    pub message_count: Option<u64>,
    /// Per topic: type, serialization format, messages.
    pub topics: BTreeMap<String, (String, String, u64)>,
    /// Per file (as listed): messages, if it says.
    pub file_counts: BTreeMap<String, u64>,
}

impl Metadata {
    /// Reads the `metadata.yaml` of the bag folder `dir`; `Ok(None)` when there is none.
    pub fn read(dir: &Path) -> Result<Option<Self>> {
        let path = dir.join(NAME);
        if !path.exists() {
            return Ok(None);
        }
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("{}: cannot read", path.display()))?;
        Self::parse(&path, &text).map(Some)
    }

    /// Parses `text`, the metadata at `path`.
    pub fn parse(path: &Path, text: &str) -> Result<Self> {
        let shown = path.display();
        let raw: Raw = serde_yaml_ng::from_str(text)
            .with_context(|| format!("{shown}: not a rosbag2 metadata file"))?;
        let info = raw.rosbag2_bagfile_information;
        match info.storage_identifier.as_str() {
            "" | "sqlite3" => {}
            "mcap" => bail!(
                "{shown}: the bag is stored as MCAP: give its .mcap file ({})",
                info.relative_file_paths.join(", ")
            ),
            other => bail!("{shown}: storage `{other}` is not sqlite3"),
        }
        let compression = match (
            info.compression_format.as_str(),
            info.compression_mode.to_ascii_lowercase().as_str(),
        ) {
            ("", _) | (_, "" | "none") => Compression::None,
            ("zstd", "file") => Compression::Files,
            ("zstd", "message") => Compression::Messages,
            (format, mode) => bail!(
                "{shown}: compression {format} ({mode}) is not read (zstd, by file or message)"
            ),
        };
        let dir = path.parent().unwrap_or(Path::new("."));
        let files = info
            .relative_file_paths
            .iter()
            .map(|f| locate(dir, f))
            .collect();
        let topics = info
            .topics_with_message_count
            .into_iter()
            .map(|t| {
                let m = t.topic_metadata;
                (m.name, (m.tp, m.serialization_format, t.message_count))
            })
            .collect();
        let file_counts = info
            .files
            .into_iter()
            .filter_map(|f| Some((f.path, f.message_count?)))
            .collect();
        let _ = info.version;
        Ok(Self {
            path: path.to_path_buf(),
            files,
            compression,
            message_count: info.message_count,
            topics,
            file_counts,
        })
    }

    /// Where what the metadata says differs from what the files hold: `counts` per topic and
    /// `types` per topic as the storage has them, `file_counts` per file name. One line each,
    /// naming the metadata.
    pub fn disagreements(
        &self,
        types: &BTreeMap<String, String>,
        counts: &BTreeMap<String, u64>,
        file_counts: &BTreeMap<String, u64>,
    ) -> Vec<String> {
        let shown = self.path.display();
        let mut out = Vec::new();
        for (topic, (tp, _, n)) in &self.topics {
            match (types.get(topic), counts.get(topic).copied().unwrap_or(0)) {
                (None, _) if *n > 0 => out.push(format!(
                    "{shown}: topic {topic} ({n} messages) is in no storage file"
                )),
                (Some(real), _) if real != tp => out.push(format!(
                    "{shown}: says {topic} carries {tp}, the storage says {real}: read as {real}"
                )),
                (Some(_), held) if held != *n => out.push(format!(
                    "{shown}: says {topic} has {n} messages, the storage holds {held}"
                )),
                _ => {}
            }
        }
        for topic in types.keys().filter(|t| !self.topics.contains_key(*t)) {
            out.push(format!(
                "{shown}: topic {topic} is in the storage but not in the metadata"
            ));
        }
        let held: u64 = counts.values().sum();
        if let Some(n) = self.message_count.filter(|n| *n != held) {
            out.push(format!(
                "{shown}: says the bag has {n} messages, the storage holds {held}"
            ));
        }
        for (file, n) in &self.file_counts {
            let name = Path::new(file).file_name().and_then(|f| f.to_str());
            let held = name.and_then(|f| file_counts.get(f));
            if let Some(held) = held.filter(|h| *h != n) {
                out.push(format!(
                    "{shown}: says {file} has {n} messages, it holds {held}"
                ));
            }
        }
        out
    }
}

/// A listed file under `dir`: as written, else by its name alone (early rosbag2 versions
/// wrote the bag folder's name before it).
fn locate(dir: &Path, listed: &str) -> PathBuf {
    let path = dir.join(listed);
    if path.exists() {
        return path;
    }
    match Path::new(listed).file_name() {
        Some(name) if dir.join(name).exists() => dir.join(name),
        _ => path,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "rosbag2_bagfile_information:
  version: 5
  storage_identifier: sqlite3
  message_count: 4
  topics_with_message_count:
    - topic_metadata:
        name: /pandar_packets
        type: pandar_msgs/msg/PandarScan
        serialization_format: cdr
        offered_qos_profiles: \"\"
      message_count: 4
  compression_format: \"\"
  compression_mode: \"\"
  relative_file_paths:
    - a_0.db3
  files:
    - path: a_0.db3
      message_count: 4
";

    #[test]
    fn nebulas_metadata_reads_and_every_disagreement_is_named() {
        let m = Metadata::parse(Path::new("/bag/metadata.yaml"), TEXT).unwrap();
        assert_eq!(m.files, [PathBuf::from("/bag/a_0.db3")]);
        assert_eq!(m.compression, Compression::None);
        let types = BTreeMap::from([("/pandar_packets".to_string(), "x/msg/Y".to_string())]);
        let counts = BTreeMap::from([("/pandar_packets".to_string(), 3)]);
        let files = BTreeMap::from([("a_0.db3".to_string(), 3)]);
        let d = m.disagreements(&types, &counts, &files);
        println!("{d:#?}");
        assert_eq!(d.len(), 3, "{d:?}");
        assert!(d[0].contains("carries pandar_msgs/msg/PandarScan, the storage says x/msg/Y"));
        assert!(d[1].contains("the bag has 4 messages, the storage holds 3"));
        assert!(d[2].contains("a_0.db3 has 4 messages, it holds 3"));
    }

    #[test]
    fn other_storage_and_compression_are_refused_naming_the_file() {
        let mcap = TEXT.replace("sqlite3", "mcap");
        let e = format!(
            "{:#}",
            Metadata::parse(Path::new("m.yaml"), &mcap).unwrap_err()
        );
        assert!(
            e.contains("m.yaml") && e.contains("give its .mcap file"),
            "{e}"
        );
        let lz4 = TEXT.replace(
            "compression_format: \"\"\n  compression_mode: \"\"",
            "compression_format: lz4\n  compression_mode: FILE",
        );
        let e = format!(
            "{:#}",
            Metadata::parse(Path::new("m.yaml"), &lz4).unwrap_err()
        );
        assert!(e.contains("lz4 (file) is not read"), "{e}");
        let e = format!(
            "{:#}",
            Metadata::parse(Path::new("m.yaml"), "a: 1").unwrap_err()
        );
        assert!(e.contains("not a rosbag2 metadata file"), "{e}");
    }
}
