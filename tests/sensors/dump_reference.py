"""Decodes every shared sensor recording with the independent references and writes what they
give, for tests/tests/sensors.rs to compare with kiss-odom-sensors point by point.

  python dump_reference.py OUT_DIR [--golden GOLDEN_DIR]

Ouster: ouster-sdk's open_source(pcap, meta=[json]), points from XYZLut(info) on RANGE (and
RANGE2 in dual profiles), no-return pixels dropped, per-column timestamps. Velodyne:
velodyne_decoder.read_pcap(path, Config(...)) with the range filter opened (min_range 0) so
every non-zero return is compared.

For each recording OUT_DIR gets NAME.bin (48-byte records, see RECORD) and NAME.json (per-sweep
point counts). --golden also writes GOLDEN_DIR/NAME.json: the counts plus an evenly spaced
sample of points, small enough to commit, for the offline test.
"""

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT.parent / "shared" / "data" / "sensors"

RECORD = np.dtype(
    [
        ("sweep", "<u4"),
        ("ring", "<u2"),
        ("column", "<u2"),
        ("ret", "u1"),
        ("pad", "u1"),
        ("dcol", "<u2"),
        ("pad2", "<u4"),
        ("x", "<f8"),
        ("y", "<f8"),
        ("z", "<f8"),
        # Ouster: absolute column timestamp, ns. Velodyne: time since the sweep start, ns.
        ("t_ns", "<f8"),
    ]
)
assert RECORD.itemsize == 48

OUSTER = [
    ("os1_128_lb", "OS-1-128_v2.3.0_1024x10_lb_n3.pcap", "OS-1-128_v2.3.0_1024x10.json"),
    ("os0_32_dual", "OS-0-32-U1_v2.2.0_1024x10.pcap", "OS-0-32-U1_v2.2.0_1024x10.json"),
    ("os1_32_legacy", "OS-1-32-G_v2.1.1_1024x10.pcap", "OS-1-32-G_v2.1.1_1024x10.json"),
]
# (name, file, cut angle or None)
VELODYNE = [
    ("vlp16", "velodyne_vlp16.pcap", None),
    ("vlp16_cut0", "velodyne_vlp16.pcap", 0.0),
    ("vlp32c", "velodyne_vlp32.pcap", None),
    ("vlp32c_cut90", "velodyne_vlp32.pcap", 90.0),
]
# The two Velodyne recordings are HDL-32E packets (product byte 0x21). To exercise every model
# and return mode against the reference, these variants rewrite each data packet's return-mode
# and product bytes (1204, 1205); both decoders then decode the same bytes as that model and
# mode (the geometry is not physical, the decoding is what is compared).
# (name, source file, product byte, return-mode byte, cut angle or None)
VARIANTS = [
    ("v_vlp16_strongest", "velodyne_vlp16.pcap", 0x22, 0x37, None),
    ("v_vlp16_dual", "velodyne_vlp16.pcap", 0x22, 0x39, None),
    ("v_puck_hires_last", "velodyne_vlp16.pcap", 0x24, 0x38, 45.0),
    ("v_vlp32c_last", "velodyne_vlp32.pcap", 0x28, 0x38, None),
    ("v_vlp32c_dual", "velodyne_vlp32.pcap", 0x28, 0x39, None),
    ("v_hdl32e_dual", "velodyne_vlp16.pcap", 0x21, 0x39, 0.0),
    # With the calibration file calib_vlp32c.yml beside this script.
    ("v_vlp32c_calibrated", "velodyne_vlp32.pcap", 0x28, 0x37, None),
]
CALIBRATED = {"v_vlp32c_calibrated": Path(__file__).resolve().parent / "calib_vlp32c.yml"}
SAMPLE = 200


def rewrite(src, product, mode):
    """The pcap `src` with bytes 1204 and 1205 of every Velodyne data packet (Ethernet, IPv4
    without options, UDP to port 2368, 1206 bytes) set to `mode` and `product`. The same
    rewrite is in tests/tests/sensors.rs."""
    b = bytearray(src.read_bytes())
    at = 24
    while at + 16 <= len(b):
        incl = int.from_bytes(b[at + 8 : at + 12], "little")
        frame = at + 16
        if (
            incl == 42 + 1206
            and b[frame + 12 : frame + 14] == b"\x08\x00"
            and b[frame + 14] == 0x45
            and int.from_bytes(b[frame + 36 : frame + 38], "big") == 2368
        ):
            b[frame + 42 + 1204] = mode
            b[frame + 42 + 1205] = product
        at = frame + incl
    return bytes(b)


def ouster(pcap, meta):
    from ouster.sdk import open_source
    from ouster.sdk.core import ChanField, XYZLut, destagger

    src = open_source(str(DATA / "ouster" / pcap), meta=[str(DATA / "ouster" / meta)])
    info = src.sensor_info[0]
    lut = XYZLut(info)
    h, w = info.format.pixels_per_column, info.format.columns_per_frame
    cols = np.tile(np.arange(w, dtype=np.int64), (h, 1))
    dcols = np.zeros((h, w), dtype=np.int64)
    # Where destagger puts each staggered column: destagger the column indices and invert.
    moved = destagger(info, cols)
    rows = np.repeat(np.arange(h)[:, None], w, axis=1)
    dcols[rows, moved] = np.tile(np.arange(w), (h, 1))
    out, counts, frames = [], [], []
    for i, frame in enumerate(src):
        scan = frame[0] if isinstance(frame, list) else list(frame)[0]
        frames.append(int(scan.frame_id))
        fields = [(1, ChanField.RANGE)]
        if scan.has_field(ChanField.RANGE2):
            fields.append((2, ChanField.RANGE2))
        n = 0
        for ret, f in fields:
            rng = scan.field(f)
            xyz = lut(rng)
            r, c = np.nonzero(rng)
            rec = np.zeros(len(r), RECORD)
            rec["sweep"], rec["ring"], rec["column"], rec["ret"] = i, r, c, ret
            rec["dcol"] = dcols[r, c]
            rec["x"], rec["y"], rec["z"] = xyz[r, c, 0], xyz[r, c, 1], xyz[r, c, 2]
            rec["t_ns"] = scan.timestamp[c].astype(np.float64)
            out.append(rec)
            n += len(r)
        counts.append(n)
    return np.concatenate(out), counts, {"frame_ids": frames}


def velodyne(pcap, cut, calibration=None):
    import velodyne_decoder as vd

    pcap = Path(pcap) if Path(pcap).is_absolute() else DATA / "velodyne" / pcap

    cfg = vd.Config(timestamp_first_packet=True, min_range=0.0, max_range=1000.0)
    if cut is not None:
        cfg.cut_angle = cut
    if calibration is not None:
        cfg.calibration = vd.Calibration.read(str(calibration))
    out, counts, stamps = [], [], []
    for i, (stamp, pts) in enumerate(vd.read_pcap(str(pcap), cfg)):
        rec = np.zeros(len(pts), RECORD)
        rec["sweep"] = i
        rec["x"], rec["y"], rec["z"] = pts[:, 0], pts[:, 1], pts[:, 2]
        rec["t_ns"] = pts[:, 4].astype(np.float64) * 1e9
        rec["column"], rec["ring"], rec["ret"] = pts[:, 5], pts[:, 6], pts[:, 7]
        out.append(rec)
        counts.append(len(pts))
        stamps.append(float(stamp.device))
    pts = np.concatenate(out) if out else np.zeros(0, RECORD)
    return pts, counts, {"stamps": stamps, "cut_angle": cut}


def golden(rec, counts, extra, kind):
    step = max(1, len(rec) // SAMPLE)
    sample = rec[::step][:SAMPLE]
    keys = ["sweep", "ring", "column", "ret", "dcol", "x", "y", "z", "t_ns"]
    rows = [[s[k].item() for k in keys] for s in sample]
    return {"kind": kind, "counts": counts, **extra, "fields": keys, "sample": rows}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out", type=Path)
    ap.add_argument("--golden", type=Path)
    a = ap.parse_args()
    a.out = a.out.resolve()
    a.out.mkdir(parents=True, exist_ok=True)
    jobs = [(n, "ouster", lambda p=p, m=m: ouster(p, m)) for n, p, m in OUSTER]
    jobs += [(n, "velodyne", lambda p=p, c=c: velodyne(p, c)) for n, p, c in VELODYNE]
    for n, src, product, mode, cut in VARIANTS:
        path = a.out / f"{n}.pcap"
        path.write_bytes(rewrite(DATA / "velodyne" / src, product, mode))
        calib = CALIBRATED.get(n)
        jobs.append((n, "velodyne", lambda p=path, c=cut, k=calib: velodyne(p, c, k)))
    for name, kind, run in jobs:
        rec, counts, extra = run()
        rec.tofile(a.out / f"{name}.bin")
        (a.out / f"{name}.json").write_text(json.dumps({"kind": kind, "counts": counts, **extra}))
        print(f"{name}: {len(counts)} sweeps, {len(rec)} points {counts}", file=sys.stderr)
        if a.golden:
            a.golden.mkdir(parents=True, exist_ok=True)
            g = golden(rec, counts, extra, kind)
            (a.golden / f"{name}.json").write_text(json.dumps(g, indent=0) + "\n")


if __name__ == "__main__":
    main()
