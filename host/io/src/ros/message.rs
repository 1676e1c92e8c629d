//! `sensor_msgs/PointCloud2` messages as the two ROS generations serialize them, read into a
//! [`PointCloud2`] view by one parser: ROS 1 (bags: little-endian, packed, strings without a
//! terminator) and CDR (XCDR1, ROS 2's MCAP files and DDS: either byte order, 4-byte values
//! aligned, strings with a terminating NUL, a 4-byte encapsulation header first). The message
//! layouts differ only in the header: ROS 1's has a `seq` and an unsigned stamp.

use super::pointcloud2::{PointCloud2, PointField, Stamp};
use super::serial::Reader;

/// Parses a ROS 1 serialized `sensor_msgs/PointCloud2`.
pub fn parse_ros1(body: &[u8]) -> Result<PointCloud2<'_>, String> {
    let mut r = Reader::ros1(body);
    let _seq = r.u32("header.seq")?;
    let sec = r.u32("header.stamp")?;
    let nsec = r.u32("header.stamp")?;
    let stamp = Stamp {
        sec: i64::from(sec),
        nsec,
    };
    let cloud = after_stamp(&mut r, stamp)?;
    r.finish()?;
    Ok(cloud)
}

/// Parses a CDR serialized `sensor_msgs/msg/PointCloud2` (with its encapsulation header).
pub fn parse_cdr(body: &[u8]) -> Result<PointCloud2<'_>, String> {
    let mut r = Reader::cdr(body)?;
    let sec = r.i32("header.stamp.sec")?;
    let nsec = r.u32("header.stamp.nanosec")?;
    let stamp = Stamp {
        sec: i64::from(sec),
        nsec,
    };
    let cloud = after_stamp(&mut r, stamp)?;
    // Serializers may pad the message to a multiple of 4 bytes; more is not this type.
    r.finish()?;
    Ok(cloud)
}

/// The message from `header.frame_id` on, the same fields in both generations.
fn after_stamp<'a>(r: &mut Reader<'a>, stamp: Stamp) -> Result<PointCloud2<'a>, String> {
    let frame_id = r.string("header.frame_id")?;
    let height = r.u32("height")?;
    let width = r.u32("width")?;
    // Each field takes at least 13 bytes; a larger count is garbage, not an allocation size.
    let n_fields = r.count("fields", 13)?;
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
    let data = r.bytes("data")?;
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
