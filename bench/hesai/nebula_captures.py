#!/usr/bin/env python3
"""TIER IV nebula's Hesai decoder test captures as pcaps, for the comparison of
tests/tests/sensors_hesai_nebula.rs.

    nebula_captures.py NEBULA_GIT OUT [--fixtures FIXTURE_DIR]

NEBULA_GIT is a clone (or bare git directory) of github.com/tier4/nebula. For each model whose
bag is in it (`src/nebula_hesai/nebula_hesai/test_resources/decoder_ground_truth/MODEL/`), OUT
gets MODEL.pcap (the bag's packets, bag_to_pcap.py), MODEL.pcd (nebula's decoded scan) and the
angle correction CSV nebula decodes it with; run the test with KISS_ODOM_NEBULA_CAPTURES=OUT.

--fixtures also writes the small sectors the test ships: the packets of the scan nebula
decoded whose first block azimuth lies in [A, A + 40) degrees (A = 100; 10 for the XT32M), and
the PCD's points whose azimuth (nebula's: atan2(x, y)) lies in [A + 10, A + 30) degrees. The
scan is found by the raw distances alone: of each bag message's packets before and after the
azimuth wraps, those in the sector whose distances hold the most of the PCD points' ranges
(on a tie, those of the message the PCD is named after).
"""
import argparse
import math
import os
import sqlite3
import struct
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bag_to_pcap import packets_of, udp_frame  # noqa: E402

ROOT = "src/nebula_hesai/nebula_hesai/test_resources/decoder_ground_truth"
CALIB = "src/nebula_hesai/nebula_hesai_decoders/calibration"
# Model folder: its calibration file; the sector's first azimuth (degrees; the XT32M's bag lost
# most of the scan's packets, its sector lies where they arrived); the packet layout: header
# bytes, block bytes, bytes before a block's units (where its azimuth ends), unit bytes,
# blocks, lasers, millimetres per distance unit.
MODELS = {
    "40p": ("Pandar40P.csv", 100.0, (0, 124, 4, 3, 10, 40, 4)),
    "64": ("Pandar64.csv", 100.0, (8, 194, 2, 3, 6, 64, 4)),
    "qt64": ("PandarQT64.csv", 100.0, (12, 258, 2, 4, 4, 64, 4)),
    "xt16": ("PandarXT16.csv", 100.0, (12, 66, 2, 4, 8, 16, 4)),
    "xt32": ("PandarXT32.csv", 100.0, (12, 130, 2, 4, 8, 32, 4)),
    "xt32m": ("PandarXT32M.csv", 10.0, (12, 130, 2, 4, 6, 32, 5)),
    "qt128": ("PandarQT128.csv", 100.0, (12, 514, 2, 4, 2, 128, 4)),
}
# Packets whose first block lies within 40 degrees from the sector's start; the points within
# the 20 degrees in their middle (the channels' azimuth offsets are under 10 degrees).


def git(repo, *args):
    return subprocess.run(["git", "-C", repo, *args], check=True, capture_output=True).stdout


def write_pcap(path, pkts):
    with open(path, "wb") as f:
        f.write(struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1))
        for t, p in pkts:
            frame = udp_frame(p)
            f.write(struct.pack("<IIII", t // 1_000_000_000, t % 1_000_000_000 // 1000,
                                len(frame), len(frame)))
            f.write(frame)


def pcd_split(data):
    marker = b"DATA binary\n"
    at = data.index(marker) + len(marker)
    return data[:at], [struct.unpack_from("<3f", data, i) for i in range(at, len(data) - 11, 12)]


def write_pcd(path, pts):
    head = (
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\n"
        f"TYPE F F F\nCOUNT 1 1 1\nWIDTH {len(pts)}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
        f"POINTS {len(pts)}\nDATA binary\n"
    )
    with open(path, "wb") as f:
        f.write(head.encode())
        for p in pts:
            f.write(struct.pack("<3f", *p))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("nebula_git")
    ap.add_argument("out")
    ap.add_argument("--fixtures")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    files = git(a.nebula_git, "ls-tree", "-r", "--name-only", "HEAD", ROOT).decode().split()
    for model, (csv, a0, layout) in MODELS.items():
        mine = [f for f in files if f.startswith(f"{ROOT}/{model}/")]
        bag = [f for f in mine if f.endswith(".db3") and "all_points" not in f]
        pcd = [f for f in mine if f.endswith(".pcd")]
        if not bag or not pcd:
            print(f"{model}: no bag or PCD in nebula's tree")
            continue
        try:
            db = git(a.nebula_git, "show", f"HEAD:{bag[0]}")
        except subprocess.CalledProcessError:
            print(f"{model}: {bag[0]} is not in this copy (too large?)")
            continue
        with tempfile.NamedTemporaryFile(suffix=".db3") as tmp:
            tmp.write(db)
            tmp.flush()
            con = sqlite3.connect(tmp.name)
            msgs = [(ts, packets_of(d)) for ts, d in
                    con.execute("SELECT timestamp, data FROM messages ORDER BY timestamp")]
            con.close()
        pkts = [p for _, ps in msgs for p in ps]
        write_pcap(os.path.join(a.out, f"{model}.pcap"), pkts)
        pcd_bytes = git(a.nebula_git, "show", f"HEAD:{pcd[0]}")
        open(os.path.join(a.out, f"{model}.pcd"), "wb").write(pcd_bytes)
        calib = git(a.nebula_git, "show", f"HEAD:{CALIB}/{csv}")
        open(os.path.join(a.out, csv), "wb").write(calib)
        print(f"{model}: {len(pkts)} packets, {os.path.basename(pcd[0])}")
        if not a.fixtures:
            continue
        os.makedirs(a.fixtures, exist_ok=True)
        _, pts = pcd_split(pcd_bytes)
        keep = [p for p in pts
                if a0 + 10.0 <= math.degrees(math.atan2(p[0], p[1])) % 360.0 < a0 + 30.0]
        header, block_len, lead, unit_len, blocks, lasers, unit_mm = layout
        want = [round(math.sqrt(x * x + y * y + z * z) * 1000.0 / unit_mm) for x, y, z in keep]
        best = (-1, [])
        # The message the PCD is named after first: it wins a tie (a static scene's ranges
        # repeat from one turn to the next).
        named = int(os.path.basename(pcd[0])[:-4])
        for _, ps in sorted(msgs, key=lambda m: m[0] != named):
            parts, part, last = [[], []], 0, -1.0
            for t, p in ps:
                az = struct.unpack_from("<H", p, header + lead - 2)[0] / 100.0
                if az < last:
                    part = 1
                last = az
                if a0 <= az < a0 + 40.0:
                    parts[part].append((t, p))
            for cand in parts:
                raw = set()
                for _, p in cand:
                    for k in range(blocks):
                        at = header + k * block_len + lead
                        raw.update(struct.unpack_from("<H", p, at + unit_len * c)[0]
                                   for c in range(lasers))
                hits = sum(1 for w in want if w in raw)
                print(f"  candidate of {len(cand)} packets: {hits} of {len(want)} ranges")
                if hits > best[0]:
                    best = (hits, cand)
        sector = best[1]
        write_pcap(os.path.join(a.fixtures, f"{model}.pcap"), sector)
        write_pcd(os.path.join(a.fixtures, f"{model}.pcd"), keep)
        open(os.path.join(a.fixtures, csv), "wb").write(calib)
        print(f"  fixture: {len(sector)} packets, {len(keep)} of the scan's {len(pts)} points")


if __name__ == "__main__":
    main()
