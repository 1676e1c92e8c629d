"""Scores a localization run (`kiss-odom run --map`) and odometry alone on the same revisit
against the revisit's ground truth (in the map frame).

    python3 bench/localize_score.py NAME GT INITIAL LOC_DIR ODO_DIR [LOC_S ODO_S]

GT: the revisit's poses.txt (map frame); INITIAL: the X,Y,Z,ROLL,PITCH,YAW odometry alone is
placed at (the pose localization was given); LOC_DIR and ODO_DIR: the two runs' output folders
(poses_kitti.txt, frames.csv). LOC_S and ODO_S: the two runs' wall seconds, for the speed
ratio. Prints one JSON line: position errors (median, worst, worst of each half of the run),
frames by state, the two-way count of `lost` against an error over 1 m, and the confident
wrong frames (`localized` with an error over 1 m), which must be 0.
"""

import csv
import json
import math
import sys


def read_kitti(path):
    out = []
    with open(path) as f:
        for line in f:
            v = [float(x) for x in line.split()]
            if len(v) == 12:
                out.append([v[0:4], v[4:8], v[8:12], [0.0, 0.0, 0.0, 1.0]])
    return out


def mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def pose_from(text):
    x, y, z, roll, pitch, yaw = (float(v) for v in text.strip().split(","))
    r, p, w = (math.radians(v) for v in (roll, pitch, yaw))
    cr, sr, cp, sp, cw, sw = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(w), math.sin(w)
    return [
        [cw * cp, cw * sp * sr - sw * cr, cw * sp * cr + sw * sr, x],
        [sw * cp, sw * sp * sr + cw * cr, sw * sp * cr - cw * sr, y],
        [-sp, cp * sr, cp * cr, z],
        [0.0, 0.0, 0.0, 1.0],
    ]


def errors(est, gt):
    return [math.dist([e[0][3], e[1][3], e[2][3]], [g[0][3], g[1][3], g[2][3]]) for e, g in zip(est, gt)]


def summary(err):
    s = sorted(err)
    half = len(err) // 2
    return {
        "median_m": round(s[len(s) // 2], 4),
        "worst_m": round(s[-1], 4),
        "worst_first_half_m": round(max(err[:half]), 4),
        "worst_second_half_m": round(max(err[half:]), 4),
    }


def main():
    name, gt_path, initial, loc_dir, odo_dir = sys.argv[1:6]
    gt = read_kitti(gt_path)
    start = pose_from(open(initial).read() if initial.endswith(".txt") else initial)
    loc = read_kitti(f"{loc_dir}/poses_kitti.txt")
    odo = [mul(start, p) for p in read_kitti(f"{odo_dir}/poses_kitti.txt")]
    with open(f"{loc_dir}/frames.csv") as f:
        states = [row["localization"] for row in csv.DictReader(f)]
    n = min(len(gt), len(loc), len(odo), len(states))
    le, oe = errors(loc[:n], gt[:n]), errors(odo[:n], gt[:n])
    count = lambda s: sum(1 for x in states[:n] if x == s)
    out = {
        "run": name,
        "frames": n,
        "localization": summary(le),
        "odometry": summary(oe),
        "localized": count("localized"),
        "degraded": count("degraded"),
        "lost": count("lost"),
        "lost_within_1m": sum(1 for s, e in zip(states, le) if s == "lost" and e <= 1.0),
        "not_lost_over_1m": sum(1 for s, e in zip(states, le) if s != "lost" and e > 1.0),
        "localized_over_1m": sum(1 for s, e in zip(states, le) if s == "localized" and e > 1.0),
        "first_localized": next((k for k, s in enumerate(states) if s == "localized"), None),
    }
    if len(sys.argv) > 7:
        out["wall_ratio_loc_over_odo"] = round(float(sys.argv[6]) / float(sys.argv[7]), 3)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
