//! ROS 2 MCAP files as a [`Recording`]: `sensor_msgs/msg/PointCloud2`, sensor packets, Livox
//! points and IMU samples, read by [`frames`].
//!
//! The container is read with the `mcap` crate's sans-io readers fed from a buffered file, so
//! neither the file nor more than a few chunks of it have to fit in memory, and no record
//! larger than the limit the scan capacity sets ([`pointcloud2::record_limit`]) is read. The
//! summary at the end of the file says which topics exist and how many messages each holds;
//! with its chunk index the messages of the chosen topics are read in log-time order (as
//! `ros2 bag play` plays them) whatever order they were written in, and a file written out of
//! order says so in a dataset warning. Without a summary (a file cut short) or chunks, a linear
//! reader streams the data section in file order and warns at the first message out of order.
//! The message bodies are CDR. The passes made when the file is opened (its IMU topic, the
//! sensor's metadata) read the data section once each, in file order.

use super::frames;
use super::pointcloud2;
use super::recording::{Message, MessageStream, Recording};
use crate::dataset::{Dataset, Format, OpenOptions};
use anyhow::{bail, Context, Result};
use mcap::records::{op, Record};
use mcap::sans_io::{
    LinearReadEvent, LinearReader, LinearReaderOptions, SummaryReadEvent, SummaryReader,
    SummaryReaderOptions,
};
use std::collections::HashMap;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::ops::ControlFlow;
use std::path::Path;

/// Schema name of ROS 2 point clouds.
pub const POINTCLOUD2_SCHEMA: &str = "sensor_msgs/msg/PointCloud2";

/// Message encoding of ROS 2 messages.
pub const CDR_ENCODING: &str = "cdr";

/// Chunks whose time ranges overlap are held decompressed together while reading in log-time
/// order; more than this many limits' worth is read in file order instead.
const OVERLAP_BUDGET: u64 = 4;

/// Opens an MCAP file and streams the frames of `opts.topic`, or of the only PointCloud2
/// topic (else the only topic of sensor packets or Livox points).
pub fn open(path: &Path, opts: &OpenOptions) -> Result<Dataset> {
    let file = McapRecording::open(path, pointcloud2::record_limit(opts.scan_points))?;
    frames::open(Box::new(file), opts)
}

/// An MCAP file opened for reading.
pub struct McapRecording {
    input: BufReader<File>,
    len: u64,
    /// Where a linear reader must stop (see [`chunks`]).
    bound: chunks::Bound,
    limit: u64,
    label: String,
    summary: Option<mcap::Summary>,
    catalog: Catalog,
    warnings: Vec<String>,
}

impl McapRecording {
    /// Opens the MCAP file at `path`; records larger than `limit` bytes are refused.
    pub fn open(path: &Path, limit: u64) -> Result<Self> {
        let label = path.display().to_string();
        let mut file = File::open(path).with_context(|| format!("{label}: cannot open"))?;
        let len = file
            .metadata()
            .with_context(|| format!("{label}: cannot stat"))?
            .len();
        let mut magic = [0u8; 8];
        if file.read_exact(&mut magic).is_err() || magic != mcap::MAGIC {
            bail!("{label}: not an MCAP file (no MCAP magic at the start)");
        }
        let mut input = BufReader::with_capacity(1 << 16, file);
        // A linear reader is given the file up to its first unsound chunk only.
        let mut bound = chunks::Bound::new(len);
        let mut warnings = Vec::new();
        let summary = chunks::summary_sound(&mut input, len)
            .then(|| read_summary(&mut input, len, limit).ok().flatten())
            .flatten();
        let catalog = match &summary {
            Some(summary) if !summary.channels.is_empty() => Catalog::of(summary),
            // No summary (cut short, or written without one): learn the channels by reading once.
            _ => {
                let sound = bound.get(&mut input);
                input
                    .seek(SeekFrom::Start(0))
                    .with_context(|| format!("{label}: cannot read"))?;
                warnings.push(format!(
                    "{label}: MCAP file has no summary (cut short or not finished); its topics \
                     were found by scanning"
                ));
                scan(&mut input, limit, sound)
            }
        };
        Ok(Self {
            input,
            len,
            bound,
            limit,
            label,
            summary,
            catalog,
            warnings,
        })
    }
}

impl Recording for McapRecording {
    fn label(&self) -> &str {
        &self.label
    }

    fn format(&self) -> Format {
        Format::Mcap
    }

    fn ros1(&self) -> bool {
        false
    }

    fn topics(&self) -> Vec<(String, String)> {
        let mut out: Vec<(String, String)> = (self.catalog.channels.values())
            .map(|c| {
                (
                    c.topic.clone(),
                    self.catalog.schema_name(c.schema_id).to_string(),
                )
            })
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    fn count(&self, topic: &str) -> Option<usize> {
        let counts = self.catalog.counts.as_ref()?;
        let ids = self
            .catalog
            .channels
            .iter()
            .filter(|(_, c)| c.topic == topic);
        Some(
            ids.map(|(id, _)| counts.get(id).copied().unwrap_or(0) as usize)
                .sum(),
        )
    }

    fn take_warnings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.warnings)
    }

    fn scan(
        &mut self,
        topics: &[String],
        f: &mut dyn FnMut(Message<'_>) -> ControlFlow<()>,
    ) -> Result<()> {
        let file = self.label.clone();
        let ours: HashMap<u16, (usize, String)> = (self.catalog.channels.iter())
            .filter_map(|(&id, c)| {
                let topic = topics.iter().position(|t| *t == c.topic)?;
                Some((id, (topic, self.catalog.type_of(c))))
            })
            .collect();
        let sound = self.bound.get(&mut self.input);
        self.input
            .seek(SeekFrom::Start(0))
            .with_context(|| format!("{file}: cannot read"))?;
        let mut reader = LinearReader::new_with_options(reader_options(self.limit));
        while let Some(event) = reader.next_event() {
            let record = match event {
                Ok(LinearReadEvent::ReadRequest(need)) => {
                    let buf = reader.insert(need.min(READ_PIECE));
                    let n = chunks::read_within(&mut self.input, buf, sound)
                        .with_context(|| format!("{file}: cannot read"))?;
                    reader.notify_read(n);
                    continue;
                }
                Ok(LinearReadEvent::Record { opcode, data }) if opcode == op::MESSAGE => {
                    mcap::parse_record(opcode, data)
                }
                Ok(LinearReadEvent::Record { .. }) => continue,
                Err(e) => Err(e),
            };
            match record {
                Ok(Record::Message { header, data }) => {
                    let Some((topic, tp)) = ours.get(&header.channel_id) else {
                        continue;
                    };
                    let message = Message {
                        topic: *topic,
                        time_ns: header.log_time,
                        data: &data,
                        tp,
                        md5: None,
                        warning: None,
                    };
                    if f(message).is_break() {
                        return Ok(());
                    }
                }
                Ok(_) => {}
                Err(e) => bail!("{file}: {e}"),
            }
        }
        Ok(())
    }

    fn stream(self: Box<Self>, topics: &[String]) -> Result<Box<dyn MessageStream>> {
        stream::open(*self, topics)
    }
}

/// Most bytes handed to the mcap reader per read. The reader asks for what a record header
/// declares and grows its buffer by that much before anything is read, so a damaged length
/// field would cost gigabytes; in pieces, its buffer grows only by bytes the file really has.
const READ_PIECE: usize = 1 << 16;

fn reader_options(limit: u64) -> LinearReaderOptions {
    LinearReaderOptions::default()
        .with_validate_chunk_crcs(true)
        .with_record_length_limit(usize::try_from(limit).unwrap_or(usize::MAX))
}

/// A channel: its topic, schema id and message encoding.
#[derive(Clone, Debug)]
struct ChannelInfo {
    topic: String,
    schema_id: u16,
    encoding: String,
}

/// Channels and schemas known before streaming, and how many messages each channel has.
#[derive(Debug, Default)]
struct Catalog {
    channels: HashMap<u16, ChannelInfo>,
    schemas: HashMap<u16, String>,
    counts: Option<HashMap<u16, u64>>,
}

impl Catalog {
    fn of(summary: &mcap::Summary) -> Self {
        let channels = summary
            .channels
            .iter()
            .map(|(&id, c)| {
                let info = ChannelInfo {
                    topic: c.topic.clone(),
                    schema_id: c.schema.as_ref().map_or(0, |s| s.id),
                    encoding: c.message_encoding.clone(),
                };
                (id, info)
            })
            .collect();
        let schemas = summary
            .schemas
            .iter()
            .map(|(&id, s)| (id, s.name.clone()))
            .collect();
        let counts = summary
            .stats
            .as_ref()
            .map(|s| s.channel_message_counts.clone().into_iter().collect());
        Catalog {
            channels,
            schemas,
            counts,
        }
    }

    fn schema_name(&self, id: u16) -> &str {
        self.schemas.get(&id).map_or("", String::as_str)
    }

    /// The type of a channel's messages: its schema name, and its encoding when that is not
    /// CDR (which no reader takes).
    fn type_of(&self, c: &ChannelInfo) -> String {
        type_of(self.schema_name(c.schema_id), &c.encoding)
    }
}

/// A message type as the readers see it: the schema name, with its encoding when that is not
/// CDR.
fn type_of(schema: &str, encoding: &str) -> String {
    if encoding == CDR_ENCODING {
        schema.to_string()
    } else {
        format!("{schema} ({encoding})")
    }
}

/// Reads the summary section; `Ok(None)` when the file has none.
fn read_summary(
    input: &mut BufReader<File>,
    len: u64,
    limit: u64,
) -> mcap::McapResult<Option<mcap::Summary>> {
    let mut reader = SummaryReader::new_with_options(
        SummaryReaderOptions::default()
            .with_file_size(len)
            .with_record_length_limit(usize::try_from(limit).unwrap_or(usize::MAX)),
    );
    while let Some(event) = reader.next_event() {
        match event? {
            SummaryReadEvent::ReadRequest(need) => {
                let n = input.read(reader.insert(need.min(READ_PIECE)))?;
                reader.notify_read(n);
            }
            SummaryReadEvent::SeekRequest(to) => {
                let pos = input.seek(to)?;
                reader.notify_seeked(pos);
            }
        }
    }
    Ok(reader.finish())
}

/// Reads the whole data section once, counting messages per channel, up to the first error.
fn scan(input: &mut BufReader<File>, limit: u64, sound: u64) -> Catalog {
    let mut reader = LinearReader::new_with_options(reader_options(limit));
    let mut catalog = Catalog::default();
    let mut counts: HashMap<u16, u64> = HashMap::new();
    while let Some(Ok(event)) = reader.next_event() {
        match event {
            LinearReadEvent::ReadRequest(need) => {
                let n = chunks::read_within(input, reader.insert(need.min(READ_PIECE)), sound)
                    .unwrap_or(0);
                reader.notify_read(n);
            }
            LinearReadEvent::Record { opcode, data } => match mcap::parse_record(opcode, data) {
                Ok(Record::Schema { header, .. }) => {
                    catalog.schemas.insert(header.id, header.name);
                }
                Ok(Record::Channel(c)) => {
                    let info = ChannelInfo {
                        topic: c.topic,
                        schema_id: c.schema_id,
                        encoding: c.message_encoding,
                    };
                    catalog.channels.insert(c.id, info);
                }
                Ok(Record::Message { header, .. }) => {
                    *counts.entry(header.channel_id).or_default() += 1;
                }
                Ok(_) => {}
                Err(_) => break,
            },
        }
    }
    catalog.counts = Some(counts);
    catalog
}

mod chunks;
mod stream;
#[cfg(test)]
mod tests;
