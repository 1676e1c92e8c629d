#!/usr/bin/env python3
"""A ROS 2 sqlite3 bag of `velodyne_msgs/msg/VelodyneScan` to a pcap of its packets.

Standard library only: each scan message's CDR (header: stamp, frame_id; packets[]: each a
stamp and 1206 data bytes) is unpacked and every packet written as an IPv4/UDP datagram to
port 2368 stamped with the packet's own stamp, which is what the capture reader takes.

    velodyne_bag_to_pcap.py BAG.db3 OUT.pcap [--first-scan N] [--scans M]
                            [--skip-packets K] [--packets P]

`--skip-packets` and `--packets` then keep P packets of the chosen scans from the K-th on
(how the fixtures in fixtures/velodyne-nebula/ were cut).
"""
import argparse
import sqlite3
import struct

PACKET_LEN = 1206


def scans(db):
    con = sqlite3.connect(db)
    topics = {i: (n, t) for i, n, t in con.execute("select id, name, type from topics")}
    rows = con.execute("select topic_id, timestamp, data from messages order by timestamp")
    for topic, stamp, data in rows:
        if topics[topic][1] == "velodyne_msgs/msg/VelodyneScan":
            yield stamp, data


def unpack_scan(cdr):
    """Packets (sec, nanosec, data) of one VelodyneScan in CDR (little-endian only)."""
    if cdr[1] not in (1, 3):
        raise ValueError("not little-endian CDR")
    body = memoryview(cdr)[4:]
    at = 8  # header stamp
    (n,) = struct.unpack_from("<I", body, at)
    at += 4 + n  # frame_id with its NUL
    at = (at + 3) & ~3
    (count,) = struct.unpack_from("<I", body, at)
    at += 4
    out = []
    for _ in range(count):
        at = (at + 3) & ~3
        sec, nsec = struct.unpack_from("<iI", body, at)
        at += 8
        out.append((sec, nsec, bytes(body[at : at + PACKET_LEN])))
        at += PACKET_LEN
    return out


def udp_frame(payload):
    udp = struct.pack(">HHHH", 2369, 2368, 8 + len(payload), 0) + payload
    ip = struct.pack(
        ">BBHHHBBH4s4s", 0x45, 0, 20 + len(udp), 0, 0x4000, 64, 17, 0,
        bytes([192, 168, 1, 201]), bytes([255, 255, 255, 255]),
    )
    eth = b"\xff" * 6 + b"\x60\x76\x88\x00\x00\x00" + b"\x08\x00"
    return eth + ip + udp


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("bag")
    ap.add_argument("out")
    ap.add_argument("--first-scan", type=int, default=0)
    ap.add_argument("--scans", type=int, default=1 << 30)
    ap.add_argument("--skip-packets", type=int, default=0)
    ap.add_argument("--packets", type=int, default=1 << 30)
    a = ap.parse_args()
    n = 0
    with open(a.out, "wb") as f:
        f.write(struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1))
        for i, (stamp, data) in enumerate(scans(a.bag)):
            if not a.first_scan <= i < a.first_scan + a.scans:
                continue
            for sec, nsec, payload in unpack_scan(data):
                n += 1
                if not a.skip_packets < n <= a.skip_packets + a.packets:
                    continue
                frame = udp_frame(payload)
                f.write(struct.pack("<IIII", sec, nsec // 1000, len(frame), len(frame)))
                f.write(frame)
            print(f"scan {i}: bag stamp {stamp}, {len(unpack_scan(data))} packets")


if __name__ == "__main__":
    main()
