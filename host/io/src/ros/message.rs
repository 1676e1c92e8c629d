//! `sensor_msgs/PointCloud2` messages as the two ROS generations serialize them, read into a
//! [`PointCloud2`] view by one parser: ROS 1 (bags: little-endian, packed, strings without a
//! terminator) and CDR (XCDR1, ROS 2's MCAP files and DDS: either byte order, 4-byte values
//! aligned, strings with a terminating NUL, a 4-byte encapsulation header first). The message
//! layouts differ only in the header: ROS 1's has a `seq` and an unsigned stamp.

use super::pointcloud2::{PointCloud2, PointField, Stamp};

/// How a message's bytes are laid out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    /// ROS 1: little-endian, no alignment.
    Ros1,
    /// CDR after its encapsulation header (alignment is relative to the header's end).
    Cdr { big_endian: bool },
}

/// Cursor over a message body.
struct Reader<'a> {
    buf: &'a [u8],
    pos: usize,
    encoding: Encoding,
    /// Bytes before `buf` in the message (the encapsulation header), for error positions.
    before: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        let bytes = self
            .pos
            .checked_add(n)
            .and_then(|end| self.buf.get(self.pos..end))
            .ok_or_else(|| {
                format!(
                    "message ends inside {what} (needs {n} bytes at byte {} of {})",
                    self.pos + self.before,
                    self.buf.len() + self.before
                )
            })?;
        self.pos += n;
        Ok(bytes)
    }

    fn u8(&mut self, what: &str) -> Result<u8, String> {
        Ok(self.take(1, what)?[0])
    }

    fn u32(&mut self, what: &str) -> Result<u32, String> {
        if let Encoding::Cdr { .. } = self.encoding {
            self.pos = self.pos.next_multiple_of(4);
        }
        let b = self.take(4, what)?;
        let b = [b[0], b[1], b[2], b[3]];
        Ok(match self.encoding {
            Encoding::Cdr { big_endian: true } => u32::from_be_bytes(b),
            _ => u32::from_le_bytes(b),
        })
    }

    /// A u32 length, then the bytes (in CDR the length counts a terminating NUL).
    fn string(&mut self, what: &str) -> Result<String, String> {
        let n = self.u32(what)? as usize;
        let mut bytes = self.take(n, what)?;
        if let Encoding::Cdr { .. } = self.encoding {
            bytes = bytes.strip_suffix(&[0]).unwrap_or(bytes);
        }
        Ok(String::from_utf8_lossy(bytes).into_owned())
    }

    /// Bytes left after the message.
    fn rest(&self) -> usize {
        self.buf.len() - self.pos
    }
}

/// Parses a ROS 1 serialized `sensor_msgs/PointCloud2`.
pub fn parse_ros1(body: &[u8]) -> Result<PointCloud2<'_>, String> {
    let mut r = Reader {
        buf: body,
        pos: 0,
        encoding: Encoding::Ros1,
        before: 0,
    };
    let _seq = r.u32("header.seq")?;
    let sec = r.u32("header.stamp")?;
    let nsec = r.u32("header.stamp")?;
    let stamp = Stamp {
        sec: i64::from(sec),
        nsec,
    };
    let cloud = after_stamp(&mut r, stamp)?;
    match r.rest() {
        0 => Ok(cloud),
        extra => Err(format!("{extra} bytes after the end of the message")),
    }
}

/// Parses a CDR serialized `sensor_msgs/msg/PointCloud2` (with its encapsulation header).
pub fn parse_cdr(body: &[u8]) -> Result<PointCloud2<'_>, String> {
    let (header, buf) = body
        .split_first_chunk::<4>()
        .ok_or("message shorter than the CDR encapsulation header")?;
    let big_endian = match header[..2] {
        [0, 0] => true,
        [0, 1] => false,
        _ => {
            return Err(format!(
                "encapsulation {:02x}{:02x} is not plain CDR",
                header[0], header[1]
            ))
        }
    };
    let mut r = Reader {
        buf,
        pos: 0,
        encoding: Encoding::Cdr { big_endian },
        before: header.len(),
    };
    let sec = r.u32("header.stamp.sec")? as i32;
    let nsec = r.u32("header.stamp.nanosec")?;
    let stamp = Stamp {
        sec: i64::from(sec),
        nsec,
    };
    let cloud = after_stamp(&mut r, stamp)?;
    // Serializers may pad the message to a multiple of 4 bytes; more is not this type.
    match r.rest() {
        0..=3 => Ok(cloud),
        extra => Err(format!("{extra} bytes after the end of the message")),
    }
}

/// The message from `header.frame_id` on, the same fields in both generations.
fn after_stamp<'a>(r: &mut Reader<'a>, stamp: Stamp) -> Result<PointCloud2<'a>, String> {
    let frame_id = r.string("header.frame_id")?;
    let height = r.u32("height")?;
    let width = r.u32("width")?;
    let n_fields = r.u32("fields")? as usize;
    // Each field takes at least 13 bytes; a larger count is garbage, not an allocation size.
    if n_fields > r.rest() / 13 {
        return Err(format!("{n_fields} fields cannot fit in the message"));
    }
    let mut fields = Vec::with_capacity(n_fields);
    for _ in 0..n_fields {
        fields.push(PointField {
            name: r.string("fields.name")?,
            offset: r.u32("fields.offset")?,
            datatype: r.u8("fields.datatype")?,
            count: r.u32("fields.count")?,
        });
    }
    let is_bigendian = r.u8("is_bigendian")? != 0;
    let point_step = r.u32("point_step")?;
    let row_step = r.u32("row_step")?;
    let data_len = r.u32("data")? as usize;
    let data = r.take(data_len, "data")?;
    let is_dense = r.u8("is_dense")? != 0;
    Ok(PointCloud2 {
        stamp,
        frame_id,
        height,
        width,
        fields,
        is_bigendian,
        point_step,
        row_step,
        data,
        is_dense,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Where a ROS 1 message of [`ros1_head`] holds its field count.
    const FIELD_COUNT_AT: usize = 25;

    /// A ROS 1 message up to its field count `n`: seq, stamp, frame id `f`, a 1 x 1 cloud.
    fn ros1_head(n: u32) -> Vec<u8> {
        let mut b = Vec::new();
        for v in [7u32, 1, 2, 1] {
            b.extend(v.to_le_bytes());
        }
        b.push(b'f');
        for v in [1u32, 1, n] {
            b.extend(v.to_le_bytes());
        }
        assert_eq!(b.len(), FIELD_COUNT_AT + 4);
        b
    }

    /// A field of the fewest bytes, 13: an empty name, `offset`, FLOAT32, count 1.
    fn field(b: &mut Vec<u8>, offset: u32) {
        b.extend(0u32.to_le_bytes());
        b.extend(offset.to_le_bytes());
        b.push(7);
        b.extend(1u32.to_le_bytes());
    }

    #[test]
    fn a_field_count_the_message_cannot_hold_is_refused_before_allocating() {
        let err = parse_ros1(&ros1_head(u32::MAX)).unwrap_err();
        println!("{} fields: {err}", u32::MAX);
        assert!(err.contains("cannot fit"), "{err}");
        // As many fields as the rest holds at 13 bytes each: read, then the message ends.
        let mut b = ros1_head(3);
        for k in 0..3 {
            field(&mut b, 4 * k);
        }
        let err = parse_ros1(&b).unwrap_err();
        println!("3 fields in 39 bytes: {err}");
        assert!(err.contains("inside is_bigendian"), "{err}");
        // One more than that cannot fit.
        b[FIELD_COUNT_AT..FIELD_COUNT_AT + 4].copy_from_slice(&4u32.to_le_bytes());
        let err = parse_ros1(&b).unwrap_err();
        assert!(err.contains("4 fields cannot fit"), "{err}");
    }

    #[test]
    fn the_flags_after_the_fields_are_read_as_written() {
        for (big, dense) in [(0u8, 0u8), (1, 0), (0, 1), (1, 1)] {
            let mut b = ros1_head(1);
            field(&mut b, 0);
            b.push(big);
            for v in [4u32, 4, 4] {
                b.extend(v.to_le_bytes());
            }
            b.extend(1.5f32.to_le_bytes());
            b.push(dense);
            let cloud = parse_ros1(&b).unwrap();
            assert_eq!((cloud.is_bigendian, cloud.is_dense), (big == 1, dense == 1));
            assert_eq!((cloud.point_step, cloud.row_step), (4, 4));
            assert_eq!(cloud.data, &1.5f32.to_le_bytes()[..]);
        }
    }
}
