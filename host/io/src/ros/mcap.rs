//! ROS 2 MCAP files carrying `sensor_msgs/msg/PointCloud2`.
//!
//! The container is read with the `mcap` crate's sans-io readers fed from a buffered file, so
//! neither the file nor more than a few chunks of it have to fit in memory, and no record
//! larger than the limit the scan capacity sets ([`pointcloud2::record_limit`]) is read. The
//! summary at the end of the file says which topics exist and how many messages each holds;
//! with its chunk index the messages of the chosen topic are read in log-time order (as
//! `ros2 bag play` plays them) whatever order they were written in, and a file written out of
//! order says so in a dataset warning. Without a summary (a file cut short) or chunks, a linear
//! reader streams the data section in file order and warns at the first message out of order.
//! The message body is CDR; [`message`](super::message) parses it into a
//! [`PointCloud2`](super::pointcloud2::PointCloud2) view and [`pointcloud2`] decodes it. With
//! `--imu`, the messages of its `sensor_msgs/msg/Imu` topic (`imu_topic`) are read when it is
//! opened, in one pass over the data section.

use super::message::parse_cdr;
use super::pointcloud2::{self, MessageAt};
use super::{imu_msg, imu_topic};
use crate::dataset::{Dataset, DatasetInfo, Format, FrameSource, Item, OpenOptions};
use crate::imu::{attach::WithImu, ImuSample};
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
use std::path::Path;

/// Schema name of the messages this reader decodes.
pub const POINTCLOUD2_SCHEMA: &str = "sensor_msgs/msg/PointCloud2";

/// Message encoding of ROS 2 messages.
pub const CDR_ENCODING: &str = "cdr";

/// Chunks whose time ranges overlap are held decompressed together while reading in log-time
/// order; more than this many limits' worth is read in file order instead.
const OVERLAP_BUDGET: u64 = 4;

/// Opens an MCAP file and streams the PointCloud2 messages of `opts.topic`, or of the only
/// PointCloud2 topic in the file.
pub fn open(path: &Path, opts: &OpenOptions) -> Result<Dataset> {
    let label = path.display().to_string();
    let limit = pointcloud2::record_limit(opts.scan_points);
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
                "{label}: MCAP file has no summary (cut short or not finished); its topics were \
                 found by scanning"
            ));
            scan(&mut input, limit, sound)
        }
    };

    let topics: Vec<(String, String)> = catalog
        .channels
        .values()
        .map(|c| {
            (
                c.topic.clone(),
                catalog.schema_name(c.schema_id).to_string(),
            )
        })
        .collect();
    let topic = pointcloud2::choose_topic(
        &label,
        &topics,
        |s| s == POINTCLOUD2_SCHEMA,
        pointcloud2::Wanted::cloud(POINTCLOUD2_SCHEMA),
        opts.topic.as_deref(),
    )
    .map_err(|e| anyhow!(e))?;
    let imu_topic = imu_topic::choose(
        &label,
        &topics,
        |s| s == imu_msg::ROS2_SCHEMA,
        imu_msg::ROS2_SCHEMA,
        &opts.imu,
    )
    .map_err(|e| anyhow!(e))?;
    let imu = match imu_topic {
        Some(t) => Some(read_imu(
            (&mut input, &mut bound),
            limit,
            &label,
            &t,
            &catalog,
            &mut warnings,
        )?),
        None => None,
    };
    let total = catalog.counts.as_ref().map(|counts| {
        catalog
            .channels
            .iter()
            .filter(|(_, c)| c.topic == topic)
            .map(|(id, _)| counts.get(id).copied().unwrap_or(0) as usize)
            .sum()
    });
    let indexed = summary
        .as_ref()
        .filter(|s| !s.chunk_indexes.is_empty() && !s.channels.is_empty())
        .and_then(|s| {
            indexed_reader(&label, &topic, s, &mut input, limit, &mut warnings)
                .ok()
                .flatten()
        });
    let sound = match indexed {
        Some(_) => len,
        None => bound.get(&mut input),
    };
    input
        .seek(SeekFrom::Start(0))
        .with_context(|| format!("{label}: cannot read"))?;
    let (reader, channels) = match indexed {
        Some(reader) => (Reader::Indexed(reader), catalog.channels.clone()),
        None => (
            Reader::Linear(LinearReader::new_with_options(reader_options(limit))),
            HashMap::new(),
        ),
    };
    let source = McapSource {
        input,
        sound,
        reader,
        chunk: Vec::new(),
        total,
        done: false,
        topic: Topic {
            file: label,
            name: topic,
            schemas: catalog.schemas.clone(),
            channels,
            index: 0,
            max_points: opts.scan_points,
            latest: None,
        },
    };
    let mut frames: Box<dyn FrameSource> = Box::new(source);
    if let Some(samples) = imu {
        frames = Box::new(WithImu::new(frames, samples));
    }
    Ok(Dataset {
        frames,
        info: DatasetInfo {
            format: Some(Format::Mcap),
            warnings,
            ..DatasetInfo::default()
        },
    })
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

/// The samples of the `sensor_msgs/msg/Imu` messages on `topic`, read in one pass over the data
/// section (from its start: `input` is left anywhere), in stamp order; what went wrong goes to
/// `warnings`.
fn read_imu(
    (input, bound): (&mut BufReader<File>, &mut chunks::Bound),
    limit: u64,
    file: &str,
    topic: &str,
    catalog: &Catalog,
    warnings: &mut Vec<String>,
) -> Result<Vec<ImuSample>> {
    let usable: HashMap<u16, Option<String>> = catalog
        .channels
        .iter()
        .filter(|(_, c)| c.topic == topic)
        .map(|(&id, c)| {
            let schema = catalog.schema_name(c.schema_id);
            let wrong = (schema != imu_msg::ROS2_SCHEMA || c.encoding != CDR_ENCODING)
                .then(|| format!("{schema} ({})", c.encoding));
            (id, wrong)
        })
        .collect();
    let sound = bound.get(input);
    input
        .seek(SeekFrom::Start(0))
        .with_context(|| format!("{file}: cannot read"))?;
    let mut reader = LinearReader::new_with_options(reader_options(limit));
    let mut collected = imu_topic::Collector::new(file, topic);
    let mut index = 0;
    while let Some(event) = reader.next_event() {
        let record = match event {
            Ok(LinearReadEvent::ReadRequest(need)) => {
                let n = chunks::read_within(input, reader.insert(need.min(READ_PIECE)), sound)
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
                match usable.get(&header.channel_id) {
                    None => continue,
                    Some(Some(wrong)) => collected.refuse(index, wrong),
                    Some(None) => collected.push(index, imu_msg::parse_cdr(&data)),
                }
                index += 1;
            }
            Ok(_) => {}
            Err(e) => {
                collected.stop(index, &e);
                break;
            }
        }
    }
    Ok(collected.finish(warnings))
}

/// A reader of the messages of `topic` in log-time order, if the chunk index allows it within
/// memory; warns (in `warnings`) when the file was written out of order, naming the first
/// message out of order, and when it is but cannot be reordered.
fn indexed_reader(
    label: &str,
    topic: &str,
    summary: &mcap::Summary,
    input: &mut BufReader<File>,
    limit: u64,
    warnings: &mut Vec<String>,
) -> Result<Option<IndexedReader>> {
    let ours: Vec<u16> = summary
        .channels
        .iter()
        .filter(|(_, c)| c.topic == topic)
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
    let warning = pointcloud2::time_order(label, topic, &mut order, |t| *t);
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
        .include_topics([topic])
        .with_record_length_limit(usize::try_from(limit).unwrap_or(usize::MAX));
    Ok(Some(IndexedReader::new_with_options(summary, options)?))
}

/// How the data section is read.
enum Reader {
    /// Record by record in file order.
    Linear(LinearReader),
    /// The chosen topic's messages in log-time order, chunk by chunk.
    Indexed(IndexedReader),
}

/// The frames of one topic of an open MCAP file.
struct McapSource {
    input: BufReader<File>,
    /// Where the linear reader's file ends (see [`chunks`]).
    sound: u64,
    reader: Reader,
    /// Buffer for a chunk the indexed reader asks for.
    chunk: Vec<u8>,
    total: Option<usize>,
    done: bool,
    topic: Topic,
}

/// What turns messages of the data section into items of the chosen topic.
struct Topic {
    file: String,
    name: String,
    /// Schema names by id (from the summary, or as met in the data section).
    schemas: HashMap<u16, String>,
    /// Channels by id (from the summary, or as met in the data section).
    channels: HashMap<u16, ChannelInfo>,
    index: usize,
    max_points: usize,
    /// Latest log time and message index so far, for the order warning of linear reading.
    latest: Option<(u64, usize)>,
}

impl Topic {
    /// The item of a message, `None` for a message of another topic.
    fn item(&mut self, channel_id: u16, log_time: u64, data: &[u8]) -> Result<Option<Item>> {
        let (file, index) = (&self.file, self.index);
        let Some(channel) = self.channels.get(&channel_id) else {
            bail!("{file}: message on channel {channel_id} before its channel record");
        };
        if channel.topic != self.name {
            return Ok(None);
        }
        let topic = &self.name;
        let schema = self
            .schemas
            .get(&channel.schema_id)
            .map_or("no schema", String::as_str);
        if schema != POINTCLOUD2_SCHEMA || channel.encoding != CDR_ENCODING {
            bail!(
                "{file}: message {index} on {topic} is {schema} ({}), not {POINTCLOUD2_SCHEMA} \
                 ({CDR_ENCODING})",
                channel.encoding
            );
        }
        let at = MessageAt {
            index,
            file,
            topic,
            received: log_time,
        };
        let mut item = pointcloud2::message_item(at, parse_cdr(data), self.max_points);
        match self.latest {
            Some((t, k)) if log_time < t => {
                if let Item::Frame(f) = &mut item {
                    f.warnings.push(format!(
                        "{file}: message {index} on {topic} was logged at {}, before message {k} \
                         ({}): the file is out of time order and cannot be reordered (no chunk \
                         index); frames are read in file order",
                        pointcloud2::stamp_of_nanos(log_time),
                        pointcloud2::stamp_of_nanos(t)
                    ));
                }
            }
            _ => self.latest = Some((log_time, index)),
        }
        self.index += 1;
        Ok(Some(item))
    }
}

impl FrameSource for McapSource {
    fn len_hint(&self) -> Option<usize> {
        self.total
    }

    fn next_item(&mut self) -> Result<Option<Item>> {
        if self.done {
            return Ok(None);
        }
        let result = self.next_frame();
        if !matches!(result, Ok(Some(_))) {
            self.done = true;
        }
        result
    }
}

impl McapSource {
    /// Reads the data section up to the next message on the chosen topic.
    fn next_frame(&mut self) -> Result<Option<Item>> {
        let file = self.topic.file.clone();
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
                            let topic = &mut self.topic;
                            match record {
                                Record::Schema { header, .. } => {
                                    topic.schemas.insert(header.id, header.name);
                                }
                                Record::Channel(c) => {
                                    let info = ChannelInfo {
                                        topic: c.topic,
                                        schema_id: c.schema_id,
                                        encoding: c.message_encoding,
                                    };
                                    topic.channels.insert(c.id, info);
                                }
                                Record::Message { header, data } => {
                                    let item =
                                        topic.item(header.channel_id, header.log_time, &data)?;
                                    if item.is_some() {
                                        return Ok(item);
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
                        let item = self.topic.item(header.channel_id, header.log_time, data)?;
                        if item.is_some() {
                            return Ok(item);
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
