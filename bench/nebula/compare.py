"""`kiss-odom convert` on TIER IV nebula's decoder test bags, point by point against the clouds
nebula's own decoders made of them (nebula's `decoder_ground_truth`, Apache-2.0).

For every model kiss-odom decodes, the bag (a ROS 2 sqlite3 bag of PandarScan or VelodyneScan
messages) is converted with nebula's test configuration where kiss-odom has the option (the
angle correction file, the cut angle), and the frame that holds nebula's cloud is compared
with it: nebula's range and field-of-view filters applied to ours, each of nebula's points
matched to its nearest point of ours after nebula's axes, the distances summarised (median,
p99, max) and the counts compared. Where the two disagree the reason is counted where it can
be told: a point at the scan's cut that the other decoder puts in the neighbouring scan (found
in our neighbouring frame), one of a dual-return pair less than 0.1 m apart (nebula keeps
one), a point at the edge of nebula's range or field-of-view filter.

    python3 bench/nebula/compare.py NEBULA KISS_ODOM [SCRATCH]

NEBULA: a checkout of nebula, or its git directory (the files are then taken from HEAD with
`git show`); KISS_ODOM: the `kiss-odom` binary. Needs numpy.
"""

import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HESAI = "src/nebula_hesai/nebula_hesai/test_resources/decoder_ground_truth"
VELODYNE = "src/nebula_velodyne/nebula_velodyne/test_resources/decoder_ground_truth"
HESAI_CAL = "src/nebula_hesai/nebula_hesai_decoders/calibration"
VELODYNE_CAL = "src/nebula_velodyne/nebula_velodyne_decoders/calibration"

# name, bag folder, nebula's cloud, calibration, kiss-odom options, nebula's configuration
# (min range, max range, field of view start and end in degrees, dual-return threshold):
# hesai_ros_decoder_test_main.cpp and velodyne_ros_decoder_test_*.cpp. Nebula's Hesai axes are
# ours turned a quarter turn (x to azimuth 90 degrees, y to azimuth 0); its Velodyne axes are
# ours.
MODELS = [
    ("Hesai XT32", f"{HESAI}/xt32/1673400677802009732", f"{HESAI}/xt32/1673400678101968885.pcd",
     f"{HESAI_CAL}/PandarXT32.csv", ["--set", "input.cut_angle=0"], (0.05, 120.0, 0, 360, 0.1)),
    ("Hesai XT16", f"{HESAI}/xt16/1732848127890747768", f"{HESAI}/xt16/1732848128093928016.pcd",
     f"{HESAI_CAL}/PandarXT16.csv", ["--set", "input.cut_angle=0"], (0.05, 120.0, 0, 360, 0.1)),
    ("Hesai XT32M", f"{HESAI}/xt32m/1660893203042895158", f"{HESAI}/xt32m/1660893203292679064.pcd",
     f"{HESAI_CAL}/PandarXT32M.csv", ["--set", "input.cut_angle=0"], (0.5, 300.0, 0, 360, 0.1)),
    ("Hesai QT128", f"{HESAI}/qt128/1730273789074637152", f"{HESAI}/qt128/1730273789174759609.pcd",
     f"{HESAI_CAL}/PandarQT128.csv", ["--set", "input.cut_angle=0"], (0.3, 300.0, 0, 360, 0.1)),
    ("Hesai OT128", f"{HESAI}/ot128/1730271167765338806", f"{HESAI}/ot128/1730271167863837186.pcd",
     f"{HESAI_CAL}/Pandar128E4X.csv", ["--set", "input.cut_angle=0", "--sensor", "ot128"],
     (0.3, 300.0, 0, 360, 0.1)),
    ("Hesai Pandar40P", f"{HESAI}/40p/1673400149412331409", f"{HESAI}/40p/1673400149711850138.pcd",
     f"{HESAI_CAL}/Pandar40P.csv", ["--set", "input.cut_angle=0"], (0.3, 200.0, 0, 360, 0.1)),
    ("Hesai Pandar64", f"{HESAI}/64/1673403880599376836", f"{HESAI}/64/1673403880898440686.pcd",
     f"{HESAI_CAL}/Pandar64.csv", ["--set", "input.cut_angle=0"], (0.3, 200.0, 0, 360, 0.1)),
    ("Hesai PandarQT64", f"{HESAI}/qt64/1673401195788312575",
     f"{HESAI}/qt64/1673401196087570870.pcd", f"{HESAI_CAL}/PandarQT64.csv",
     ["--set", "input.cut_angle=0"], (0.1, 60.0, 0, 360, 0.1)),
    # Nebula cuts the AT128's scans at 150 degrees and keeps 30 to 150 degrees of azimuth.
    ("Hesai PandarAT128", f"{HESAI}/at128/1679653308406038376",
     f"{HESAI}/at128/1679653308704927652.pcd", f"{HESAI_CAL}/PandarAT128.dat",
     ["--set", "input.cut_angle=150"], (1.0, 180.0, 30, 150, 0.1)),
    # Their clouds cover every azimuth whatever cloud_min_angle and cloud_max_angle say.
    ("Velodyne VLP-16", f"{VELODYNE}/vlp16/1673400471837873222",
     f"{VELODYNE}/vlp16/1673400472138016708.pcd", f"{VELODYNE_CAL}/VLP16.yaml",
     ["--set", "input.cut_angle=0"], (0.3, 300.0, 0, 360, None)),
    ("Velodyne VLP-32C", f"{VELODYNE}/vlp32/1713492677464078412",
     f"{VELODYNE}/vlp32/1713492677464078412.pcd", f"{VELODYNE_CAL}/VLP32.yaml",
     ["--set", "input.cut_angle=180"], (0.4, 50.0, 0, 360, None)),
    ("Velodyne VLS-128", f"{VELODYNE}/vls128/1614315746471294674",
     f"{VELODYNE}/vls128/1585897255376374245.pcd", f"{VELODYNE_CAL}/VLS128.yaml",
     ["--set", "input.cut_angle=0", "--sensor", "vls128"], (0.3, 300.0, 0, 360, None)),
]


def read_pcd(path):
    """x, y, z of a binary PCD (any further fields skipped)."""
    raw = Path(path).read_bytes()
    at = raw.index(b"DATA binary\n") + len(b"DATA binary\n")
    head = raw[:at].decode().splitlines()
    fields = dict(line.split(" ", 1) for line in head if " " in line)
    sizes = [int(s) for s in fields["SIZE"].split()]
    names = fields["FIELDS"].split()
    n = int(fields["POINTS"])
    step = sum(sizes)
    rows = np.frombuffer(raw[at:at + n * step], dtype=np.uint8).reshape(n, step)
    offsets = np.cumsum([0] + sizes)
    xyz = [rows[:, offsets[names.index(c)]:offsets[names.index(c)] + 4].copy().view("<f4")[:, 0]
           for c in "xyz"]
    return np.stack(xyz, axis=1).astype(np.float64)


def read_frames(out):
    frames = []
    for f in sorted((out / "velodyne").glob("*.bin")):
        frames.append(np.fromfile(f, dtype="<f4").reshape(-1, 4)[:, :3].astype(np.float64))
    return frames


def nearest(query, points, cell=0.05):
    """Distance and index of each query point's nearest point (searched within one cell)."""
    keys = np.floor(points / cell).astype(np.int64)
    grid = {}
    for i, k in enumerate(map(tuple, keys)):
        grid.setdefault(k, []).append(i)
    dist = np.full(len(query), np.inf)
    index = np.full(len(query), -1)
    offsets = [(a, b, c) for a in (-1, 0, 1) for b in (-1, 0, 1) for c in (-1, 0, 1)]
    for q, key in enumerate(map(tuple, np.floor(query / cell).astype(np.int64))):
        cand = [i for o in offsets for i in grid.get((key[0] + o[0], key[1] + o[1], key[2] + o[2]), ())]
        if cand:
            d = np.linalg.norm(points[cand] - query[q], axis=1)
            j = int(np.argmin(d))
            dist[q], index[q] = d[j], cand[j]
    return dist, index


def in_fov(p, start, end):
    """Whether each point's azimuth (degrees, clockwise from nebula's y) is in [start, end]."""
    az = np.degrees(np.arctan2(p[:, 0], p[:, 1])) % 360.0
    if start <= end:
        return (az >= start) & (az <= end)
    return (az >= start) | (az <= end)


def compare(name, root, kiss_odom, scratch, model):
    _, bag, pcd, cal, options, (lo, hi, fov0, fov1, dual) = model
    bag, pcd, cal = root / bag, root / pcd, root / cal
    if not (bag / "metadata.yaml").exists() or not pcd.exists():
        return f"{name}: not in this checkout"
    db3 = next(bag.glob("*.db3"), None)
    if db3 is None or db3.stat().st_size == 0:
        return f"{name}: its bag is not in this checkout (stored apart, large file)"
    out = scratch / name.replace(" ", "_")
    cmd = [kiss_odom, "convert", str(bag), "--out", str(out), "--calibration", str(cal), "-q"]
    run = subprocess.run(cmd + options, capture_output=True, text=True)
    if run.returncode != 0:
        return f"{name}: convert failed: {run.stderr.strip()}"
    theirs = read_pcd(pcd)
    hesai = name.startswith("Hesai")
    frames = []
    for frame in read_frames(out):
        if hesai:
            frame = np.stack([-frame[:, 1], frame[:, 0], frame[:, 2]], axis=1)
        r = np.linalg.norm(frame, axis=1)
        # Nebula's float32 points at its range limits may be a hair inside ours.
        keep = (r >= lo - 1e-5) & (r <= hi + 1e-5) & in_fov(frame, fov0, fov1)
        frames.append(frame[keep])
    # The frame that holds nebula's cloud: the most of its points within 5 cm (a decoder that
    # reads returns differently still puts them there).
    scores = [np.mean(nearest(theirs[::10], f)[0] < 0.05) if len(f) else 0 for f in frames]
    if not frames or max(scores) == 0:
        return f"{name}: no frame holds nebula's cloud"
    k = int(np.argmax(scores))
    ours = frames[k]
    d, idx = nearest(theirs, ours)
    in_ours = idx[(d < 1e-4) & (idx >= 0)]
    # Nebula's points that are not in our frame but in a neighbouring one: the scan's cut.
    cut = 0
    far = d >= 1e-4
    for j in (k - 1, k + 1):
        if 0 <= j < len(frames) and far.any():
            dj, _ = nearest(theirs[far], frames[j])
            moved = np.where(far)[0][dj < 1e-4]
            d[moved] = dj[dj < 1e-4]
            cut += len(moved)
            far = d >= 1e-4
    unmatched = np.setdiff1d(np.arange(len(ours)), in_ours)
    reasons = explain(ours, unmatched, (lo, hi, fov0, fov1, dual), cut_deg(options), spread(cal))
    finite = d[np.isfinite(d)]
    told = ", ".join(f"{n} {why}" for why, n in reasons.items() if n)
    return (f"{name}: our frame {k}; points ours {len(ours)} / nebula {len(theirs)}; nebula's "
            f"points within 1e-4 m of ours {np.sum(d < 1e-4)} ({cut} of them in our "
            f"neighbouring frame: the scan cut); distance median {np.median(finite):.2e} p99 "
            f"{np.percentile(finite, 99):.2e} max {finite.max():.2e} m; ours no nebula point "
            f"within 1e-4 m: {len(unmatched)} ({told or 'none told'})")


def cut_deg(options):
    cut = [o.split("=", 1)[1] for o in options if o.startswith("input.cut_angle=")]
    return float(cut[0]) if cut else None


def spread(cal):
    """The largest azimuth offset of a Hesai angle correction file's channels, degrees (a
    channel fires that far from its block's azimuth, so its points cross the cut that far
    from it); 0 for other files."""
    if cal.suffix != ".csv":
        return 0.0
    rows = [line.split(",") for line in cal.read_text().splitlines()[1:]]
    return max((abs(float(r[2])) for r in rows if len(r) > 2), default=0.0)


def explain(ours, unmatched, config, cut, spread):
    """Why points of ours have no match, where it can be told."""
    lo, hi, fov0, fov1, dual = config
    p = ours[unmatched]
    r = np.linalg.norm(p, axis=1)
    az = np.degrees(np.arctan2(p[:, 0], p[:, 1])) % 360.0
    at = f"at the scan cut (within {spread + 1:.1f} degrees)"
    told = {at: 0, "one of a dual pair": 0,
            "at a range or field-of-view edge": 0, "other": 0}
    pair = np.zeros(len(p), bool)
    if dual is not None and len(p):
        unit = ours / np.linalg.norm(ours, axis=1, keepdims=True)
        others = np.delete(np.arange(len(ours)), unmatched)
        du, di = nearest(unit[unmatched] * 100.0, unit[others] * 100.0, cell=0.1)
        gap = np.abs(r - np.linalg.norm(ours[others[np.maximum(di, 0)]], axis=1))
        pair = (du < 100.0 * np.radians(0.05)) & (gap < dual)
    def near(a, b, within=1.0):
        return np.minimum(np.abs(a - b) % 360.0, 360.0 - np.abs(a - b) % 360.0) < within
    at_cut = near(az, cut, spread + 1.0) if cut is not None else np.zeros(len(p), bool)
    edge = (np.abs(r - lo) < 0.01) | (np.abs(r - hi) < 0.01)
    if (fov0, fov1) != (0, 360):
        edge |= near(az, fov0) | near(az, fov1)
    for c, pr, e in zip(at_cut, pair, edge):
        key = (at if c else "one of a dual pair" if pr
               else "at a range or field-of-view edge" if e else "other")
        told[key] += 1
    return told


def extract(git_dir, into):
    """The files the comparison reads, from HEAD of nebula's git directory."""
    listed = subprocess.run(["git", "-C", str(git_dir), "ls-tree", "-r", "--name-only", "HEAD"],
                            capture_output=True, text=True, check=True).stdout.split()
    wanted = [HESAI, VELODYNE, HESAI_CAL, VELODYNE_CAL]
    for path in listed:
        if any(path.startswith(w) for w in wanted):
            target = into / path
            target.parent.mkdir(parents=True, exist_ok=True)
            with open(target, "wb") as f:
                subprocess.run(["git", "-C", str(git_dir), "show", f"HEAD:{path}"], stdout=f,
                               stderr=subprocess.DEVNULL)
    return into


def main():
    root, kiss_odom = Path(sys.argv[1]), sys.argv[2]
    scratch = Path(sys.argv[3]) if len(sys.argv) > 3 else Path(tempfile.mkdtemp())
    if not (root / "src").is_dir():
        root = extract(root, scratch / "nebula")
    for model in MODELS:
        print(compare(model[0], root, kiss_odom, scratch, model), flush=True)


if __name__ == "__main__":
    main()
