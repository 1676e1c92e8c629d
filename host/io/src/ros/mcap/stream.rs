//! The messages of some topics of an open MCAP file, as a stream: with the summary's chunk
//! index, in log-time order (chunks overlapping in time held together, within a budget), else
//! record by record in file order, with a warning at the first message out of order.

use super::{chunks, reader_options, type_of, ChannelInfo, McapRecording};
use super::{OVERLAP_BUDGET, READ_PIECE};
use crate::ros::pointcloud2;
use crate::ros::recording::{Message, MessageStream, Recording};
use anyhow::{anyhow, bail, Context, Result};
use mcap::records::{op, Record};
use mcap::sans_io::indexed_reader::ReadOrder;
use mcap::sans_io::{
    IndexedReadEvent, IndexedReader, IndexedReaderOptions, LinearReadEvent, LinearReader,
};
use std::collections::HashMap;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};

/// The messages of `topics` of `file`: in log-time order where its chunk index allows it
/// within memory, else in file order.
pub(super) fn open(mut file: McapRecording, topics: &[String]) -> Result<Box<dyn MessageStream>> {
    let label = file.label.clone();
    let total = topics.iter().map(|t| file.count(t)).sum::<Option<usize>>();
    let mut warnings = Vec::new();
    let indexed = file
        .summary
        .as_ref()
        .filter(|s| !s.chunk_indexes.is_empty() && !s.channels.is_empty())
        .and_then(|s| {
            indexed_reader(
                &label,
                topics,
                s,
                &mut file.input,
                file.limit,
                &mut warnings,
            )
            .ok()
            .flatten()
        });
    let sound = match indexed {
        Some(_) => file.len,
        None => file.bound.get(&mut file.input),
    };
    file.input
        .seek(SeekFrom::Start(0))
        .with_context(|| format!("{label}: cannot read"))?;
    let (reader, channels) = match indexed {
        Some(reader) => (Reader::Indexed(reader), file.catalog.channels.clone()),
        None => (
            Reader::Linear(LinearReader::new_with_options(reader_options(file.limit))),
            HashMap::new(),
        ),
    };
    Ok(Box::new(McapStream {
        input: file.input,
        sound,
        reader,
        chunk: Vec::new(),
        total,
        done: false,
        warnings,
        topics: Topics {
            file: label,
            names: topics.to_vec(),
            schemas: file.catalog.schemas.clone(),
            channels,
            index: 0,
            latest: None,
            buf: Vec::new(),
            tp: String::new(),
        },
    }))
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
