#!/usr/bin/env python3
"""Bad input for embedded/net.sh, standard library only.

  net-input.py free-port                   an unused UDP port on 127.0.0.1
  net-input.py spoil IN.pcap OUT.pcap      IN's datagrams with, after every 25th, one each of:
                                           1206 random bytes, a 1400-byte and a 3000-byte datagram
                                           (not after the last)
  net-input.py flood PORT COUNT            COUNT random 1206-byte datagrams to 127.0.0.1:PORT from
                                           another socket (a second sender), 1 ms apart

spoil prints how many of each it added.
"""
import os
import socket
import struct
import sys
import time


def free_port():
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    print(s.getsockname()[1])


def udp_frame(template, payload):
    """An Ethernet/IPv4/UDP frame with `template`'s headers (the simulator's: no IP options)
    and `payload`, lengths and IP checksum set (UDP checksum 0: none)."""
    eth, ip, udp = template[:14], bytearray(template[14:34]), bytearray(template[34:42])
    struct.pack_into(">H", ip, 2, 20 + 8 + len(payload))
    struct.pack_into(">H", ip, 10, 0)
    words = struct.unpack(">10H", bytes(ip))
    s = sum(words)
    s = (s & 0xFFFF) + (s >> 16)
    s = (s & 0xFFFF) + (s >> 16)
    struct.pack_into(">H", ip, 10, ~s & 0xFFFF)
    struct.pack_into(">HH", udp, 4, 8 + len(payload), 0)
    return eth + bytes(ip) + bytes(udp) + payload


def spoil(src, dst):
    data = open(src, "rb").read()
    out, at, n = [data[:24]], 24, 0
    added = {"random": 0, "oversized_1400": 0, "oversized_3000": 0}
    rng = __import__("random").Random(7)
    while at + 16 <= len(data):
        ts, tus, incl, orig = struct.unpack_from("<IIII", data, at)
        frame = data[at + 16 : at + 16 + incl]
        out.append(data[at : at + 16 + incl])
        at += 16 + incl
        n += 1
        # Not after the last packet: what follows the last sweep belongs to no sweep.
        if n % 25 or at + 16 > len(data):
            continue
        for kind, payload in (
            ("random", bytes(rng.getrandbits(8) for _ in range(1206))),
            ("oversized_1400", bytes(1400)),
            ("oversized_3000", bytes(3000)),
        ):
            f = udp_frame(frame, payload)
            out.append(struct.pack("<IIII", ts, tus, len(f), len(f)) + f)
            added[kind] += 1
    open(dst, "wb").write(b"".join(out))
    print(" ".join(f"{k}={v}" for k, v in added.items()), f"data={n}")


def flood(port, count):
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    for _ in range(count):
        s.sendto(os.urandom(1206), ("127.0.0.1", port))
        time.sleep(0.001)


if __name__ == "__main__":
    cmd = sys.argv[1:2]
    if cmd == ["free-port"]:
        free_port()
    elif cmd == ["spoil"]:
        spoil(sys.argv[2], sys.argv[3])
    elif cmd == ["flood"]:
        flood(int(sys.argv[2]), int(sys.argv[3]))
    else:
        sys.exit(__doc__)
