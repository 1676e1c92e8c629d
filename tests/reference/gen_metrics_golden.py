#!/usr/bin/env python3
"""Golden values for the trajectory metrics, produced by the reference kiss-icp 1.3.0.

Writes fixtures/golden/metrics_reference.json, which `tests/tests/metrics.rs` checks without
Python. It holds:

- "kitti_mini": for each of the kitti-mini sequences 01, 02, 04, 05, the reference's own metrics
  (`kiss_icp.metrics.sequence_error` and `absolute_trajectory_error`, the C++ in
  cpp/kiss_icp/metrics/Metrics.cpp) of the stored reference poses
  (reference_kiss_icp_1.3.0/XX.txt) against the ground truth in the LiDAR frame as the
  reference's `KITTIOdometryDataset` computes it (calib read as float32,
  T_lidar = Tr^-1 * T_cam * Tr). Ten frames are shorter than any KITTI segment, so the reference's
  KITTI errors are NaN there (stored as null). The final position error and the per-frame RPE
  are not reference metrics; they are computed here with numpy, as an independent second
  implementation, and stored under "numpy".
- "synthetic": a 1500-frame trajectory pair about 1.8 km long, generated from a formula and a
  seeded splitmix64 stream (see `synthetic()` below; tests/tests/metrics.rs implements the same
  formula), with the reference's KITTI relative errors and ATE/ARE, and a few poses of both
  trajectories so the Rust side can check it generated the same pair before comparing.

The reference returns float32 (its C++ functions return std::tuple<float, float>), so its figures
carry about 7 significant digits. Every float is written with repr(), which round-trips exactly.

Usage: /work/refvenv/bin/python tests/reference/gen_metrics_golden.py [KITTI_MINI_DIR]
(default: ../shared/data/kitti-mini relative to the repository root).
"""

import json
import math
import sys
from pathlib import Path

import numpy as np
import kiss_icp
from kiss_icp.datasets.kitti import KITTIOdometryDataset
from kiss_icp.metrics import absolute_trajectory_error, sequence_error

ROOT = Path(__file__).resolve().parents[2]
DATA = Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT.parent / "shared" / "data" / "kitti-mini"
OUT = ROOT / "fixtures" / "golden" / "metrics_reference.json"

SEQUENCES = ["01", "02", "04", "05"]

# Synthetic pair: keep in sync with `synthetic_pair` in tests/tests/metrics.rs.
SYN_FRAMES = 1500
SYN_SEED = 0x4B155_0D0
SYN_CHECKPOINTS = [0, 1, 10, 749, 1498, 1499]
MASK = (1 << 64) - 1


class SplitMix64:
    def __init__(self, seed: int):
        self.state = seed & MASK

    def next_u64(self) -> int:
        self.state = (self.state + 0x9E3779B97F4A7C15) & MASK
        z = self.state
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK
        return z ^ (z >> 31)

    def uniform(self) -> float:
        """Uniform in [-1, 1): the top 53 bits as a fraction, scaled."""
        return 2.0 * ((self.next_u64() >> 11) * 2.0**-53) - 1.0


def rot_zyx(yaw: float, pitch: float, roll: float) -> np.ndarray:
    cz, sz = math.cos(yaw), math.sin(yaw)
    cy, sy = math.cos(pitch), math.sin(pitch)
    cx, sx = math.cos(roll), math.sin(roll)
    rz = np.array([[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]])
    ry = np.array([[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]])
    return rz @ ry @ rx


def transform(t, r) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = r
    m[:3, 3] = t
    return m


def synthetic():
    """Ground truth: a winding, slightly hilly drive at 0.8-1.6 m per frame. Estimate: the same
    increments followed by a per-frame error with a bias (1 % too long, 2e-4 rad/frame of yaw)
    and seeded uniform noise."""
    rng = SplitMix64(SYN_SEED)
    gt = [np.eye(4)]
    est = [np.eye(4)]
    for i in range(SYN_FRAMES - 1):
        step = 1.2 + 0.4 * math.sin(0.011 * i)
        d_gt = transform(
            [step, 0.0, 0.02 * math.sin(0.031 * i)],
            rot_zyx(0.02 * math.sin(0.0071 * i + 0.3), 0.002 * math.sin(0.023 * i),
                    0.001 * math.cos(0.017 * i)),
        )
        u = [rng.uniform() for _ in range(6)]
        noise = transform(
            [0.01 * step + 0.005 * u[0], 0.005 * u[1], 0.003 * u[2]],
            rot_zyx(2e-4 + 3e-4 * u[3], 1e-4 * u[4], 1e-4 * u[5]),
        )
        gt.append(gt[-1] @ d_gt)
        est.append(est[-1] @ d_gt @ noise)
    return np.stack(gt), np.stack(est)


def load_kitti(path: Path) -> np.ndarray:
    rows = np.loadtxt(path).reshape(-1, 3, 4)
    out = np.tile(np.eye(4), (rows.shape[0], 1, 1))
    out[:, :3, :] = rows
    return out


def angle(r: np.ndarray) -> float:
    """Rotation angle, exact for small angles: atan2(sin, cos) from the skew part and trace."""
    s = 0.5 * np.linalg.norm([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    c = 0.5 * (np.trace(r) - 1.0)
    return float(math.atan2(s, c))


def numpy_metrics(gt: np.ndarray, est: np.ndarray) -> dict:
    t_err, r_err = [], []
    for i in range(len(gt) - 1):
        e = np.linalg.inv(np.linalg.inv(gt[i]) @ gt[i + 1]) @ (np.linalg.inv(est[i]) @ est[i + 1])
        t_err.append(float(np.linalg.norm(e[:3, 3])))
        r_err.append(angle(e[:3, :3]))
    return {
        "final_error_m": float(np.linalg.norm(est[-1][:3, 3] - gt[-1][:3, 3])),
        "rpe_m_mean": float(np.mean(t_err)),
        "rpe_m_max": float(np.max(t_err)),
        "rpe_rad_mean": float(np.mean(r_err)),
    }


def reference_metrics(gt: np.ndarray, est: np.ndarray) -> dict:
    t_pct, r_deg = sequence_error(gt, est)
    are, ate = absolute_trajectory_error(gt, est)

    def finite(v):
        return float(v) if math.isfinite(v) else None

    return {
        "kitti_t_err_pct": finite(t_pct),
        "kitti_r_err_deg_per_m": finite(r_deg),
        "ate_m": float(ate),
        "are_rad": float(are),
    }


def main() -> None:
    kitti_mini = {}
    for seq in SEQUENCES:
        gt = np.asarray(KITTIOdometryDataset(DATA, seq).gt_poses, dtype=np.float64)
        est = load_kitti(DATA / "reference_kiss_icp_1.3.0" / f"{seq}.txt")
        assert gt.shape == est.shape, (seq, gt.shape, est.shape)
        kitti_mini[seq] = {
            "frames": int(len(gt)),
            "reference": reference_metrics(gt, est),
            "numpy": numpy_metrics(gt, est),
        }

    gt, est = synthetic()
    synthetic_entry = {
        "frames": SYN_FRAMES,
        "seed": SYN_SEED,
        "gt_length_m": float(sum(np.linalg.norm(gt[i + 1][:3, 3] - gt[i][:3, 3])
                                 for i in range(len(gt) - 1))),
        "reference": reference_metrics(gt, est),
        "numpy": numpy_metrics(gt, est),
        "checkpoints": {
            str(i): {
                "gt": [float(v) for v in gt[i][:3, :].reshape(-1)],
                "est": [float(v) for v in est[i][:3, :].reshape(-1)],
            }
            for i in SYN_CHECKPOINTS
        },
    }

    golden = {
        "notice": (
            "kitti_mini entries are derived from KITTI odometry sequences 01, 02, 04, 05 "
            "(Geiger, Lenz, Urtasun, CVPR 2012), licensed CC BY-NC-SA 3.0: non-commercial use, "
            "attribution, share-alike."
        ),
        "generator": "tests/reference/gen_metrics_golden.py",
        "kiss_icp_version": kiss_icp.__version__,
        "reference_precision": "float32 (the reference's metric functions return float)",
        "kitti_mini": kitti_mini,
        "synthetic": synthetic_entry,
    }
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(golden, indent=1) + "\n")
    print(f"wrote {OUT}")
    for seq, e in kitti_mini.items():
        print(seq, e["reference"], e["numpy"])
    print("synthetic", synthetic_entry["gt_length_m"], synthetic_entry["reference"],
          synthetic_entry["numpy"])


if __name__ == "__main__":
    main()
