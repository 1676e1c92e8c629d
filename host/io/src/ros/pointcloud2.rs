//! `sensor_msgs/PointCloud2` payloads, shared by the ROS 1 bag and ROS 2 MCAP readers.
//!
//! The two containers serialize the message differently (ROS 1 wire format, CDR) but carry the
//! same layout; [`message`](super::message) parses either into a [`PointCloud2`] view and
//! this module turns the view into points and per-point times the way the reference does
//! (`kiss_icp/tools/point_cloud2.py::read_point_cloud`, kiss-icp 1.3.0): x, y, z and the first
//! field named `t`, `timestamp` or `time`, every value converted to f64. Unlike the reference,
//! NaN points are kept (the core counts them) so that points and times stay aligned.

use crate::dataset::{Frame, Item};
use std::collections::{HashMap, HashSet};

/// `sensor_msgs/PointField` datatype codes.
pub const INT8: u8 = 1;
/// See [`INT8`].
pub const UINT8: u8 = 2;
/// See [`INT8`].
pub const INT16: u8 = 3;
/// See [`INT8`].
pub const UINT16: u8 = 4;
/// See [`INT8`].
pub const INT32: u8 = 5;
/// See [`INT8`].
pub const UINT32: u8 = 6;
/// See [`INT8`].
pub const FLOAT32: u8 = 7;
/// See [`INT8`].
pub const FLOAT64: u8 = 8;

/// Field names the reference accepts as per-point time, matched in field order.
pub const TIME_FIELD_NAMES: [&str; 3] = ["t", "timestamp", "time"];

/// Size in bytes and name of a datatype code, `None` for codes outside 1..=8.
pub fn datatype_info(datatype: u8) -> Option<(usize, &'static str)> {
    Some(match datatype {
        INT8 => (1, "INT8"),
        UINT8 => (1, "UINT8"),
        INT16 => (2, "INT16"),
        UINT16 => (2, "UINT16"),
        INT32 => (4, "INT32"),
        UINT32 => (4, "UINT32"),
        FLOAT32 => (4, "FLOAT32"),
        FLOAT64 => (8, "FLOAT64"),
        _ => return None,
    })
}

/// One `sensor_msgs/PointField`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PointField {
    /// Field name (`x`, `intensity`, `t`, ...).
    pub name: String,
    /// Byte offset inside a point.
    pub offset: u32,
    /// Datatype code, 1..=8 ([`INT8`]..[`FLOAT64`]).
    pub datatype: u8,
    /// Number of consecutive values.
    pub count: u32,
}

/// A message header stamp: seconds and nanoseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stamp {
    /// Whole seconds (u32 in ROS 1, i32 in ROS 2).
    pub sec: i64,
    /// Nanoseconds.
    pub nsec: u32,
}

impl Stamp {
    /// Seconds as f64, computed as the reference's `stamp.sec + stamp.nanosec / 1e9`.
    pub fn seconds(self) -> f64 {
        self.sec as f64 + f64::from(self.nsec) / 1e9
    }
}

impl std::fmt::Display for Stamp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}.{:09}", self.sec, self.nsec)
    }
}

/// A parsed PointCloud2 message whose `data` still borrows the serialized bytes.
#[derive(Clone, Debug, PartialEq)]
pub struct PointCloud2<'a> {
    /// `header.stamp`.
    pub stamp: Stamp,
    /// `header.frame_id`.
    pub frame_id: String,
    /// Number of rows (1 for unorganized clouds).
    pub height: u32,
    /// Points per row.
    pub width: u32,
    /// Point layout.
    pub fields: Vec<PointField>,
    /// Byte order of `data`.
    pub is_bigendian: bool,
    /// Bytes per point.
    pub point_step: u32,
    /// Bytes per row.
    pub row_step: u32,
    /// The points.
    pub data: &'a [u8],
    /// Whether the publisher promised no invalid points (not trusted).
    pub is_dense: bool,
}

/// Points and per-point times read from a [`PointCloud2`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Decoded {
    /// x, y, z of every point, row-major, NaN points included.
    pub points: Vec<[f64; 3]>,
    /// Values of the time field, one per point, if the cloud has one.
    pub stamps: Option<Vec<f64>>,
    /// Oddities that did not prevent decoding.
    pub warnings: Vec<String>,
}

/// How to read one scalar out of a point.
#[derive(Clone, Copy, Debug)]
struct Scalar {
    offset: usize,
    datatype: u8,
    big_endian: bool,
}

impl Scalar {
    /// The value in `point`, `None` if `point` is too short (never after validation).
    fn read(self, point: &[u8]) -> Option<f64> {
        let bytes = point.get(self.offset..)?;
        macro_rules! num {
            ($t:ty) => {{
                let raw = *bytes.first_chunk()?;
                let v = if self.big_endian {
                    <$t>::from_be_bytes(raw)
                } else {
                    <$t>::from_le_bytes(raw)
                };
                v as f64
            }};
        }
        Some(match self.datatype {
            INT8 => num!(i8),
            UINT8 => num!(u8),
            INT16 => num!(i16),
            UINT16 => num!(u16),
            INT32 => num!(i32),
            UINT32 => num!(u32),
            FLOAT32 => num!(f32),
            FLOAT64 => num!(f64),
            _ => return None,
        })
    }
}

/// Checks the layout of `cloud` and reads its points and per-point times.
///
/// Every field must have a known datatype, a non-zero count and fit inside `point_step` (the
/// reference's numpy dtype rejects anything else); x, y, z must be single FLOAT32 or FLOAT64
/// values; rows are `row_step` bytes apart and `data` must hold `row_step * height` bytes. When
/// `row_step == width * point_step` (every publisher we know of) this reads exactly the bytes the
/// reference reads; the reference ignores `row_step` altogether.
pub fn decode(cloud: &PointCloud2<'_>) -> Result<Decoded, String> {
    decode_at_most(cloud, usize::MAX)
}

/// [`decode`], reading at most the first `max_points` points (row-major); a cloud cut there
/// says so in [`Decoded::warnings`].
pub fn decode_at_most(cloud: &PointCloud2<'_>, max_points: usize) -> Result<Decoded, String> {
    let point_step = u64::from(cloud.point_step);
    // The reference names subfields of count > 1 `name_0`, `name_1`, ... and unnamed fields
    // `unnamed_field_i`, then rejects duplicate names; the same rule is checked here without
    // spelling out every subfield (a count can be huge).
    let mut singles: HashSet<String> = HashSet::new();
    let mut multis: HashMap<String, u32> = HashMap::new();
    for (i, f) in cloud.fields.iter().enumerate() {
        let (size, _) = datatype_info(f.datatype)
            .ok_or_else(|| format!("field `{}` has unknown datatype {}", f.name, f.datatype))?;
        if f.count == 0 {
            return Err(format!("field `{}` has count 0", f.name));
        }
        let end = u64::from(f.offset) + u64::from(f.count) * size as u64;
        if end > point_step {
            return Err(format!(
                "field `{}` (offset {}, {} x {} bytes) does not fit in point_step {}",
                f.name, f.offset, f.count, size, cloud.point_step
            ));
        }
        let base = if f.name.is_empty() {
            format!("unnamed_field_{i}")
        } else {
            f.name.clone()
        };
        let duplicate = if f.count == 1 {
            !singles.insert(base.clone())
        } else {
            multis.insert(base.clone(), f.count).is_some()
        };
        if duplicate {
            return Err(format!("duplicate field name `{base}`"));
        }
    }
    for s in &singles {
        // `s` collides with subfield k of a multi-valued field `b` when s == "b_k".
        if let Some((b, k)) = s.rsplit_once('_') {
            let clash = multis.get(b).is_some_and(|&count| {
                k.parse::<u32>()
                    .is_ok_and(|k_num| k_num < count && k_num.to_string() == k)
            });
            if clash {
                return Err(format!("duplicate field name `{s}`"));
            }
        }
    }

    let big_endian = cloud.is_bigendian;
    let scalar = |f: &PointField| Scalar {
        offset: f.offset as usize,
        datatype: f.datatype,
        big_endian,
    };
    let mut xyz = [None; 3];
    for (slot, axis) in xyz.iter_mut().zip(["x", "y", "z"]) {
        // As in the reference, a count > 1 field `x` only provides `x_0`, `x_1`, ...
        let named = |f: &&PointField| f.name == axis;
        let f = match cloud.fields.iter().filter(named).find(|f| f.count == 1) {
            Some(f) => f,
            None => match cloud.fields.iter().find(named) {
                Some(f) => return Err(format!("field `{axis}` has count {}, expected 1", f.count)),
                None => return Err(format!("no field `{axis}`")),
            },
        };
        if f.datatype != FLOAT32 && f.datatype != FLOAT64 {
            let (_, name) = datatype_info(f.datatype).unwrap_or((0, "?"));
            return Err(format!(
                "field `{axis}` is {name}; x, y, z must be FLOAT32 or FLOAT64"
            ));
        }
        *slot = Some(scalar(f));
    }
    let [Some(x), Some(y), Some(z)] = xyz else {
        return Err("x, y, z not found".into());
    };
    let time = match cloud
        .fields
        .iter()
        .find(|f| TIME_FIELD_NAMES.contains(&f.name.as_str()))
    {
        Some(f) if f.count != 1 => {
            return Err(format!(
                "time field `{}` has count {}, expected 1",
                f.name, f.count
            ))
        }
        Some(f) => Some(scalar(f)),
        None => None,
    };

    let (width, height) = (u64::from(cloud.width), u64::from(cloud.height));
    let row_bytes = width * point_step;
    if u64::from(cloud.row_step) < row_bytes {
        return Err(format!(
            "row_step {} is less than width {} x point_step {}",
            cloud.row_step, cloud.width, cloud.point_step
        ));
    }
    let needed = u64::from(cloud.row_step) * height;
    let have = cloud.data.len() as u64;
    if have < needed {
        return Err(format!(
            "data has {have} bytes, row_step {} x height {} needs {needed}",
            cloud.row_step, cloud.height
        ));
    }
    let mut warnings = Vec::new();
    if have > needed {
        warnings.push(format!(
            "{} bytes after the last row ignored",
            have - needed
        ));
    }

    // `needed <= data.len()` bounds every index below, and the capacity by data.len() / 4.
    let declared = usize::try_from(width * height).map_err(|_| "too many points".to_string())?;
    let n = declared.min(max_points);
    if n < declared {
        warnings.push(crate::folders::file_cloud::truncation_warning(n, declared));
    }
    let mut points = Vec::with_capacity(n);
    let mut stamps = time.map(|_| Vec::with_capacity(n));
    let (row_step, point_step) = (cloud.row_step as usize, cloud.point_step as usize);
    let short = || "point outside data".to_string();
    // A zero width has no points however many (empty) rows it declares; looping over 4e9 of
    // them took minutes (found by fuzzing).
    let rows = if cloud.width == 0 {
        0
    } else {
        cloud.height as usize
    };
    for r in 0..rows {
        let row = cloud.data.get(r * row_step..).ok_or_else(short)?;
        for c in 0..cloud.width as usize {
            if points.len() == n {
                break;
            }
            let p = row
                .get(c * point_step..(c + 1) * point_step)
                .ok_or_else(short)?;
            let read = |s: Scalar| s.read(p).ok_or_else(short);
            points.push([read(x)?, read(y)?, read(z)?]);
            if let (Some(t), Some(out)) = (time, stamps.as_mut()) {
                out.push(read(t)?);
            }
        }
    }
    Ok(Decoded {
        points,
        stamps,
        warnings,
    })
}

/// Bytes a point of a PointCloud2 may take when sizing container records: generous for every
/// lidar driver we know (Ouster 48, Hesai 32, Velodyne 22-32, Livox 18-26).
pub const MAX_POINT_BYTES: u64 = 512;

/// Smallest record limit, so that chunks of small messages around the clouds still fit.
pub const MIN_RECORD_LIMIT: u64 = 64 << 20;

/// Largest container record (a bag chunk, an MCAP chunk or message) read for a scan capacity
/// of `scan_points`: a cloud of that many points of [`MAX_POINT_BYTES`] each, at least
/// [`MIN_RECORD_LIMIT`]. Bigger records are refused before anything is allocated for them, so
/// the memory a container costs is set by the configuration, not by the file.
pub fn record_limit(scan_points: usize) -> u64 {
    (scan_points as u64)
        .saturating_mul(MAX_POINT_BYTES)
        .max(MIN_RECORD_LIMIT)
}

/// Puts the messages `plan` (in file order) in receive-time order (stable: equal times keep
/// file order); if they were not in that order, the warning naming the first message out of
/// order.
pub(crate) fn time_order<T>(
    file: &str,
    topic: &str,
    plan: &mut [T],
    time: impl Fn(&T) -> u64,
) -> Option<String> {
    let mut latest: Option<(usize, u64)> = None;
    let mut first_late = None;
    for (k, m) in plan.iter().enumerate() {
        let t = time(m);
        match latest {
            Some((j, l)) if t < l => {
                first_late = Some((k, t, j, l));
                break;
            }
            Some((_, l)) if t == l => {}
            _ => latest = Some((k, t)),
        }
    }
    let (k, t, j, l) = first_late?;
    plan.sort_by_key(|m| time(m));
    Some(format!(
        "{file}: messages on {topic} are not in time order (message {k} was received at {}, \
         after message {j} at {}); frames are read in receive-time order",
        stamp_of_nanos(t),
        stamp_of_nanos(l)
    ))
}

/// A container's receive (log) time in nanoseconds as a [`Stamp`].
pub fn stamp_of_nanos(ns: u64) -> Stamp {
    Stamp {
        sec: (ns / 1_000_000_000) as i64,
        nsec: (ns % 1_000_000_000) as u32,
    }
}

/// Where a message is in its container: frame identity, file, topic and receive time.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MessageAt<'a> {
    /// The frame's identity (place in receive-time order).
    pub index: usize,
    /// The container file, as shown.
    pub file: &'a str,
    /// The topic.
    pub topic: &'a str,
    /// Receive (log) time in nanoseconds.
    pub received: u64,
}

/// Turns one serialized message into a stream item: a frame named `file:topic@stamp`, or a
/// skipped entry named `file:topic@receive time` whose reason names the file, topic and
/// message when the payload cannot be read. At most `max_points` points are decoded.
pub(crate) fn message_item(
    at: MessageAt<'_>,
    parsed: Result<PointCloud2<'_>, String>,
    max_points: usize,
) -> Item {
    let MessageAt {
        index, file, topic, ..
    } = at;
    let received = stamp_of_nanos(at.received);
    let skipped = |reason: String| Item::Skipped {
        index,
        name: format!("{file}:{topic}@{received}"),
        time: Some(received.seconds()),
        reason: format!("{file}:{topic} message {index}: {reason}"),
    };
    let cloud = match parsed {
        Ok(c) => c,
        Err(e) => return skipped(e),
    };
    match decode_at_most(&cloud, max_points) {
        Ok(d) => Item::Frame(frame_of(
            index,
            format!("{file}:{topic}@{}", cloud.stamp),
            cloud.stamp,
            d,
        )),
        Err(e) => skipped(format!("stamp {}: {e}", cloud.stamp)),
    }
}

/// The frame of a decoded cloud stamped `stamp`, as every reader of PointCloud2 (bags, MCAP
/// files, the ROS 2 node) makes it: its time is the stamp, its sweep ends where
/// [`sweep_end`] says, and its warnings are prefixed with `name`.
pub fn frame_of(index: usize, name: String, stamp: Stamp, d: Decoded) -> Frame {
    let warnings = d.warnings.iter().map(|w| format!("{name}: {w}")).collect();
    let end = sweep_end(stamp.seconds(), d.stamps.as_deref());
    Frame {
        index,
        name,
        points: d.points,
        stamps: d.stamps,
        time: Some(stamp.seconds()),
        warnings,
        intensity: None,
        sweep: None,
        end,
        imu: Vec::new(),
    }
}

/// Point times further than this from the header stamp (s) are not seconds on its clock.
pub const SAME_CLOCK_S: f64 = 1.0;

/// Where a cloud stamped `header` (s) ends on the sensor's clock when its point times do not
/// tell: at its header stamp if they are offsets or another unit (farther than
/// [`SAME_CLOCK_S`] from it), `None` when they are seconds on its clock or absent.
pub fn sweep_end(header: f64, stamps: Option<&[f64]>) -> Option<f64> {
    let latest = stamps?.iter().copied().reduce(f64::max)?;
    ((latest - header).abs() > SAME_CLOCK_S).then_some(header)
}

/// What kind of topic a reader looks for, for [`choose_topic`] and its messages.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Wanted<'a> {
    /// The message type (or schema) name.
    pub type_name: &'a str,
    /// What its topics are called in a list (`point-cloud`, `IMU`).
    pub kind: &'a str,
    /// The flag that names one.
    pub flag: &'a str,
}

impl<'a> Wanted<'a> {
    /// Point clouds of `type_name`, chosen with `--topic`.
    pub const fn cloud(type_name: &'a str) -> Self {
        Self {
            type_name,
            kind: "point-cloud",
            flag: "--topic",
        }
    }
}

/// Picks the topic to read: `requested` if it carries the wanted type, otherwise the only
/// topic that does. `topics` lists every (topic, type) pair in the file; `is_wanted` says which
/// types are the wanted one. Errors name the file and list the candidates.
pub(crate) fn choose_topic(
    file: &str,
    topics: &[(String, String)],
    is_wanted: impl Fn(&str) -> bool,
    wanted: Wanted<'_>,
    requested: Option<&str>,
) -> Result<String, String> {
    let Wanted {
        type_name,
        kind,
        flag,
    } = wanted;
    let candidates = wanted_topics(topics, is_wanted);
    let listing = if candidates.is_empty() {
        "none".to_string()
    } else {
        candidates.join(", ")
    };
    match requested {
        Some(t) if candidates.contains(&t) => Ok(t.to_string()),
        Some(t) => match topics.iter().find(|(name, _)| name == t) {
            Some((_, ty)) => Err(format!(
                "{file}: topic {t} carries {ty}, not {type_name} ({kind} topics: {listing})"
            )),
            None => Err(format!("{file}: no topic {t} ({kind} topics: {listing})")),
        },
        None => match candidates.as_slice() {
            [only] => Ok(only.to_string()),
            [] => {
                let mut all: Vec<String> =
                    topics.iter().map(|(t, ty)| format!("{t} ({ty})")).collect();
                all.sort_unstable();
                all.dedup();
                Err(format!(
                    "{file}: no {type_name} topic (topics: {})",
                    if all.is_empty() {
                        "none".to_string()
                    } else {
                        all.join(", ")
                    }
                ))
            }
            _ => Err(format!(
                "{file}: several {type_name} topics ({listing}); choose one with {flag}"
            )),
        },
    }
}

/// The topics of `topics` whose type `is_wanted` accepts, sorted, each once.
pub(crate) fn wanted_topics(
    topics: &[(String, String)],
    is_wanted: impl Fn(&str) -> bool,
) -> Vec<&str> {
    let mut out: Vec<&str> = topics
        .iter()
        .filter(|(_, ty)| is_wanted(ty))
        .map(|(t, _)| t.as_str())
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

#[cfg(test)]
mod tests;

/// Clouds built by tests, with values known independently of [`decode`].
#[cfg(test)]
pub(crate) mod fixture;
