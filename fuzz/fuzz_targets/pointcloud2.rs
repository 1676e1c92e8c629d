//! PointCloud2 payloads: the ROS 1 (`message::parse_ros1`) and CDR (`message::parse_cdr`)
//! serializations, and `pointcloud2::decode` on what they parse. The first byte picks the
//! serialization; a decoded cloud has `width * height` points and as many stamps, if any.
#![no_main]

use kiss_odom_io::ros::message::{parse_cdr, parse_ros1};
use kiss_odom_io::ros::pointcloud2::{decode, PointCloud2};
use libfuzzer_sys::fuzz_target;

fn check(cloud: &PointCloud2<'_>) {
    if let Ok(d) = decode(cloud) {
        assert_eq!(
            d.points.len() as u64,
            u64::from(cloud.width) * u64::from(cloud.height)
        );
        if let Some(s) = &d.stamps {
            assert_eq!(s.len(), d.points.len());
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&kind, body)) = data.split_first() else {
        return;
    };
    let parsed = if kind & 1 == 0 {
        parse_ros1(body)
    } else {
        parse_cdr(body)
    };
    if let Ok(cloud) = parsed {
        check(&cloud);
    }
});
