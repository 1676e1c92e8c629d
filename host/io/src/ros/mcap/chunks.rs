//! A guard in front of the `mcap` crate's linear reader: it walks an uncompressed chunk's
//! records trusting their lengths, and a record that runs past its chunk makes it subtract past
//! zero (a panic where overflow is checked, records read from outside the chunk where it is not).
//! [`sound_until`] finds the first chunk whose records do not fit in it, and [`read_within`]
//! ends the file there for the reader, which then stops as at a file cut short. The crate's
//! summary reader runs a linear reader from where the footer says the summary starts, which a
//! damaged footer can point at such a chunk: [`summary_sound`] walks from there first.

use mcap::records::op::{CHUNK, FOOTER};
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};

/// A record's opcode and length.
const RECORD_HEADER: u64 = 1 + 8;
/// The footer record (opcode, length, summary start and summary offset start (u64 each), CRC
/// (u32)) and the end magic.
const FOOTER_AND_MAGIC: u64 = 1 + 8 + 8 + 8 + 4 + 8;

/// A chunk record's body before its compression string: message start and end times,
/// uncompressed size (u64 each), uncompressed CRC (u32), the compression string's length (u32).
const CHUNK_FIXED: u64 = 8 + 8 + 8 + 4 + 4;

/// The offset at which the file stops being safe for the linear reader: the start of the first
/// uncompressed chunk whose records run past its end (the part of it the file holds), else
/// `len`. A file cut short elsewhere, or a record that is not a chunk, is left to the reader to
/// judge. Leaves `input` anywhere.
pub fn sound_until(input: &mut BufReader<File>, len: u64) -> u64 {
    walk(input, mcap::MAGIC.len() as u64, len).unwrap_or(len)
}

/// Whether the summary section the footer points at is safe for the summary reader's linear
/// reader: no uncompressed chunk from there on has records that run past its end. A file
/// without a footer or summary is left to the reader to judge. Leaves `input` anywhere.
pub fn summary_sound(input: &mut BufReader<File>, len: u64) -> bool {
    let Some(footer) = len.checked_sub(FOOTER_AND_MAGIC) else {
        return true;
    };
    let start = input
        .seek(SeekFrom::Start(footer + RECORD_HEADER))
        .ok()
        .and_then(|_| u64_at(input));
    match start {
        Some(start) if start > 0 => walk(input, start, len).is_none(),
        _ => true,
    }
}

/// [`sound_until`], walked at most once, and only when a linear reader is about to need it.
pub struct Bound {
    len: u64,
    until: Option<u64>,
}

impl Bound {
    /// For a file of `len` bytes; nothing is read yet.
    pub fn new(len: u64) -> Self {
        Self { len, until: None }
    }

    /// The offset the linear reader may read up to; the first call walks the file (leaving
    /// `input` anywhere).
    pub fn get(&mut self, input: &mut BufReader<File>) -> u64 {
        let len = self.len;
        *self.until.get_or_insert_with(|| sound_until(input, len))
    }
}

/// `input.read` into `buf`, as if the file ended at `end`.
pub fn read_within(
    input: &mut BufReader<File>,
    buf: &mut [u8],
    end: u64,
) -> std::io::Result<usize> {
    let room = end.saturating_sub(input.stream_position()?);
    let n = buf.len().min(usize::try_from(room).unwrap_or(usize::MAX));
    input.read(&mut buf[..n])
}

/// The walk from `at`; `None` where the file ends or cannot be read before anything unsound is
/// met.
fn walk(input: &mut BufReader<File>, mut at: u64, len: u64) -> Option<u64> {
    loop {
        input.seek(SeekFrom::Start(at)).ok()?;
        let (opcode, body) = header(input)?;
        if opcode == FOOTER {
            return None;
        }
        // A chunk is walked even where it claims more than the file holds: the reader reads its
        // records up to the file's end, so one that overruns the chunk before then counts.
        if opcode == CHUNK && !chunk_fits(input, body)? {
            return Some(at);
        }
        let next = at.checked_add(RECORD_HEADER)?.checked_add(body)?;
        if next > len {
            return None;
        }
        at = next;
    }
}

/// Whether a chunk (`input` at its body, `body` bytes long) keeps its records inside it; only
/// uncompressed chunks are walked, compressed ones count as fitting.
fn chunk_fits(input: &mut BufReader<File>, body: u64) -> Option<bool> {
    let mut fixed = [0u8; CHUNK_FIXED as usize];
    input.read_exact(&mut fixed).ok()?;
    let compression = u64::from(u32::from_le_bytes(fixed[28..32].try_into().ok()?));
    input.seek_relative(i64::try_from(compression).ok()?).ok()?;
    let records = u64_at(input)?;
    let used = CHUNK_FIXED.checked_add(compression)?.checked_add(8)?;
    if used.checked_add(records)? > body {
        return Some(false);
    }
    if compression > 0 {
        return Some(true);
    }
    let mut left = records;
    while left > 0 {
        if left < RECORD_HEADER {
            return Some(false);
        }
        let (_, inner) = header(input)?;
        match inner.checked_add(RECORD_HEADER) {
            Some(whole) if whole <= left => left -= whole,
            _ => return Some(false),
        }
        input.seek_relative(i64::try_from(inner).ok()?).ok()?;
    }
    Some(true)
}

/// A record's opcode and body length at `input`.
fn header(input: &mut BufReader<File>) -> Option<(u8, u64)> {
    let mut op = [0u8; 1];
    input.read_exact(&mut op).ok()?;
    Some((op[0], u64_at(input)?))
}

fn u64_at(input: &mut BufReader<File>) -> Option<u64> {
    let mut b = [0u8; 8];
    input.read_exact(&mut b).ok()?;
    Some(u64::from_le_bytes(b))
}
