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
use anyhow::{anyhow, bail, Context, Result};
use mcap::records::{op, Record};
use mcap::sans_io::indexed_reader::ReadOrder;
use mcap::sans_io::{
    IndexedReadEvent, IndexedReader, IndexedReaderOptions, LinearReadEvent, LinearReader,
    LinearReaderOptions, SummaryReadEvent, SummaryReader, SummaryReaderOptions,
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

    fn stream(mut self: Box<Self>, topics: &[String]) -> Result<Box<dyn MessageStream>> {
        let label = self.label.clone();
        let total = topics.iter().map(|t| self.count(t)).sum::<Option<usize>>();
        let mut warnings = Vec::new();
        let indexed = self
            .summary
            .as_ref()
            .filter(|s| !s.chunk_indexes.is_empty() && !s.channels.is_empty())
            .and_then(|s| {
                indexed_reader(
                    &label,
                    topics,
                    s,
                    &mut self.input,
                    self.limit,
                    &mut warnings,
                )
                .ok()
                .flatten()
            });
        let sound = match indexed {
            Some(_) => self.len,
            None => self.bound.get(&mut self.input),
        };
        self.input
            .seek(SeekFrom::Start(0))
            .with_context(|| format!("{label}: cannot read"))?;
        let (reader, channels) = match indexed {
            Some(reader) => (Reader::Indexed(reader), self.catalog.channels.clone()),
            None => (
                Reader::Linear(LinearReader::new_with_options(reader_options(self.limit))),
                HashMap::new(),
            ),
        };
        Ok(Box::new(McapStream {
            input: self.input,
            sound,
            reader,
            chunk: Vec::new(),
            total,
            done: false,
            warnings,
            topics: Topics {
                file: label,
                names: topics.to_vec(),
                schemas: self.catalog.schemas.clone(),
                channels,
                index: 0,
                latest: None,
                buf: Vec::new(),
                tp: String::new(),
            },
        }))
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

/// A reader of the messages of `topics` in log-time order, if the chunk index allows it within
/// memory; warns (in `warnings`) when the file was written out of order, naming the first
/// message out of order, and when it is but cannot be reordered.
fn indexed_reader(
    label: &str,
    topics: &[String],
    summary: &mcap::Summary,
    input: &mut BufReader<File>,
    limit: u64,
    warnings: &mut Vec<String>,
) -> Result<Option<IndexedReader>> {
    let ours: Vec<u16> = summary
        .channels
        .iter()
        .filter(|(_, c)| topics.contains(&c.topic))
        .map(|(&id, _)| id)
        .collect();
    // The mcap crate copies an uncompressed chunk into a buffer of its uncompressed size, and
    // panics when an index says the two sizes differ: such an index is not used.
    if let Some(c) = summary
        .chunk_indexes
        .iter()
        .find(|c| c.compression.is_empty() && c.compressed_size != c.uncompressed_size)
    {
        bail!(
            "the index of the chunk at byte {} gives it two sizes",
            c.chunk_start_offset
        );
    }
    let mut chunks = summary.chunk_indexes.clone();
    chunks.sort_by_key(|c| c.chunk_start_offset);
    // Log times of our messages in file order, from the message indexes after each chunk.
    let mut times = Vec::new();
    for chunk in &chunks {
        let mut entries = Vec::new();
        for id in &ours {
            let Some(&at) = chunk.message_index_offsets.get(id) else {
                continue;
            };
            input.seek(SeekFrom::Start(at))?;
            let mut head = [0u8; 9];
            input.read_exact(&mut head)?;
            let len = u64::from_le_bytes(head[1..].try_into()?);
            if head[0] != op::MESSAGE_INDEX || len > limit {
                bail!("no message index at byte {at}");
            }
            let mut body = vec![0u8; len as usize];
            input.read_exact(&mut body)?;
            if let Record::MessageIndex(index) = mcap::parse_record(op::MESSAGE_INDEX, &body)? {
                entries.extend(index.records.into_iter().map(|e| (e.offset, e.log_time)));
            }
        }
        entries.sort_unstable();
        times.extend(entries.into_iter().map(|(_, t)| t));
    }
    let mut order: Vec<u64> = times.clone();
    let warning = pointcloud2::time_order(label, &topics.join(", "), &mut order, |t| *t);
    // Chunks overlapping in time are held together; bound how many.
    let mut spans: Vec<(u64, u64, u64)> = chunks
        .iter()
        .map(|c| {
            (
                c.message_start_time,
                c.message_end_time,
                c.uncompressed_size,
            )
        })
        .collect();
    spans.sort_unstable();
    let mut held = 0u64;
    for (i, &(start, _, _)) in spans.iter().enumerate() {
        let overlapping: u64 = spans[..=i]
            .iter()
            .filter(|(_, end, _)| *end >= start)
            .map(|(_, _, size)| *size)
            .sum();
        held = held.max(overlapping);
    }
    if held > OVERLAP_BUDGET.saturating_mul(limit) {
        if let Some(w) = warning {
            warnings.push(format!(
                "{w} would need {held} bytes of chunks at once, so frames are read in file order"
            ));
        }
        return Ok(None);
    }
    warnings.extend(warning);
    let options = IndexedReaderOptions::new()
        .with_order(ReadOrder::LogTime)
        .include_topics(topics)
        .with_record_length_limit(usize::try_from(limit).unwrap_or(usize::MAX));
    Ok(Some(IndexedReader::new_with_options(summary, options)?))
}

/// How the data section is read.
enum Reader {
    /// Record by record in file order.
    Linear(LinearReader),
    /// The chosen topics' messages in log-time order, chunk by chunk.
    Indexed(IndexedReader),
}

/// The messages of some topics of an open MCAP file.
struct McapStream {
    input: BufReader<File>,
    /// Where the linear reader's file ends (see [`chunks`]).
    sound: u64,
    reader: Reader,
    /// Buffer for a chunk the indexed reader asks for.
    chunk: Vec<u8>,
    total: Option<usize>,
    done: bool,
    warnings: Vec<String>,
    topics: Topics,
}

/// What picks the messages of the chosen topics out of the data section.
struct Topics {
    file: String,
    names: Vec<String>,
    /// Schema names by id (from the summary, or as met in the data section).
    schemas: HashMap<u16, String>,
    /// Channels by id (from the summary, or as met in the data section).
    channels: HashMap<u16, ChannelInfo>,
    /// The next message's place in the stream.
    index: usize,
    /// Latest log time and message index so far, for the order warning of linear reading.
    latest: Option<(u64, usize)>,
    /// The message handed on last, and its type.
    buf: Vec<u8>,
    tp: String,
}

/// A message of a chosen topic: the topic's place, log time, order warning.
type Picked = (usize, u64, Option<String>);

impl Topics {
    /// Keeps a copy of a message of a chosen topic; `None` for another topic's.
    fn pick(&mut self, channel_id: u16, log_time: u64, data: &[u8]) -> Result<Option<Picked>> {
        let (file, index) = (&self.file, self.index);
        let Some(channel) = self.channels.get(&channel_id) else {
            bail!("{file}: message on channel {channel_id} before its channel record");
        };
        let Some(topic) = self.names.iter().position(|t| *t == channel.topic) else {
            return Ok(None);
        };
        let schema = self
            .schemas
            .get(&channel.schema_id)
            .map_or("no schema", String::as_str);
        let tp = type_of(schema, &channel.encoding);
        let warning = match self.latest {
            Some((t, k)) if log_time < t => Some(format!(
                "{file}: message {index} on {} was logged at {}, before message {k} ({}): the \
                 file is out of time order and cannot be reordered (no chunk index); frames \
                 are read in file order",
                channel.topic,
                pointcloud2::stamp_of_nanos(log_time),
                pointcloud2::stamp_of_nanos(t)
            )),
            _ => {
                self.latest = Some((log_time, index));
                None
            }
        };
        self.index += 1;
        self.buf.clear();
        self.buf.extend_from_slice(data);
        self.tp = tp;
        Ok(Some((topic, log_time, warning)))
    }
}

impl MessageStream for McapStream {
    fn len_hint(&self) -> Option<usize> {
        self.total
    }

    fn next_message(&mut self) -> Result<Option<Message<'_>>> {
        if self.done {
            return Ok(None);
        }
        let picked = self.next_picked();
        if !matches!(picked, Ok(Some(_))) {
            self.done = true;
        }
        Ok(picked?.map(|(topic, time_ns, warning)| Message {
            topic,
            time_ns,
            data: &self.topics.buf,
            tp: &self.topics.tp,
            md5: None,
            warning,
        }))
    }

    fn take_warnings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.warnings)
    }
}

impl McapStream {
    /// Reads the data section up to the next message on a chosen topic.
    fn next_picked(&mut self) -> Result<Option<Picked>> {
        let file = self.topics.file.clone();
        loop {
            match &mut self.reader {
                Reader::Linear(reader) => {
                    let event = match reader.next_event() {
                        None => return Ok(None),
                        Some(Err(e)) => {
                            let hint = match e {
                                mcap::McapError::UnexpectedEof => " (the file looks cut short)",
                                _ => "",
                            };
                            bail!("{file}: {e}{hint}");
                        }
                        Some(Ok(event)) => event,
                    };
                    match event {
                        LinearReadEvent::ReadRequest(need) => {
                            let buf = reader.insert(need.min(READ_PIECE));
                            let n = chunks::read_within(&mut self.input, buf, self.sound)
                                .with_context(|| file.clone())?;
                            reader.notify_read(n);
                        }
                        LinearReadEvent::Record { opcode, data } => {
                            let record = mcap::parse_record(opcode, data).map_err(|e| {
                                anyhow!("{file}: bad record (opcode {opcode:#04x}): {e}")
                            })?;
                            let topics = &mut self.topics;
                            match record {
                                Record::Schema { header, .. } => {
                                    topics.schemas.insert(header.id, header.name);
                                }
                                Record::Channel(c) => {
                                    let info = ChannelInfo {
                                        topic: c.topic,
                                        schema_id: c.schema_id,
                                        encoding: c.message_encoding,
                                    };
                                    topics.channels.insert(c.id, info);
                                }
                                Record::Message { header, data } => {
                                    let picked =
                                        topics.pick(header.channel_id, header.log_time, &data)?;
                                    if picked.is_some() {
                                        return Ok(picked);
                                    }
                                }
                                _ => {}
                            }
                        }
                    }
                }
                Reader::Indexed(reader) => match reader.next_event() {
                    None => return Ok(None),
                    Some(Err(e)) => bail!("{file}: {e}"),
                    Some(Ok(IndexedReadEvent::ReadChunkRequest { offset, length })) => {
                        self.chunk.resize(length, 0);
                        self.input
                            .seek(SeekFrom::Start(offset))
                            .and_then(|_| self.input.read_exact(&mut self.chunk))
                            .with_context(|| format!("{file}: cannot read a chunk"))?;
                        reader
                            .insert_chunk_record_data(offset, &self.chunk)
                            .with_context(|| file.clone())?;
                    }
                    Some(Ok(IndexedReadEvent::Message { header, data })) => {
                        let picked = self.topics.pick(header.channel_id, header.log_time, data)?;
                        if picked.is_some() {
                            return Ok(picked);
                        }
                    }
                },
            }
        }
    }
}

mod chunks;
#[cfg(test)]
mod tests;
