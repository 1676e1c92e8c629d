#!/usr/bin/env python3
"""A ROS 2 sqlite3 bag of `pandar_msgs/msg/PandarScan` to a pcap of UDP datagrams.

Each PandarScan (CDR: header stamp and frame_id, then packets[], each a stamp, data[1500] and
size) becomes its packets' first `size` bytes, written as UDP datagrams from 192.168.1.201:2368
to port 2368 at the packet stamps (Ethernet, IPv4, UDP; pcap microsecond records). Stdlib only.

    bag_to_pcap.py BAG.db3 OUT.pcap [--first N] [--skip K]

--skip K leaves out the first K packets, --first N keeps N packets after those (a fixture's
cut).
"""
import argparse
import sqlite3
import struct


def align(off, n):
    return (off + n - 1) // n * n


def packets_of(cdr):
    """(stamp_ns, payload) of each packet of one CDR-encoded PandarScan."""
    body = cdr[4:]  # encapsulation header; CDR alignment counts from here
    if cdr[1] != 1:
        raise ValueError("not little-endian CDR")
    off = 8  # header.stamp: int32 sec, uint32 nanosec
    (n,) = struct.unpack_from("<I", body, off)
    off += 4 + n  # frame_id string (length includes the NUL)
    off = align(off, 4)
    (count,) = struct.unpack_from("<I", body, off)
    off += 4
    out = []
    for _ in range(count):
        off = align(off, 4)
        sec, nsec = struct.unpack_from("<iI", body, off)
        off += 8
        data = body[off : off + 1500]
        off += 1500
        off = align(off, 4)
        (size,) = struct.unpack_from("<I", body, off)
        off += 4
        if size > 1500:
            raise ValueError(f"packet size {size} over 1500")
        out.append((sec * 1_000_000_000 + nsec, bytes(data[:size])))
    return out


def udp_frame(payload, sport=2368, dport=2368):
    udp = struct.pack(">HHHH", sport, dport, 8 + len(payload), 0) + payload
    total = 20 + len(udp)
    ip = struct.pack(
        ">BBHHHBBH4s4s", 0x45, 0, total, 0, 0x4000, 64, 17, 0,
        bytes([192, 168, 1, 201]), bytes([255, 255, 255, 255]),
    )
    s = sum(struct.unpack(">10H", ip))
    while s >> 16:
        s = (s & 0xFFFF) + (s >> 16)
    ip = ip[:10] + struct.pack(">H", ~s & 0xFFFF) + ip[12:]
    eth = b"\xff" * 6 + b"\x00\x11\x22\x33\x44\x55" + b"\x08\x00"
    return eth + ip + udp


def bag_packets(db):
    con = sqlite3.connect(db)
    rows = con.execute(
        "SELECT m.data FROM messages m JOIN topics t ON m.topic_id = t.id "
        "WHERE t.type = 'pandar_msgs/msg/PandarScan' ORDER BY m.timestamp"
    )
    for (data,) in rows:
        yield from packets_of(data)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("bag")
    ap.add_argument("out")
    ap.add_argument("--skip", type=int, default=0)
    ap.add_argument("--first", type=int, default=None)
    a = ap.parse_args()
    pkts = list(bag_packets(a.bag))[a.skip :]
    if a.first is not None:
        pkts = pkts[: a.first]
    with open(a.out, "wb") as f:
        f.write(struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1))
        for t, p in pkts:
            frame = udp_frame(p)
            f.write(struct.pack("<IIII", t // 1_000_000_000, t % 1_000_000_000 // 1000,
                                len(frame), len(frame)))
            f.write(frame)
    sizes = sorted({len(p) for _, p in pkts})
    print(f"{a.out}: {len(pkts)} packets, sizes {sizes}")


if __name__ == "__main__":
    main()
