//! The two ways ROS serializes a message, read field by field: ROS 1 (bags: little-endian,
//! packed, strings without a terminator) and CDR (XCDR1, ROS 2's MCAP files and `.db3` bags:
//! a 4-byte encapsulation header, then either byte order, every value aligned to its size from
//! the header's end, strings with a terminating NUL). Every read is checked against the
//! message's length first and names the field it was for; a sequence's element count is
//! checked against the bytes left before anything is allocated for it.

use super::pointcloud2::Stamp;

/// How a message's bytes are laid out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Encoding {
    /// ROS 1: little-endian, no alignment.
    Ros1,
    /// CDR after its encapsulation header (alignment is relative to the header's end).
    Cdr {
        /// Big-endian (encapsulation `00 00`) or little-endian (`00 01`).
        big_endian: bool,
    },
}

/// Cursor over a message body.
pub(crate) struct Reader<'a> {
    buf: &'a [u8],
    pos: usize,
    encoding: Encoding,
    /// Bytes before `buf` in the message (the encapsulation header), for error positions.
    before: usize,
}

impl<'a> Reader<'a> {
    /// A ROS 1 message.
    pub fn ros1(body: &'a [u8]) -> Self {
        Self {
            buf: body,
            pos: 0,
            encoding: Encoding::Ros1,
            before: 0,
        }
    }

    /// A CDR message, its encapsulation header first.
    pub fn cdr(body: &'a [u8]) -> Result<Self, String> {
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
        Ok(Self {
            buf,
            pos: 0,
            encoding: Encoding::Cdr { big_endian },
            before: header.len(),
        })
    }

    /// A message of `encoding` generation: ROS 1 or CDR (whose byte order its header gives).
    pub fn of(ros1: bool, body: &'a [u8]) -> Result<Self, String> {
        if ros1 {
            Ok(Self::ros1(body))
        } else {
            Self::cdr(body)
        }
    }

    /// Skips CDR padding up to a multiple of `n` bytes (nothing in ROS 1).
    pub fn align(&mut self, n: usize) {
        if let Encoding::Cdr { .. } = self.encoding {
            self.pos = self
                .pos
                .next_multiple_of(n)
                .min(self.buf.len().max(self.pos));
        }
    }

    /// The next `n` bytes.
    pub fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
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

    fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N], String> {
        self.align(N);
        let b = self.take(N, what)?;
        let mut out = [0u8; N];
        out.copy_from_slice(b);
        if let Encoding::Cdr { big_endian: true } = self.encoding {
            out.reverse();
        }
        Ok(out)
    }

    /// A `uint8` (or `bool`, `byte`).
    pub fn u8(&mut self, what: &str) -> Result<u8, String> {
        Ok(self.take(1, what)?[0])
    }

    /// A `uint32`.
    pub fn u32(&mut self, what: &str) -> Result<u32, String> {
        self.array::<4>(what).map(u32::from_le_bytes)
    }

    /// An `int32`.
    pub fn i32(&mut self, what: &str) -> Result<i32, String> {
        self.array::<4>(what).map(i32::from_le_bytes)
    }

    /// A `uint64`.
    pub fn u64(&mut self, what: &str) -> Result<u64, String> {
        self.array::<8>(what).map(u64::from_le_bytes)
    }

    /// A `float32`.
    pub fn f32(&mut self, what: &str) -> Result<f32, String> {
        self.array::<4>(what).map(f32::from_le_bytes)
    }

    /// A `string`: a u32 length, then the bytes (in CDR the length counts a terminating NUL).
    pub fn string(&mut self, what: &str) -> Result<String, String> {
        let n = self.u32(what)? as usize;
        let mut bytes = self.take(n, what)?;
        if let Encoding::Cdr { .. } = self.encoding {
            bytes = bytes.strip_suffix(&[0]).unwrap_or(bytes);
        }
        Ok(String::from_utf8_lossy(bytes).into_owned())
    }

    /// A `uint8[]`: its length, then the bytes.
    pub fn bytes(&mut self, what: &str) -> Result<&'a [u8], String> {
        let n = self.u32(what)? as usize;
        self.take(n, what)
    }

    /// A sequence's element count, refused when `min_bytes`-byte elements cannot all fit in
    /// the bytes left: a larger count is garbage, not an allocation size.
    pub fn count(&mut self, what: &str, min_bytes: usize) -> Result<usize, String> {
        let n = self.u32(what)? as usize;
        if n.saturating_mul(min_bytes.max(1)) > self.rest() {
            return Err(format!("{n} {what} cannot fit in the message"));
        }
        Ok(n)
    }

    /// A `time` (ROS 1: u32 seconds) or `builtin_interfaces/Time` (CDR: i32 seconds), then
    /// nanoseconds.
    pub fn time(&mut self, what: &str) -> Result<Stamp, String> {
        let sec = match self.encoding {
            Encoding::Ros1 => i64::from(self.u32(what)?),
            Encoding::Cdr { .. } => i64::from(self.i32(what)?),
        };
        let nsec = self.u32(what)?;
        Ok(Stamp { sec, nsec })
    }

    /// A `std_msgs/Header` (ROS 1 has a `seq` first): its stamp and frame id.
    pub fn header(&mut self) -> Result<(Stamp, String), String> {
        if self.encoding == Encoding::Ros1 {
            self.u32("header.seq")?;
        }
        let stamp = self.time("header.stamp")?;
        let frame_id = self.string("header.frame_id")?;
        Ok((stamp, frame_id))
    }

    /// Bytes left after the message.
    pub fn rest(&self) -> usize {
        self.buf.len() - self.pos
    }

    /// Nothing may follow the message but (in CDR) the up to 3 bytes of padding serializers
    /// add to a multiple of 4; more is another type's message.
    pub fn finish(&self) -> Result<(), String> {
        let slack = match self.encoding {
            Encoding::Ros1 => 0,
            Encoding::Cdr { .. } => 3,
        };
        match self.rest() {
            n if n <= slack => Ok(()),
            extra => Err(format!("{extra} bytes after the end of the message")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cdr_values_are_aligned_from_the_header_end_in_either_byte_order() {
        // u8 1, pad to 8, u64 2, u32 3; little-endian.
        let mut le = vec![0, 1, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0];
        le.extend(2u64.to_le_bytes());
        le.extend(3u32.to_le_bytes());
        let mut be = vec![0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0];
        be.extend(2u64.to_be_bytes());
        be.extend(3u32.to_be_bytes());
        for body in [le, be] {
            let mut r = Reader::cdr(&body).unwrap();
            assert_eq!(r.u8("a").unwrap(), 1);
            assert_eq!(r.u64("b").unwrap(), 2);
            assert_eq!(r.u32("c").unwrap(), 3);
            r.finish().unwrap();
        }
        // ROS 1 is packed.
        let mut b = vec![1u8];
        b.extend(2u64.to_le_bytes());
        let mut r = Reader::ros1(&b);
        assert_eq!((r.u8("a").unwrap(), r.u64("b").unwrap()), (1, 2));
        r.finish().unwrap();
    }

    #[test]
    fn counts_that_cannot_fit_and_cut_messages_are_errors_naming_the_field() {
        let b = u32::MAX.to_le_bytes();
        let e = Reader::ros1(&b).count("points", 19).unwrap_err();
        assert!(e.contains("4294967295 points cannot fit"), "{e}");
        let e = Reader::ros1(&[1, 0]).u32("point_num").unwrap_err();
        assert!(e.contains("inside point_num"), "{e}");
        let e = Reader::cdr(&[1, 1, 0, 0]).err().unwrap();
        assert!(e.contains("not plain CDR"), "{e}");
        let e = Reader::ros1(&[0]).finish().unwrap_err();
        assert!(e.contains("1 bytes after"), "{e}");
    }
}
