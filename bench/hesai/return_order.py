#!/usr/bin/env python3
"""Which return each block of a Hesai dual-return pair holds, from recorded captures.

    return_order.py CAPTURES [MODEL...]

CAPTURES is the folder `nebula_captures.py` writes (MODEL.pcap from nebula's recorded bags).
For every dual-return packet, every firing (two consecutive blocks) and every channel where
both blocks have a return of different ranges, it counts which block is the nearer and which
the stronger, and prints them with the packets' return-mode bytes and header return counts.
A block that is the farther in every differing pair holds the last return; the nearer in
every one, the first (or, in a last + strongest mode, the strongest: then it is also the
weaker wherever the last is the strongest, since the other block holds the second strongest).

Used for `ReturnMode::from_byte` (sensors/src/hesai/model.rs). Layouts: header bytes, block
bytes, where a block's units begin, unit bytes, blocks, lasers, where the return-mode byte
lies (nebula's packet structs).
"""
import collections
import struct
import sys

FORMATS = {
    "40p": (0, 124, 4, 3, 10, 40, 10 * 124 + 14),
    "64": (8, 194, 2, 3, 6, 64, 8 + 6 * 194 + 14),
    "qt64": (12, 258, 2, 4, 4, 64, 12 + 4 * 258 + 16),
    "xt16": (12, 66, 2, 4, 8, 16, 12 + 8 * 66 + 10),
    "xt32": (12, 130, 2, 4, 8, 32, 12 + 8 * 130 + 10),
    "xt32m": (12, 130, 2, 4, 6, 32, 12 + 6 * 130 + 10),
}


def payloads(path):
    """UDP payloads of a pcap of Ethernet/IPv4/UDP frames (as nebula_captures.py writes)."""
    d = open(path, "rb").read()
    at = 24
    while at + 16 <= len(d):
        incl = struct.unpack_from("<I", d, at + 8)[0]
        yield d[at + 16 + 42:at + 16 + incl]
        at += 16 + incl


def main():
    root = sys.argv[1]
    for model in sys.argv[2:] or FORMATS:
        header, block, lead, unit, blocks, lasers, mode_at = FORMATS[model]
        modes, counts = collections.Counter(), collections.Counter()
        n = collections.Counter()
        for p in payloads(f"{root}/{model}.pcap"):
            mode = p[mode_at]
            modes[f"0x{mode:02X}"] += 1
            if header == 12:
                counts[p[10]] += 1
            if mode < 0x39:
                continue
            for k in range(0, blocks, 2):
                for c in range(lasers):
                    a = header + k * block + lead + unit * c
                    d0, r0 = struct.unpack_from("<HB", p, a)
                    d1, r1 = struct.unpack_from("<HB", p, a + block)
                    if d0 == 0 or d1 == 0 or d0 == d1:
                        continue
                    n["block 0 nearer" if d0 < d1 else "block 0 farther"] += 1
                    if r0 != r1:
                        n["block 0 stronger" if r0 > r1 else "block 1 stronger"] += 1
        print(f"{model}: modes {dict(modes)}, header return counts {dict(counts)}; "
              f"differing pairs: {dict(n)}")


if __name__ == "__main__":
    main()
