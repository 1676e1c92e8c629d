//! Messages written field by field from their definitions, ROS 1 or CDR, for the tests of the
//! readers: independent of [`serial`](super::serial), which reads them.

use super::pointcloud2::fixture::RawCloud;

/// Appends values with ROS 1's or CDR's rules (CDR little-endian unless `big`).
pub struct Out {
    pub bytes: Vec<u8>,
    cdr: bool,
    big: bool,
}

impl Out {
    pub fn new(ros1: bool) -> Self {
        Self::with_order(ros1, false)
    }

    pub fn with_order(ros1: bool, big: bool) -> Self {
        let bytes = match (ros1, big) {
            (true, _) => Vec::new(),
            (false, false) => vec![0, 1, 0, 0],
            (false, true) => vec![0, 0, 0, 0],
        };
        Self {
            bytes,
            cdr: !ros1,
            big,
        }
    }

    fn align(&mut self, n: usize) {
        if self.cdr {
            while (self.bytes.len() - 4) % n != 0 {
                self.bytes.push(0);
            }
        }
    }

    fn put<const N: usize>(&mut self, mut le: [u8; N]) {
        self.align(N);
        if self.big {
            le.reverse();
        }
        self.bytes.extend_from_slice(&le);
    }

    pub fn u8(&mut self, v: u8) {
        self.bytes.push(v);
    }

    pub fn u32(&mut self, v: u32) {
        self.put(v.to_le_bytes());
    }

    pub fn u64(&mut self, v: u64) {
        self.put(v.to_le_bytes());
    }

    pub fn f32(&mut self, v: f32) {
        self.put(v.to_le_bytes());
    }

    pub fn raw(&mut self, b: &[u8]) {
        self.bytes.extend_from_slice(b);
    }

    pub fn string(&mut self, s: &str) {
        let nul = usize::from(self.cdr);
        self.u32((s.len() + nul) as u32);
        self.raw(s.as_bytes());
        if self.cdr {
            self.u8(0);
        }
    }

    pub fn bytes(&mut self, b: &[u8]) {
        self.u32(b.len() as u32);
        self.raw(b);
    }

    pub fn time(&mut self, ns: u64) {
        self.u32((ns / 1_000_000_000) as u32);
        self.u32((ns % 1_000_000_000) as u32);
    }

    pub fn header(&mut self, ns: u64) {
        if !self.cdr {
            self.u32(7); // seq
        }
        self.time(ns);
        self.string("lidar");
    }
}

/// `velodyne_msgs/VelodyneScan` of `packets` (stamp ns, 1206 bytes each).
pub fn velodyne_scan(ros1: bool, stamp: u64, packets: &[(u64, Vec<u8>)]) -> Vec<u8> {
    let mut o = Out::new(ros1);
    o.header(stamp);
    o.u32(packets.len() as u32);
    for (t, data) in packets {
        assert_eq!(data.len(), 1206);
        o.time(*t);
        o.raw(data);
    }
    o.bytes
}

/// `pandar_msgs/PandarScan` as nebula defines it: `uint8[1500] data`, then `size`.
pub fn pandar_scan(ros1: bool, stamp: u64, packets: &[(u64, Vec<u8>)]) -> Vec<u8> {
    let mut o = Out::new(ros1);
    o.header(stamp);
    o.u32(packets.len() as u32);
    for (t, data) in packets {
        o.time(*t);
        let mut fixed = data.clone();
        fixed.resize(1500, 0);
        o.raw(&fixed);
        o.u32(data.len() as u32);
    }
    o.bytes
}

/// `PandarScan` whose packets' data is a `uint8[]` (Hesai's own drivers).
pub fn pandar_scan_sized(ros1: bool, stamp: u64, packets: &[(u64, Vec<u8>)]) -> Vec<u8> {
    let mut o = Out::new(ros1);
    o.header(stamp);
    o.u32(packets.len() as u32);
    for (t, data) in packets {
        o.time(*t);
        o.bytes(data);
        o.u32(data.len() as u32);
    }
    o.bytes
}

/// `nebula_msgs/NebulaPackets`.
pub fn nebula_packets(stamp: u64, packets: &[(u64, Vec<u8>)]) -> Vec<u8> {
    let mut o = Out::new(false);
    o.header(stamp);
    o.u32(packets.len() as u32);
    for (t, data) in packets {
        o.time(*t);
        o.bytes(data);
    }
    o.bytes
}

/// Ouster's `PacketMsg`.
pub fn ouster_packet(ros1: bool, data: &[u8]) -> Vec<u8> {
    let mut o = Out::new(ros1);
    o.bytes(data);
    o.bytes
}

/// `std_msgs/String`.
pub fn text(ros1: bool, s: &str) -> Vec<u8> {
    let mut o = Out::new(ros1);
    o.string(s);
    o.bytes
}

/// A Livox `CustomMsg` whose `point_num` says `point_num` (normally `points.len()`).
pub fn custom_msg(
    ros1: bool,
    big: bool,
    timebase: u64,
    points: &[(u32, [f32; 3], u8, u8, u8)],
    point_num: u32,
) -> Vec<u8> {
    let mut o = Out::with_order(ros1, big);
    o.header(timebase);
    o.u64(timebase);
    o.u32(point_num);
    o.u8(3); // lidar_id
    o.raw(&[0, 0, 0]);
    o.u32(points.len() as u32);
    for &(offset, xyz, reflectivity, tag, line) in points {
        o.u32(offset);
        for v in xyz {
            o.f32(v);
        }
        o.u8(reflectivity);
        o.u8(tag);
        o.u8(line);
    }
    o.bytes
}

/// Writes a ROS 2 sqlite3 bag file as rosbag2 (Humble) lays it out: `topics` (name, type),
/// then `messages` (topic's place in `topics`, receive time ns, data).
pub fn write_db3(
    path: &std::path::Path,
    topics: &[(&str, &str)],
    messages: &[(usize, u64, Vec<u8>)],
) {
    let _ = std::fs::remove_file(path);
    let conn = rusqlite::Connection::open(path).unwrap();
    conn.execute_batch(
        "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY,ros_distro TEXT NOT NULL);
         CREATE TABLE metadata(id INTEGER PRIMARY KEY,metadata_version INTEGER NOT NULL,metadata TEXT NOT NULL);
         CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type TEXT NOT NULL,serialization_format TEXT NOT NULL,offered_qos_profiles TEXT NOT NULL);
         CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER NOT NULL,timestamp INTEGER NOT NULL, data BLOB NOT NULL);
         CREATE INDEX timestamp_idx ON messages (timestamp ASC);",
    )
    .unwrap();
    for (k, (name, tp)) in topics.iter().enumerate() {
        conn.execute(
            "INSERT INTO topics VALUES (?1, ?2, ?3, 'cdr', '')",
            rusqlite::params![k as i64 + 1, name, tp],
        )
        .unwrap();
    }
    for (topic, t, data) in messages {
        conn.execute(
            "INSERT INTO messages (topic_id, timestamp, data) VALUES (?1, ?2, ?3)",
            rusqlite::params![*topic as i64 + 1, *t as i64, data],
        )
        .unwrap();
    }
}

/// The `metadata.yaml` rosbag2 writes for `files`, with `topics` (name, type, messages).
pub fn metadata_yaml(files: &[(&str, u64)], topics: &[(&str, &str, u64)]) -> String {
    let total: u64 = topics.iter().map(|t| t.2).sum();
    let mut s = format!(
        "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n  \
         message_count: {total}\n  topics_with_message_count:\n"
    );
    for (name, tp, n) in topics {
        s += &format!(
            "    - topic_metadata:\n        name: {name}\n        type: {tp}\n        \
             serialization_format: cdr\n        offered_qos_profiles: \"\"\n      \
             message_count: {n}\n"
        );
    }
    s += "  compression_format: \"\"\n  compression_mode: \"\"\n  relative_file_paths:\n";
    for (f, _) in files {
        s += &format!("    - {f}\n");
    }
    s += "  files:\n";
    for (f, n) in files {
        s += &format!("    - path: {f}\n      message_count: {n}\n");
    }
    s
}

/// CDR serialization of `c` written from the IDL: 4-byte encapsulation header, then every
/// primitive aligned to its size counted from the end of that header.
pub fn cdr_body(c: &RawCloud, big_endian: bool) -> Vec<u8> {
    struct W {
        b: Vec<u8>,
        big: bool,
    }
    impl W {
        fn u32(&mut self, v: u32) {
            while (self.b.len() - 4) % 4 != 0 {
                self.b.push(0);
            }
            let bytes = if self.big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            };
            self.b.extend_from_slice(&bytes);
        }
        fn string(&mut self, s: &str) {
            self.u32(s.len() as u32 + 1);
            self.b.extend_from_slice(s.as_bytes());
            self.b.push(0);
        }
    }
    let mut w = W {
        b: vec![0, if big_endian { 0 } else { 1 }, 0, 0],
        big: big_endian,
    };
    w.u32(c.sec);
    w.u32(c.nsec);
    w.string(&c.frame_id);
    w.u32(c.height);
    w.u32(c.width);
    w.u32(c.fields.len() as u32);
    for f in &c.fields {
        w.string(&f.name);
        w.u32(f.offset);
        w.b.push(f.datatype);
        w.u32(f.count);
    }
    w.b.push(u8::from(c.is_bigendian));
    w.u32(c.point_step);
    w.u32(c.row_step);
    w.u32(c.data.len() as u32);
    w.b.extend_from_slice(&c.data);
    w.b.push(u8::from(c.is_dense));
    w.b
}

/// A little-endian CDR `sensor_msgs/msg/Imu` stamped `ns`, angular velocity (k, 0, 0), frame id
/// `imu` (4 bytes with its NUL, which end 16 bytes after the encapsulation header: the f64 need
/// no padding).
pub fn imu_cdr(ns: u64, k: u32) -> Vec<u8> {
    let mut b = vec![0, 1, 0, 0];
    for v in [(ns / 1_000_000_000) as u32, (ns % 1_000_000_000) as u32, 4] {
        b.extend(v.to_le_bytes());
    }
    b.extend(b"imu\0");
    let mut block = [0.0f64; 37];
    block[13] = f64::from(k); // angular_velocity.x
    block[27] = 9.8; // linear_acceleration.z
    for v in block {
        b.extend(v.to_le_bytes());
    }
    b
}

/// nebula's `robosense_msgs/RobosenseScan`: each packet a stamp and a `uint8[1248]`.
pub fn robosense_scan(stamp: u64, packets: &[(u64, Vec<u8>)]) -> Vec<u8> {
    let mut o = Out::new(false);
    o.header(stamp);
    o.u32(packets.len() as u32);
    for (t, data) in packets {
        o.time(*t);
        let mut fixed = data.clone();
        fixed.resize(1248, 0);
        o.raw(&fixed);
    }
    o.bytes
}

/// nebula's `robosense_msgs/RobosenseInfoPacket`: the model's name and one packet.
pub fn robosense_info(model: &str, (t, data): (u64, &[u8])) -> Vec<u8> {
    let mut o = Out::new(false);
    o.string(model);
    o.time(t);
    o.raw(data);
    o.bytes
}
