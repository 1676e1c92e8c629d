"""Writes the hand-made seeds of fuzz/corpus/<target>/ (seed-*); the rest of each corpus is what
libFuzzer kept from our runs, minimised with `-merge=1`. Standard library only; run from
anywhere: python3 fuzz/make_seeds.py
"""

import math
import random
import shutil
import struct
from pathlib import Path

FUZZ = Path(__file__).resolve().parent
ROOT = FUZZ.parent
CORPUS = FUZZ / "corpus"
rng = random.Random(6)


def put(target, name, data):
    d = CORPUS / target
    d.mkdir(parents=True, exist_ok=True)
    (d / f"seed-{name}").write_bytes(data if isinstance(data, bytes) else data.encode())


def xyzt(n):
    return [(1.0 + i / 8, -i / 4, 0.5, i / 32) for i in range(n)]


def bin_seeds():
    pts = b"".join(struct.pack("<4f", x, y, z, 0.5) for x, y, z, _ in xyzt(4))
    put("bin", "4-points", pts)
    kitti = (ROOT / "fixtures/kitti-05-reduced/velodyne/000000.bin").read_bytes()
    put("bin", "kitti-64-points", kitti[: 64 * 16])
    put("bin", "nan-inf", struct.pack("<8f", math.nan, math.inf, -math.inf, 0, 1e38, -0.0, 1, 2))


def ply_seeds():
    pts = xyzt(3)
    head = "ply\nformat {}\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    text = head.format("ascii 1.0") + "property double time\nend_header\n"
    text += "".join(f"{x} {y} {z} {t}\n" for x, y, z, t in pts)
    put("ply", "ascii-time", text)
    for fmt, e in (("binary_little_endian 1.0", "<"), ("binary_big_endian 1.0", ">")):
        h = head.format(fmt) + "property uchar intensity\nproperty float t\nend_header\n"
        body = b"".join(struct.pack(e + "3fBf", x, y, z, 7, t) for x, y, z, t in pts)
        put("ply", fmt.split()[0], h.encode() + body)
    # An element before the vertices, and a list property.
    h = ("ply\nformat ascii 1.0\ncomment x\nelement camera 1\nproperty int id\n"
         "element vertex 2\nproperty double x\nproperty double y\nproperty double z\n"
         "element face 1\nproperty list uchar int vertex_indices\nend_header\n")
    put("ply", "elements", h + "5\n1 2 3\n4 5 6\n3 0 1 1\n")


def pcd_seeds():
    pts = xyzt(3)

    def header(fields, size, typ, data):
        return (f"# .PCD v0.7\nVERSION 0.7\nFIELDS {fields}\nSIZE {size}\nTYPE {typ}\n"
                f"COUNT {' '.join('1' * len(fields.split()))}\nWIDTH 3\nHEIGHT 1\n"
                f"VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA {data}\n")

    text = header("x y z time", "4 4 4 8", "F F F F", "ascii")
    text += "".join(f"{x} {y} {z} {t}\n" for x, y, z, t in pts)
    put("pcd", "ascii-time", text)
    h = header("x y z intensity t", "4 4 4 1 4", "F F F U U", "binary")
    body = b"".join(struct.pack("<3fBI", x, y, z, 9, int(t * 1e6)) for x, y, z, t in pts)
    put("pcd", "binary-t", h.encode() + body)
    h = header("x y z", "8 8 8", "F F F", "binary_compressed")
    put("pcd", "compressed", h.encode() + b"\0" * 16)


def timestamps_seeds():
    put("timestamps", "stamps-bin", b"".join(struct.pack("<d", i * 1e-4) for i in range(6)))
    times = (ROOT / "fixtures/kitti-05-reduced/times.txt").read_text().splitlines()[:4]
    put("timestamps", "times-txt", "\n".join(times) + "\n\n")


def poses_seeds():
    lines = (ROOT / "fixtures/kitti-05-reduced/poses.txt").read_text().splitlines()[:3]
    put("poses_text", "kitti", "\n".join(lines) + "\n")
    put("poses_text", "tum", "# t x y z qx qy qz qw\n1317384506.40 1 2 3 0 0 0 1\n"
        "1317384506.50 1.5 2 3 0.0087 0 0 0.99996\n")
    put("poses_text", "calib", (ROOT / "fixtures/kitti-05-reduced/calib.txt").read_text())


# PointCloud2 bodies; the target's first byte picks the serialization (even: ROS 1, odd: CDR).
FIELDS = [("x", 0, 7), ("y", 4, 7), ("z", 8, 7), ("intensity", 16, 7), ("t", 20, 7), ("ring", 24, 4)]


def cloud_data(n, step):
    out = b""
    for x, y, z, t in xyzt(n):
        p = struct.pack("<3f4xffH", x, y, z, 100.0, t, 3)
        out += p + b"\0" * (step - len(p))
    return out


def ros1_body(n=4, step=32, height=1):
    s = lambda b: struct.pack("<I", len(b)) + b
    body = struct.pack("<3I", 7, 1_700_000_000, 5) + s(b"lidar")
    body += struct.pack("<III", height, n, len(FIELDS))
    for name, off, dt in FIELDS:
        body += s(name.encode()) + struct.pack("<IBI", off, dt, 1)
    data = cloud_data(n * height, step)
    body += struct.pack("<BIII", 0, step, step * n, len(data)) + data + b"\0"
    return body


class Cdr:
    def __init__(self):
        self.b = b""

    def align(self, k):
        self.b += b"\0" * (-len(self.b) % k)

    def u32(self, v):
        self.align(4)
        self.b += struct.pack("<I", v)

    def u8(self, v):
        self.b += bytes([v])

    def string(self, s):
        self.u32(len(s) + 1)
        self.b += s.encode() + b"\0"


def cdr_body(n=4, step=32):
    c = Cdr()
    c.u32(1_700_000_000)
    c.u32(5)
    c.string("lidar")
    c.u32(1)
    c.u32(n)
    c.u32(len(FIELDS))
    for name, off, dt in FIELDS:
        c.string(name)
        c.u32(off)
        c.u8(dt)
        c.u32(1)
    c.u8(0)
    c.u32(step)
    c.u32(step * n)
    data = cloud_data(n, step)
    c.u32(len(data))
    c.b += data
    c.u8(0)
    return b"\x00\x01\x00\x00" + c.b


def pointcloud2_seeds():
    put("pointcloud2", "ros1", b"\0" + ros1_body())
    put("pointcloud2", "ros1-organized", b"\0" + ros1_body(n=2, height=2))
    put("pointcloud2", "cdr", b"\1" + cdr_body())


def container_seeds():
    for stem in ("ouster", "abs_time", "xyz64", "two_topics", "bad_step", "truncated"):
        for ext, target in ((".bag", "rosbag"), (".mcap", "mcap")):
            d = CORPUS / target
            d.mkdir(parents=True, exist_ok=True)
            shutil.copy(ROOT / "fixtures/bags" / f"{stem}{ext}", d / f"seed-{stem}{ext}")


class Ser:
    """ROS 1 (packed) or little-endian CDR (aligned from after its 4-byte header)."""

    def __init__(self, ros1):
        self.ros1 = ros1
        self.b = b"" if ros1 else b"\x00\x01\x00\x00"

    def align(self, k):
        if not self.ros1:
            self.b += b"\0" * (-(len(self.b) - 4) % k)

    def put(self, fmt, v):
        self.align(struct.calcsize(fmt))
        self.b += struct.pack("<" + fmt, v)

    def string(self, s):
        data = s.encode() + (b"" if self.ros1 else b"\0")
        self.put("I", len(data))
        self.b += data

    def header(self, ns):
        if self.ros1:
            self.put("I", 7)
        self.put("I", ns // 10**9)
        self.put("I", ns % 10**9)
        self.string("lidar")


def packet_scan(ros1, packets, fixed=None, sized=False):
    """A header, then packets of a stamp and a fixed array or a uint8[] (and a size)."""
    m = Ser(ros1)
    m.header(1_700_000_000 * 10**9)
    m.put("I", len(packets))
    for k, p in enumerate(packets):
        m.put("I", 1_700_000_000)
        m.put("I", k * 1000)
        if fixed:
            m.b += p.ljust(fixed, b"\0")
        else:
            m.put("I", len(p))
            m.b += p
        if sized:
            m.put("I", len(p))
    return m.b


def custom_msg(ros1, n, point_num=None):
    m = Ser(ros1)
    m.header(1_700_000_000 * 10**9)
    m.put("Q", 1_700_000_000 * 10**9)
    m.put("I", n if point_num is None else point_num)
    m.b += bytes([1, 0, 0, 0])
    m.put("I", n)
    for i in range(n):
        m.put("I", i * 5000)
        for v in (1.0 + i, -0.5 * i, 0.25):
            m.put("f", v)
        m.b += bytes([10 * i % 256, 0, i % 4])
    return m.b


def driver_seeds():
    velodyne = [bytes(range(256)) * 4 + bytes(182)] * 2
    hesai = [b"\xee\xff\x06\x01" + bytes(1076)] * 3
    for ros1, bit in ((True, 0), (False, 1)):
        name = "ros1" if ros1 else "cdr"
        put("driver_messages", f"velodyne-{name}", bytes([bit]) + packet_scan(ros1, velodyne, 1206))
        put("driver_messages", f"pandar-{name}", bytes([2 | bit]) + packet_scan(ros1, hesai, 1500, True))
        put("driver_messages", f"pandar-sized-{name}",
            bytes([2 | bit]) + packet_scan(ros1, hesai, None, True))
        ouster = Ser(ros1)
        ouster.put("I", 48)
        ouster.b += bytes(range(48))
        put("driver_messages", f"ouster-{name}", bytes([6 | bit]) + ouster.b)
        put("driver_messages", f"custom-{name}", bytes([12 | bit]) + custom_msg(ros1, 5))
        msop = [b"\x55\xaa\x05\x5a" + bytes(1244)] * 2
        put("driver_messages", f"robosense-{name}", bytes([8 | bit]) + packet_scan(ros1, msop, 1248))
        info = Ser(ros1)
        info.string("Helios")
        info.put("I", 1_700_000_000)
        info.put("I", 0)
        info.b += b"\xa5\xff\x00\x5a\x11\x11\x55\x55" + bytes(1240)
        put("driver_messages", f"robosense-info-{name}", bytes([10 | bit]) + info.b)
    put("driver_messages", "nebula-cdr", bytes([5]) + packet_scan(False, hesai + velodyne))
    put("driver_messages", "custom-point-num", bytes([13]) + custom_msg(False, 3, 4))


def db3(path, topics, messages):
    """A ROS 2 sqlite3 bag file as rosbag2 (Humble) lays it out."""
    import sqlite3
    path.unlink(missing_ok=True)
    db = sqlite3.connect(path)
    db.executescript(
        "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY,ros_distro TEXT NOT NULL);"
        "CREATE TABLE metadata(id INTEGER PRIMARY KEY,metadata_version INTEGER NOT NULL,"
        "metadata TEXT NOT NULL);"
        "CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type TEXT NOT NULL,"
        "serialization_format TEXT NOT NULL,offered_qos_profiles TEXT NOT NULL);"
        "CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER NOT NULL,"
        "timestamp INTEGER NOT NULL, data BLOB NOT NULL);"
        "CREATE INDEX timestamp_idx ON messages (timestamp ASC);")
    for k, (name, tp) in enumerate(topics):
        db.execute("INSERT INTO topics VALUES (?, ?, ?, 'cdr', '')", (k + 1, name, tp))
    for topic, ns, data in messages:
        db.execute("INSERT INTO messages (topic_id, timestamp, data) VALUES (?, ?, ?)",
                   (topic + 1, ns, data))
    db.commit()
    db.close()


def db3_seeds():
    d = CORPUS / "db3"
    d.mkdir(parents=True, exist_ok=True)
    t0 = 1_700_000_000 * 10**9
    db3(d / "seed-clouds.db3", [("/points", "sensor_msgs/msg/PointCloud2")],
        [(0, t0 + k * 10**8, cdr_body()) for k in range(3)])
    db3(d / "seed-livox.db3", [("/livox/lidar", "livox_ros_driver2/msg/CustomMsg")],
        [(0, t0 + k * 10**8, custom_msg(False, 4)) for k in range(3)])
    hesai = [b"\xee\xff\x06\x01" + bytes(1076)] * 2
    db3(d / "seed-pandar.db3", [("/pandar_packets", "pandar_msgs/msg/PandarScan")],
        [(0, t0, packet_scan(False, hesai, 1500, True))])
    shutil.copy(ROOT / "fixtures/nebula-xt32/bag/xt32-sector_0.db3", d / "seed-nebula-xt32.db3")


def core_frame_seed(kind, deskew, moves):
    """A room of about 150 points, then `moves` small motions of it (the layout the target
    reads: see fuzz_targets/core_frame.rs)."""
    b = bytes([kind, 0, 0, 0, 20, deskew, 15, 0, 0, 0])
    b += struct.pack("<5H", 511, 255, 127, 255, 1023)
    pts = []
    for a in range(8):
        for c in range(8):
            pts.append((a - 4 + rng.random() * 0.5, c - 4 + rng.random() * 0.5, -1.5))
        for k in range(4):
            pts.append((a - 4 + rng.random() * 0.5, 4.2, k * 0.6 - 1.5))
            pts.append((4.3, a - 4 + rng.random() * 0.5, k * 0.6 - 1.5))
    b += bytes([4]) + struct.pack("<H", len(pts))
    for p in pts:
        for v in p:
            b += bytes([0]) + struct.pack("<h", round(v * 256))
    b += bytes([0])  # no stamps
    for _ in range(moves):
        b += bytes([1]) + struct.pack("<6b", *(rng.randint(-60, 60) for _ in range(6)))
        b += bytes([2, 0]) + struct.pack("<h", 0) + bytes([0]) + struct.pack("<h", 3)  # a ramp
    return b


def core_frame_seeds():
    put("core_frame", "room-f64", core_frame_seed(0, 0, 5))
    put("core_frame", "room-f32-deskew", core_frame_seed(2, 1, 5))


def pcap_records(path, count):
    """The global header and the first `count` records of a classic pcap file."""
    b = path.read_bytes()
    at = 24
    for _ in range(count):
        at += 16 + int.from_bytes(b[at + 8:at + 12], "little")
    return b[:at]


def udp_payloads(path, port):
    """UDP payloads to `port` of an Ethernet/IPv4 pcap (no options, no fragments)."""
    b = path.read_bytes()
    at, out = 24, []
    while at + 16 <= len(b):
        incl = int.from_bytes(b[at + 8:at + 12], "little")
        f = b[at + 16:at + 16 + incl]
        if len(f) > 42 and f[12:14] == b"\x08\x00" and int.from_bytes(f[36:38], "big") == port:
            out.append(f[42:])
        at += 16 + incl
    return out


def ouster_packet(profile, beams, fid, first):
    """A lidar packet of the fuzz target's small sensor (4 columns, ranges of 8 m)."""
    pixel = {0: 12, 1: 12, 2: 16, 3: 4}[profile]
    cols = b""
    for m in range(first, first + 4):
        ts = struct.pack("<Q", 10**9 + m * 10**5)
        px = b"".join(
            (struct.pack("<I", 8000) if profile != 3 else struct.pack("<H", 1000))
            + bytes(pixel - (4 if profile != 3 else 2)) for _ in range(beams))
        if profile == 0:
            cols += ts + struct.pack("<HHI", m, fid, 0) + px + b"\xff" * 4
        else:
            cols += ts + struct.pack("<HH", m, 1) + px
    if profile == 0:
        return cols
    return struct.pack("<HH", 1, fid) + bytes(28) + cols + bytes(32)


def robosense_capture(lasers, span, mode, shape, packet_us, azimuth, msop_bytes):
    """A spinning Robosense DIFOP packet with `lasers` angles evenly over `span` degrees and
    `mode` (byte, value), then two MSOP packets `packet_us` apart of `shape` (blocks,
    channels), the block azimuths `azimuth(n, k)`, `msop_bytes` set in each."""
    difop = bytearray(1248)
    difop[:8] = bytes([0xA5, 0xFF, 0x00, 0x5A, 0x11, 0x11, 0x55, 0x55])
    difop[8:10] = (600).to_bytes(2, "big")
    difop[mode[0]] = mode[1]
    for i in range(lasers):
        v = round((span[0] + (span[1] - span[0]) * i / (lasers - 1)) * 100)
        difop[468 + 3 * i] = int(v < 0)
        difop[469 + 3 * i : 471 + 3 * i] = abs(v).to_bytes(2, "big")
    out = b"\0\0" + bytes(difop)
    blocks, channels = shape
    for n in range(2):
        msop = bytearray(1248)
        msop[:4] = bytes([0x55, 0xAA, 0x05, 0x5A])
        for at, v in msop_bytes.items():
            msop[at] = v
        msop[20:26] = (1_704_067_200).to_bytes(6, "big")
        msop[26:30] = (n * packet_us).to_bytes(4, "big")
        for k in range(blocks):
            at = 42 + (4 + 3 * channels) * k
            msop[at : at + 2] = b"\xff\xee"
            msop[at + 2 : at + 4] = azimuth(n, k).to_bytes(2, "big")
            for c in range(channels):
                msop[at + 4 + 3 * c : at + 6 + 3 * c] = (2000 + 37 * c).to_bytes(2, "big")
                msop[at + 6 + 3 * c] = 100
        out += b"\0\0" + bytes(msop)
    return out


def robosense_helios():
    """A Helios DIFOP packet with its angles, then two MSOP packets of twelve blocks."""
    return robosense_capture(32, (-55, 15), (300, 0x04), (12, 32), 667,
                             lambda n, k: (n * 12 + k) * 20, {})


def robosense_airy():
    """An RS-Airy DIFOP packet (96 lasers, mounted normally), then two MSOP packets of eight
    blocks of 48 channels (96-channel mode, single return)."""
    return robosense_capture(96, (-45, 45), (289, 0), (8, 48), 444,
                             lambda n, k: (n * 4 + k // 2) * 40, {17: 0x01, 32: 0x02})


def sensor_seeds():
    data = ROOT.parent / "shared" / "data" / "sensors" / "velodyne"
    packets = udp_payloads(data / "velodyne_vlp16.pcap", 2368)[:3]
    put("velodyne_packets", "hdl32e-3-packets", bytes([0]) + b"".join(b"\0\0" + p for p in packets))
    dual = [p[:1204] + bytes([0x39, 0x22]) for p in packets]
    put("velodyne_packets", "vlp16-dual-cut", bytes([0x05 | 8 << 3]) + b"".join(b"\0\0" + p for p in dual))
    for profile, name in enumerate(["legacy", "single", "dual", "lb"]):
        head = bytes([profile | 1 << 2, 0, 63, 10])
        body = b"".join(bytes([0]) + ouster_packet(profile, 2, fid, first)
                        for fid in (3, 4) for first in range(0, 64, 4))
        put("ouster_packets", name, head + body)
    vls = udp_payloads(ROOT / "fixtures" / "velodyne-nebula" / "vls128-sector.pcap", 2368)[:3]
    put("velodyne_wide_packets", "vls128-3-packets", bytes([2, 0]) + b"".join(b"\0\0" + p for p in vls))
    # The same packets as an HDL-64E's: upper and lower blocks by turns, no product byte.
    hdl = [bytes(b ^ (0x33 if k % 200 == 101 else 0) for k, b in enumerate(p[:1200])) + p[1200:1204] + b"\0\0"
           for p in vls]
    put("velodyne_wide_packets", "hdl64e-3-packets", bytes([1, 3]) + b"".join(b"\0\0" + p for p in hdl))
    put("robosense_packets", "helios-difop-msop", bytes([3]) + robosense_helios())
    put("robosense_packets", "airy-difop-msop", bytes([6]) + robosense_airy())
    m1 = bytearray(1210)
    m1[:4] = bytes([0x55, 0xAA, 0x5A, 0xA5])
    m1[4:6] = (1).to_bytes(2, "big")
    m1[8] = 0x04
    for k in range(25):
        for c in range(5):
            at = 32 + 47 * k + 2 + 9 * c
            m1[at : at + 6] = (2000 + c).to_bytes(2, "big") + (32768 + k).to_bytes(2, "big") + (32768 - c).to_bytes(2, "big")
    put("robosense_packets", "m1-one-packet", bytes([0x80]) + b"\0\0" + bytes(m1))
    hesai = udp_payloads(data.parent / "hesai" / "hesai-xt32-small.pcap", 2368)[:3]
    put("hesai_packets", "xt32-3-packets", bytes([0]) + b"".join(b"\0\0" + p for p in hesai))
    qt128 = udp_payloads(ROOT / "fixtures" / "hesai-qt128" / "qt128-sector.pcap", 2368)[:3]
    put("hesai_packets", "qt128-3-packets", bytes([1 << 1 | 8]) + b"".join(b"\0\0" + p for p in qt128))
    put("hesai_packets", "ot128-4-packets", bytes([3 << 1]) + b"".join(
        b"\0\0" + hesai_1_4_packet(k) for k in range(4)))
    for k, model in enumerate(["40p", "64", "qt64", "xt16", "xt32m"]):
        pkts = udp_payloads(ROOT / "fixtures" / "hesai-nebula" / f"{model}.pcap", 2368)[:3]
        put("hesai_fixed_packets", f"{model}-3-packets",
            bytes([k << 1]) + b"".join(b"\0\0" + p for p in pkts))
    put("hesai_fixed_packets", "at128-4-packets", bytes([5 << 1]) + b"".join(
        b"\0\0" + hesai_at128_packet(k) for k in range(4)))
    livox = udp_payloads(data.parent / "livox" / "livox_tele15_small.pcap", 56001)[:6]
    put("livox_packets", "tele15-6-packets",
        bytes([0]) + b"".join(struct.pack("<H", 0x8000 | len(p)) + p for p in livox))
    put("livox_packets", "mid360-sdk2-packets", bytes([2 | 4]) + b"".join(
        struct.pack("<H", 0x8000 | len(p)) + p for p in livox_sdk2_packets()))
    put("sensor_pcap", "vli16-one-packet", (data / "VLI-16-one-packet.pcap").read_bytes())
    put("sensor_pcap", "vlp16-5-records", pcap_records(data / "velodyne_vlp16.pcap", 5))


def hesai_1_4_packet(k):
    """A protocol 1.4 (Pandar128, OT128) packet of 861 bytes: sequence, IMU and safety
    flagged, standard mode, dual return 0x39, the k-th of a 10 Hz turn's 0.2 degree steps."""
    head = bytes([0xEE, 0xFF, 1, 4, 0, 0, 128, 2, 1, 4, 2, 0x07])
    blocks = b"".join(struct.pack("<H", 20 * k) + b"".join(
        struct.pack("<HB", 500 + c + 7 * b, c) for c in range(128)) for b in range(2))
    tail = bytes(9) + struct.pack("<HBBH", 0b0110 << 12, 2, 0x39, 600)
    tail += bytes([124, 10, 30, 7, 36, 29]) + struct.pack("<IB", 55 * k, 0x42)
    return head + blocks + bytes(4 + 17) + tail + struct.pack("<I", k) + bytes(22 + 4)


def hesai_at128_packet(k):
    """A PandarAT128 (protocol 4.3) packet of 1086 bytes, single strongest return: the k-th
    after motor angle 40 degrees, 0.1 degree (two firings) a packet, in the fuzz target's
    frame 0; the last packet steps into frame 1 (motor 140 degrees on)."""
    head = bytes([0xEE, 0xFF, 4, 3, 0, 0, 128, 2, 0, 4, 1, 1])
    motor = (40 * 25_600 + 2_560 * k) if k < 3 else 150 * 25_600
    blocks = b"".join(struct.pack("<HB", (motor + 1_280 * b) >> 8, (motor + 1_280 * b) & 0xFF)
                      + b"".join(struct.pack("<HBB", 800 + c + 9 * b, c, 0) for c in range(128))
                      for b in range(2))
    tail = bytes(18) + struct.pack("<HIBB", 200, 83 * k, 0x37, 0x42)
    tail += bytes([0]) + (1_704_067_200).to_bytes(5, "big") + struct.pack("<I", k) + bytes(4)
    return head + blocks + bytes(4) + tail


def livox_sdk2_packets():
    """Livox SDK 2 (Mid-360) packets: each point data type (1, 2, 3, 0x11) and an IMU sample,
    96 points 5 us apart, CRC-32 over the timestamp and data as the sensor writes it."""
    import zlib
    out, t = [], 1_000_000_000
    sizes = {0: 24, 1: 14, 2: 8, 3: 10, 0x11: 28}
    for data_type in (1, 2, 3, 0x11, 0):
        n = 1 if data_type == 0 else 96
        body = bytes(rng.randrange(256) for _ in range(sizes[data_type] * n))
        stamped = struct.pack("<Q", t) + body
        head = struct.pack("<BHHHHBBB12s", 0, 36 + len(body), 4800, n, len(out), 0, data_type, 0,
                           bytes(12))
        out.append(head + struct.pack("<I", zlib.crc32(stamped)) + stamped)
        t += 480_000
    return out


def ethernet_frames(path, count):
    """The first `count` link frames of a classic pcap file."""
    b = path.read_bytes()
    at, out = 24, []
    while at + 16 <= len(b) and len(out) < count:
        incl = int.from_bytes(b[at + 8:at + 12], "little")
        out.append(b[at + 16:at + 16 + incl])
        at += 16 + incl
    return out


def ipv4_fragments(payload, ident, step):
    """IPv4 packets (no checksum) carrying UDP `payload` to port 2368 in fragments."""
    body = struct.pack(">HHHH", 2368, 2368, 8 + len(payload), 0) + payload
    out = []
    for k in range(0, len(body), step):
        piece = body[k:k + step]
        flags = (0x2000 if k + step < len(body) else 0) | (k // 8)
        out.append(struct.pack(">BBHHHBBH4s4s", 0x45, 0, 20 + len(piece), ident, flags, 64, 17,
                               0, bytes([192, 168, 1, 201]), bytes([192, 168, 1, 2])) + piece)
    return out


def capture_seeds():
    """The `capture` target: reassembly ops, a pcapng of three interfaces, a pcap of SLL2."""
    ops = b""
    for key, offset, more, length, t in [(1, 0, 1, 8, 0), (2, 0, 1, 8, 1), (1, 8, 0, 3, 2),
                                         (1, 1, 1, 8, 3), (1, 1, 1, 8, 3), (2, 1, 1, 9, 4),
                                         (2, 0, 1, 8, 5000), (0x81, 0, 0, 4, 6)]:
        ops += bytes([key]) + struct.pack("<H", offset) + bytes([more << 7 | length]) \
            + struct.pack("<H", t)
    put("capture", "reassembly", b"\0" + ops)
    data = ROOT.parent / "shared" / "data" / "sensors" / "velodyne"
    frames = ethernet_frames(data / "velodyne_vlp16.pcap", 4)
    ips = [f[14:] for f in frames if f[12:14] == b"\x08\x00"]
    sll2 = lambda ip: b"\x08\x00" + bytes(6) + b"\x00\x01\x00\x06" + bytes(8) + ip
    # Interfaces: Ethernet in microseconds; SLL2 in nanoseconds 100 s on; raw IP in 2^-20 s.
    head = bytes([2]) + bytes([0, 255, 6, 0]) + bytes([2, 255, 9, 101]) + bytes([3, 255, 0x94, 0])
    epbs = b""
    for i, f in enumerate(frames):
        for iface, pkt in ((0, f), (1, sll2(f[14:])), (2, f[14:])):
            epbs += bytes([iface]) + struct.pack("<Q", 10**6 * i + 5) + struct.pack("<H", len(pkt)) \
                + b"\0\0\0" + pkt
    for frag in ipv4_fragments(bytes(range(256)) * 12, 7, 1480):
        epbs += bytes([2]) + struct.pack("<Q", 9) + struct.pack("<H", len(frag)) + b"\0\0\0" + frag
    put("capture", "pcapng-3-interfaces", bytes([1]) + head + epbs)
    records = b"".join(struct.pack("<H", len(sll2(ip))) + sll2(ip) for ip in ips)
    put("capture", "pcap-sll2", bytes([2 + 3 * 2]) + records)


def prior_map_file(tiles, voxel=1.0, tile=20.0, per_voxel=4, frame=b"map"):
    """A map file (core/src/prior_map.rs's format, version 2) of `tiles`: {(i, j): [(x, y, z)
    offsets]}, each tile's points sorted by voxel (of the stored f32 point) and trimmed to
    `per_voxel` a voxel, as `prior_map::arrange_tile` does."""
    import zlib
    f32 = lambda v: struct.unpack("<f", struct.pack("<f", v))[0]

    def arranged(i, j, pts):
        def key(p):
            x, y, z = (f32(c) for c in p)
            return (math.floor((i * tile + x) / voxel), math.floor((j * tile + y) / voxel),
                    math.floor(z / voxel))
        out, runs = [], {}
        for p in sorted(pts, key=lambda p: (key(p), *(f32(c) for c in p))):
            runs[key(p)] = runs.get(key(p), 0) + 1
            if runs[key(p)] <= per_voxel:
                out.append(p)
        return out

    tiles = {k: arranged(*k, v) for k, v in tiles.items()}
    cap = max((len(p) for p in tiles.values()), default=1) or 1
    keys = sorted(tiles)
    index = b"".join(struct.pack("<iiI", i, j, len(tiles[(i, j)])) for i, j in keys)
    records = b""
    for i, j in keys:
        pts = b"".join(struct.pack("<3f", *p) for p in tiles[(i, j)])
        pts += bytes(12 * cap - len(pts))
        head = struct.pack("<iiI", i, j, len(tiles[(i, j)]))
        records += head + struct.pack("<I", zlib.crc32(head + pts)) + pts
    h = b"KOMAP\0\0\0" + struct.pack("<II", 2, 0) + struct.pack("<dd", voxel, tile)
    h += struct.pack("<IIII", per_voxel, cap, len(keys), zlib.crc32(index))
    h += frame.ljust(16, b"\0") + bytes(60)
    h += struct.pack("<I", zlib.crc32(h))
    return h + index + records


def prior_map_seeds():
    wall = [(x / 2, 5.0, z / 2) for x in range(0, 30) for z in range(0, 6)]
    ground = [(x / 2, y / 2, 0.0) for x in range(0, 30, 3) for y in range(0, 30, 3)]
    put("prior_map", "two-tiles", prior_map_file({(0, 0): wall + ground, (-1, 0): ground}))
    put("prior_map", "empty", prior_map_file({}))


def main():
    for make in (bin_seeds, ply_seeds, pcd_seeds, timestamps_seeds, poses_seeds,
                 pointcloud2_seeds, container_seeds, core_frame_seeds, sensor_seeds,
                 capture_seeds, driver_seeds, db3_seeds, prior_map_seeds):
        make()
    for d in sorted(CORPUS.iterdir()):
        print(f"{d.name}: {len(list(d.iterdir()))} seeds")


if __name__ == "__main__":
    main()
