"""Where ouster-sdk's poses file for the OS-1-128 recording comes from (BENCHMARKS.md section 7,
"From recordings and the network"; run by bench/ouster_sdk_poses.sh).

The file `OS-1-128_v2.3.0_1024x10_lb_n3_poses_kitti.txt` beside the recording is named as
kiss-icp's pipeline names its output. This script replays what kiss-icp 0.2.10's Ouster
dataloader did (ouster-sdk's XYZLut on RANGE, no-return pixels dropped, each column stamped
with its nominal fraction of the sweep, `linspace(0, 1, W, endpoint=False)`) and feeds the
points to kiss-icp 0.2.10's `KissICP` with its default configuration, deskew on and off, and
prints the worst position difference from the file.

  export (in a venv with ouster-sdk 1.0.1, decoding with tests/sensors/dump_reference.py):
                                             python ouster_sdk_poses.py export OUT.npz
  run    (in a venv with kiss-icp 0.2.10):   python ouster_sdk_poses.py run OUT.npz

bench/ouster_sdk_poses.sh makes both venvs and runs the two steps.
"""
import json
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data" / "sensors" / "ouster"
PCAP = "OS-1-128_v2.3.0_1024x10_lb_n3.pcap"
META = "OS-1-128_v2.3.0_1024x10.json"
POSES = DATA / "OS-1-128_v2.3.0_1024x10_lb_n3_poses_kitti.txt"


def export(out):
    # ouster-sdk's decoding as the decoder tests compare it (no-return pixels dropped, points in
    # row-major image order, as kiss-icp 0.2.10's boolean mask gave them).
    sys.path.insert(0, str(REPO / "tests" / "sensors"))
    from dump_reference import ouster

    rec, counts, _ = ouster(PCAP, META)
    width = json.loads((DATA / META).read_text())["data_format"]["columns_per_frame"]
    nominal = np.linspace(0, 1.0, width, endpoint=False)
    arrays = {}
    for k in range(len(counts)):
        sweep = rec[rec["sweep"] == k]
        arrays[f"xyz{k}"] = np.stack([sweep["x"], sweep["y"], sweep["z"]], axis=1)
        arrays[f"t{k}"] = nominal[sweep["column"]]
    np.savez(out, **arrays)
    print(f"{len(counts)} sweeps exported to {out}")


def run(npz):
    from kiss_icp.config import KISSConfig
    from kiss_icp.kiss_icp import KissICP

    frames = np.load(npz)
    sweeps = len(frames.files) // 2
    sdk = np.loadtxt(POSES)
    for deskew in (True, False):
        config = KISSConfig()
        config.data.deskew = deskew
        config.mapping.voxel_size = config.data.max_range / 100.0
        odometry = KissICP(config)
        for k in range(sweeps):
            odometry.register_frame(frames[f"xyz{k}"].astype(np.float64), frames[f"t{k}"])
        ours = np.array([p[:3, 3] for p in odometry.poses])
        worst = np.linalg.norm(ours - sdk[:, [3, 7, 11]], axis=1).max()
        print(f"kiss-icp 0.2.10, deskew {'on ' if deskew else 'off'}: worst {worst:.2e} m "
              f"from ouster-sdk's poses ({sweeps} sweeps)")


if __name__ == "__main__":
    {"export": export, "run": run}[sys.argv[1]](sys.argv[2])
