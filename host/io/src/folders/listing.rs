//! Which files of a frame folder are frames, and which frame each one is: the first step of
//! reading a folder dataset (generic or KITTI), before any frame is read.
//!
//! A frame is identified by the number in its name (`000005.bin` is frame 5, and row 5 of
//! `poses.txt` and `times.txt`), or, for names that are times (`100.05.bin`,
//! `1694000000.123456789.pcd`, an integer of nanoseconds...), by its place in time order, with
//! the time from the name; never by its place in a directory listing. A number missing from a
//! numbered sequence (or a folder, a dangling symlink in its place) becomes a [`Slot`] with a
//! problem, which the source turns into a skipped frame. Files that are not frames (hidden
//! files, AppleDouble `._*` companions, editor leftovers, system files) are ignored with one
//! warning; names that cannot be told apart (two files for frame 5, numbered and unnumbered
//! names mixed, frames of several formats under `--format auto`) are refused with the names.

use crate::dataset::Format;
use anyhow::{bail, Context, Result};
use std::cmp::Ordering;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Frame formats of the folder layouts and their file extension.
pub const FRAME_FORMATS: [(Format, &str); 3] = [
    (Format::Bin, "bin"),
    (Format::Ply, "ply"),
    (Format::Pcd, "pcd"),
];

/// Extensions of editor, download and backup leftovers.
const LEFTOVER_EXTENSIONS: [&str; 12] = [
    "swp",
    "swo",
    "swx",
    "bak",
    "tmp",
    "temp",
    "orig",
    "rej",
    "part",
    "partial",
    "crdownload",
    "download",
];

/// Names operating systems leave in folders (compared case-insensitively).
const SYSTEM_NAMES: [&str; 7] = [
    "thumbs.db",
    "ehthumbs.db",
    "desktop.ini",
    "icon\r",
    "$recycle.bin",
    "system volume information",
    "__macosx",
];

/// A frame number missing from more places than this (and than there are files) is not a gap:
/// the names are not a frame sequence.
const MAX_GAPS: usize = 100;

/// An interval between time-named frames this many times the median suggests lost frames.
const GAP_FACTOR: f64 = 1.9;

/// Whether a directory entry named `name` is a file no frame folder means as a frame: hidden
/// files (`.*`, including macOS `._*` and `.DS_Store`), editor and download leftovers
/// (`*~`, `#*#`, `~$*`, `*.swp`, `*.bak`, `*.tmp`, `*.part`...) and system files
/// (`Thumbs.db`, `desktop.ini`, `__MACOSX`...).
pub fn is_foreign(name: &str) -> bool {
    let lower = name.to_ascii_lowercase();
    let ext = lower.rsplit_once('.').map(|(_, e)| e);
    name.starts_with('.')
        || name.ends_with('~')
        || (name.len() > 1 && name.starts_with('#') && name.ends_with('#'))
        || name.starts_with("~$")
        || ext.is_some_and(|e| LEFTOVER_EXTENSIONS.contains(&e))
        || SYSTEM_NAMES.contains(&lower.as_str())
}

/// How the frames of a folder are named.
#[derive(Clone, Debug, PartialEq)]
pub enum Naming {
    /// By frame number; the numbers go in steps of `step` (1 unless frames were thinned).
    Numbered {
        /// Common difference of the numbers.
        step: u64,
    },
    /// By time: frames are numbered 0, 1, ... in time order.
    Timed,
    /// No number in the names: frames are numbered in name order.
    Unnumbered,
}

/// One frame of a folder, present or not.
#[derive(Clone, Debug, PartialEq)]
pub struct Slot {
    /// The frame's identity: its number, or its place in time (or name) order.
    pub index: usize,
    /// The file (for a missing frame: the name it would have).
    pub path: PathBuf,
    /// Time from the name, seconds, for time-named frames.
    pub time: Option<f64>,
    /// Why the frame cannot be read, known before reading (missing, a folder...).
    pub problem: Option<String>,
}

/// The frames of a folder, in frame order, and what was found about them.
#[derive(Clone, Debug)]
pub struct Listing {
    /// The folder.
    pub dir: PathBuf,
    /// The format whose files are the frames.
    pub format: Format,
    /// Every frame from the first to the last, gaps included.
    pub slots: Vec<Slot>,
    /// How the frames are named.
    pub naming: Naming,
    /// Findings to report (ignored files, thinned numbering, time gaps).
    pub warnings: Vec<String>,
}

/// A directory entry with a frame extension.
struct Candidate {
    name: String,
    path: PathBuf,
    format: Format,
    problem: Option<String>,
}

/// Counts of frame files per format in `dir`, ignoring foreign files (see [`is_foreign`]).
pub fn count_formats(dir: &Path) -> Result<Vec<(Format, usize)>> {
    let (candidates, _) = candidates(dir)?;
    Ok(FRAME_FORMATS
        .iter()
        .map(|(f, _)| (*f, candidates.iter().filter(|c| c.format == *f).count()))
        .filter(|(_, n)| *n > 0)
        .collect())
}

/// The extension of frames of `format`, if it is a per-file format.
pub fn extension(format: Format) -> Option<&'static str> {
    FRAME_FORMATS
        .iter()
        .find(|(f, _)| *f == format)
        .map(|(_, ext)| *ext)
}

fn format_of(name: &str) -> Option<Format> {
    let (_, ext) = name.rsplit_once('.')?;
    FRAME_FORMATS
        .iter()
        .find(|(_, e)| e.eq_ignore_ascii_case(ext))
        .map(|(f, _)| *f)
}

/// Frame-extension entries of `dir` (with what is wrong with those that are not files) and the
/// names of the foreign ones.
fn candidates(dir: &Path) -> Result<(Vec<Candidate>, Vec<String>)> {
    let mut out = Vec::new();
    let mut foreign = Vec::new();
    for entry in std::fs::read_dir(dir).with_context(|| format!("{}", dir.display()))? {
        let entry = entry.with_context(|| format!("{}: cannot list", dir.display()))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if is_foreign(&name) {
            foreign.push(name);
            continue;
        }
        let Some(format) = format_of(&name) else {
            continue;
        };
        let path = entry.path();
        let problem = match std::fs::metadata(&path) {
            Ok(m) if m.is_file() => None,
            Ok(m) if m.is_dir() => Some("a folder, not a frame file".to_string()),
            Ok(_) => Some("not a regular file".to_string()),
            Err(_) if path.is_symlink() => Some("a symlink to nothing".to_string()),
            Err(e) => Some(format!("cannot be read ({e})")),
        };
        out.push(Candidate {
            name,
            path,
            format,
            problem,
        });
    }
    foreign.sort();
    Ok((out, foreign))
}

/// The number at the end of a file stem, split as (prefix, number, suffix): the last run of
/// digits, with one decimal point inside it (`100.05`, `1694000000.123456789`).
fn split_number(stem: &str) -> Option<(&str, &str, &str)> {
    let b = stem.as_bytes();
    let end = b.iter().rposition(u8::is_ascii_digit)? + 1;
    let mut start = end;
    while start > 0 && b[start - 1].is_ascii_digit() {
        start -= 1;
    }
    if start >= 2 && b[start - 1] == b'.' && b[start - 2].is_ascii_digit() {
        start -= 1;
        while start > 0 && b[start - 1].is_ascii_digit() {
            start -= 1;
        }
    }
    Some((&stem[..start], &stem[start..end], &stem[end..]))
}

/// An exact, ordered time from a name: whole seconds and the decimal digits of the fraction
/// (trailing zeros removed, so that equal times compare equal and digit strings compare in
/// numeric order).
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct TimeKey {
    seconds: u128,
    fraction: String,
}

impl TimeKey {
    fn new(seconds: u128, fraction: &str) -> Self {
        Self {
            seconds,
            fraction: fraction.trim_end_matches('0').to_string(),
        }
    }

    fn seconds_f64(&self) -> f64 {
        format!("{}.{}0", self.seconds, self.fraction)
            .parse()
            .unwrap_or(f64::NAN)
    }
}

/// Integer names at or above this are times (seconds since 2001 or finer units), not frame
/// numbers.
const FIRST_TIME_NAME: u128 = 1_000_000_000;

/// Decimal digits of the unit of an integer time name, from the largest one of the folder:
/// nanoseconds, microseconds, milliseconds or seconds since the epoch.
fn integer_time_digits(largest: u128) -> u32 {
    match largest {
        v if v >= 100_000_000_000_000_000 => 9,
        v if v >= 100_000_000_000_000 => 6,
        v if v >= 100_000_000_000 => 3,
        _ => 0,
    }
}

/// A parsed frame name.
struct Named {
    candidate: Candidate,
    /// Digits before the decimal point, and after it (empty for integers).
    whole: u128,
    fraction: String,
    digits: usize,
    decimal: bool,
}

/// Lists the frames of `dir`. `format` is the frame format asked for (`None`: the only one
/// present; several present is refused). With an explicit format, files of the other frame
/// formats are ignored with a warning.
pub fn list(dir: &Path, format: Option<Format>) -> Result<Listing> {
    let (all, foreign) = candidates(dir)?;
    let shown = dir.display();
    let mut warnings = Vec::new();
    if let Some(first) = foreign.first() {
        warnings.push(format!(
            "{shown}: ignored {} file(s) that are not frames (hidden, system or editor files, \
             e.g. {first})",
            foreign.len()
        ));
    }
    let counts: Vec<(Format, &str, usize)> = FRAME_FORMATS
        .iter()
        .map(|(f, e)| (*f, *e, all.iter().filter(|c| c.format == *f).count()))
        .filter(|(_, _, n)| *n > 0)
        .collect();
    let format = match (format, counts.as_slice()) {
        (Some(f), _) => f,
        (None, [(f, _, _)]) => *f,
        (None, []) => bail!("{shown}: no frames (*.bin, *.ply or *.pcd) found"),
        (None, several) => {
            let listed: Vec<String> = several
                .iter()
                .map(|(_, e, n)| format!("{n} *.{e}"))
                .collect();
            let choices: Vec<String> = several
                .iter()
                .map(|(_, e, _)| format!("--format {e}"))
                .collect();
            bail!(
                "{shown}: frames of several formats ({}); choose one with {}",
                listed.join(", "),
                choices.join(" or ")
            )
        }
    };
    let Some(ext) = extension(format) else {
        bail!("{shown}: {format:?} is not a folder format");
    };
    let (chosen, others): (Vec<Candidate>, Vec<Candidate>) =
        all.into_iter().partition(|c| c.format == format);
    if let Some(first) = others.first() {
        warnings.push(format!(
            "{shown}: ignored {} frame file(s) of another format (e.g. {}): --format {ext} \
             reads only *.{ext} frames",
            others.len(),
            first.name
        ));
    }
    if chosen.is_empty() {
        bail!("{shown}: no *.{ext} frames found");
    }
    let hints: HashMap<String, String> = others
        .iter()
        .filter_map(|c| Some((stem(&c.name)?.to_string(), c.name.clone())))
        .collect();

    // Every name must follow one pattern: the same text around one number.
    let mut patterns: HashMap<(String, String), usize> = HashMap::new();
    let mut unnumbered = Vec::new();
    let mut named = Vec::new();
    for c in chosen {
        let parsed = stem(&c.name).and_then(split_number).and_then(|(p, n, s)| {
            let (whole, fraction) = n.split_once('.').unwrap_or((n, ""));
            Some((
                p.to_string(),
                s.to_string(),
                whole.parse::<u128>().ok()?,
                fraction.to_string(),
                n.len(),
                n.contains('.'),
            ))
        });
        match parsed {
            Some((prefix, suffix, whole, fraction, digits, decimal)) => {
                *patterns.entry((prefix, suffix)).or_default() += 1;
                named.push(Named {
                    candidate: c,
                    whole,
                    fraction,
                    digits,
                    decimal,
                });
            }
            None => unnumbered.push(c),
        }
    }
    if !named.is_empty() && !unnumbered.is_empty() {
        bail!(
            "{shown}: {} frame file(s) have a number in their name and {} do not (e.g. {} and \
             {}): cannot tell which frame each one is; rename or remove the odd ones",
            named.len(),
            unnumbered.len(),
            named[0].candidate.name,
            unnumbered[0].name
        );
    }
    if patterns.len() > 1 {
        let mut examples: Vec<String> = patterns
            .iter()
            .map(|((p, s), n)| format!("{n} named {p}N{s}.{ext}"))
            .collect();
        examples.sort();
        bail!(
            "{shown}: frame names follow {} different patterns ({}): cannot tell which frame \
             each one is; put each sequence in its own folder",
            patterns.len(),
            examples.join(", ")
        );
    }

    let (slots, naming) = if !unnumbered.is_empty() {
        unnumbered.sort_by(|a, b| natural_cmp(&a.name, &b.name));
        warnings.push(format!(
            "{shown}: frame names carry no number (e.g. {}): frames are taken in name order, \
             and a lost frame cannot be detected",
            unnumbered[0].name
        ));
        let slots = unnumbered
            .into_iter()
            .enumerate()
            .map(|(index, c)| Slot {
                index,
                path: c.path,
                time: None,
                problem: c.problem,
            })
            .collect();
        (slots, Naming::Unnumbered)
    } else if named
        .iter()
        .any(|n| n.decimal || n.whole >= FIRST_TIME_NAME)
    {
        (timed(dir, named, &mut warnings)?, Naming::Timed)
    } else {
        numbered(dir, ext, named, &hints)?
    };
    Ok(Listing {
        dir: dir.to_path_buf(),
        format,
        slots,
        naming,
        warnings,
    })
}

fn stem(name: &str) -> Option<&str> {
    name.rsplit_once('.').map(|(s, _)| s)
}

fn gcd(a: u128, b: u128) -> u128 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

/// Slots of frames named by number, gaps included.
fn numbered(
    dir: &Path,
    ext: &str,
    mut named: Vec<Named>,
    hints: &HashMap<String, String>,
) -> Result<(Vec<Slot>, Naming)> {
    let shown = dir.display();
    named.sort_by(|a, b| {
        a.whole
            .cmp(&b.whole)
            .then_with(|| a.candidate.name.cmp(&b.candidate.name))
    });
    if let Some(w) = named.windows(2).find(|w| w[0].whole == w[1].whole) {
        bail!(
            "{shown}: frame {} has two files, {} and {}: remove one",
            w[0].whole,
            w[0].candidate.name,
            w[1].candidate.name
        );
    }
    let step = named
        .windows(2)
        .fold(0, |g, w| gcd(g, w[1].whole - w[0].whole))
        .max(1);
    let (first, last) = (named[0].whole, named[named.len() - 1].whole);
    let span = (last - first) / step + 1;
    let gaps = span - named.len() as u128;
    if gaps > MAX_GAPS.max(named.len()) as u128 {
        bail!(
            "{shown}: {} frame files numbered {first} to {last} leave {gaps} numbers out: \
             these names are not a frame sequence",
            named.len()
        );
    }
    // A missing frame gets the name its neighbours' pattern gives it.
    let width = named[0].digits;
    let same_width = named.iter().all(|n| n.digits == width);
    let (prefix, suffix) = {
        let stem = stem(&named[0].candidate.name).unwrap_or("");
        let (p, _, s) = split_number(stem).unwrap_or(("", "", ""));
        (p.to_string(), s.to_string())
    };
    let file_ext = named[0]
        .candidate
        .name
        .rsplit_once('.')
        .map_or(ext.to_string(), |(_, e)| e.to_string());
    let index_of = |n: u128| {
        usize::try_from(n).with_context(|| format!("{shown}: frame number {n} is too large"))
    };
    let mut slots = Vec::with_capacity(span as usize);
    let mut files = named.into_iter().peekable();
    let mut number = first;
    while number <= last {
        match files.next_if(|n| n.whole == number) {
            Some(n) => slots.push(Slot {
                index: index_of(number)?,
                path: n.candidate.path,
                time: None,
                problem: n.candidate.problem,
            }),
            None => {
                let digits = if same_width {
                    format!("{number:0width$}")
                } else {
                    number.to_string()
                };
                let stem = format!("{prefix}{digits}{suffix}");
                let problem = match hints.get(&stem) {
                    Some(other) => format!("missing ({other} is there, in another format)"),
                    None => "missing".to_string(),
                };
                slots.push(Slot {
                    index: index_of(number)?,
                    path: dir.join(format!("{stem}.{file_ext}")),
                    time: None,
                    problem: Some(problem),
                });
            }
        }
        number += step;
    }
    let step = u64::try_from(step).unwrap_or(u64::MAX);
    Ok((slots, Naming::Numbered { step }))
}

/// Slots of frames named by time, in time order; warns about unusually long intervals.
fn timed(dir: &Path, named: Vec<Named>, warnings: &mut Vec<String>) -> Result<Vec<Slot>> {
    let shown = dir.display();
    let largest_integer = named
        .iter()
        .filter(|n| !n.decimal)
        .map(|n| n.whole)
        .max()
        .unwrap_or(0);
    let unit = integer_time_digits(largest_integer);
    let scale = 10u128.pow(unit);
    let mut keyed: Vec<(TimeKey, Candidate)> = named
        .into_iter()
        .map(|n| {
            let key = if n.decimal {
                TimeKey::new(n.whole, &n.fraction)
            } else {
                let fraction = format!("{:0width$}", n.whole % scale, width = unit as usize);
                TimeKey::new(n.whole / scale, if unit == 0 { "" } else { &fraction })
            };
            (key, n.candidate)
        })
        .collect();
    keyed.sort_by(|a, b| a.0.cmp(&b.0).then_with(|| a.1.name.cmp(&b.1.name)));
    if let Some(w) = keyed.windows(2).find(|w| w[0].0 == w[1].0) {
        bail!(
            "{shown}: {} and {} name the same time: remove one",
            w[0].1.name,
            w[1].1.name
        );
    }
    let times: Vec<f64> = keyed.iter().map(|(k, _)| k.seconds_f64()).collect();
    let mut intervals: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    if intervals.len() >= 2 {
        let all = intervals.clone();
        intervals.sort_by(f64::total_cmp);
        let median = intervals[intervals.len() / 2];
        let long: Vec<usize> = (0..all.len())
            .filter(|&i| median > 0.0 && all[i] > GAP_FACTOR * median)
            .collect();
        if let Some(&i) = long.first() {
            warnings.push(format!(
                "{shown}: {} interval(s) between time-named frames are much longer than the \
                 usual {median} s, first {} s between {} and {}: frames may be missing there",
                long.len(),
                all[i],
                keyed[i].1.name,
                keyed[i + 1].1.name
            ));
        }
    }
    Ok(keyed
        .into_iter()
        .zip(times)
        .enumerate()
        .map(|(index, ((_, c), time))| Slot {
            index,
            path: c.path,
            time: Some(time),
            problem: c.problem,
        })
        .collect())
}

/// Orders names so that `scan2` comes before `scan10`: runs of digits compare as numbers,
/// everything else byte-wise. Zero-padded names keep their plain order.
pub fn natural_cmp(a: &str, b: &str) -> Ordering {
    let (mut a, mut b) = (a.as_bytes(), b.as_bytes());
    loop {
        match (a.first(), b.first()) {
            (None, None) => return Ordering::Equal,
            (None, Some(_)) => return Ordering::Less,
            (Some(_), None) => return Ordering::Greater,
            (Some(x), Some(y)) if x.is_ascii_digit() && y.is_ascii_digit() => {
                let (da, ra) = split_digits(a);
                let (db, rb) = split_digits(b);
                let (ta, tb) = (trim_zeros(da), trim_zeros(db));
                let order = ta
                    .len()
                    .cmp(&tb.len())
                    .then_with(|| ta.cmp(tb))
                    .then_with(|| da.len().cmp(&db.len()));
                if order != Ordering::Equal {
                    return order;
                }
                (a, b) = (ra, rb);
            }
            (Some(x), Some(y)) => {
                if x != y {
                    return x.cmp(y);
                }
                (a, b) = (&a[1..], &b[1..]);
            }
        }
    }
}

fn split_digits(s: &[u8]) -> (&[u8], &[u8]) {
    let n = s.iter().take_while(|c| c.is_ascii_digit()).count();
    s.split_at(n)
}

fn trim_zeros(s: &[u8]) -> &[u8] {
    let n = s.iter().take_while(|c| **c == b'0').count();
    &s[n..]
}

#[cfg(test)]
mod tests;
