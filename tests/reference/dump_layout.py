#!/usr/bin/env python3
"""Dump what kiss-icp 1.3.0's own dataloader reads from a dataset folder, for the layout tests.

    python dump_layout.py --loader mulran|nclt|ncd|helipr|boreas|nuscenes|apollo|kitti_raw \
        --data DIR [--sequence S] --out OUT [--pipeline]

Writes to OUT:
  info.json        {"frames": n, "gt_rows": m, "numpy": version}
  points_<i>.f64   frame i's points as the loader returns them, float64 little-endian, x y z
  stamps_<i>.f64   its per-point times as float64 (empty when the loader returns none)
  gt.f64           the loader's gt_poses, 16 float64 a pose, row-major
  pipeline.json    with --pipeline: kiss-icp's OdometryPipeline run on the loader (default
                   config), its poses and the metrics it prints (kiss_icp_pipeline's figures)

Exits 3 with "SKIP: reason" on stdout when the loader's own dependency cannot be used here
(scipy for nclt, pyntcloud for ncd, open3d for apollo, nuscenes-devkit for nuscenes;
pyntcloud 0.3 and nuscenes-devkit need numpy below 2).
"""
import argparse
import importlib
import json
import os
import sys
from pathlib import Path

import numpy as np

NEEDS = {
    "nclt": "scipy",
    "ncd": "pyntcloud",
    "apollo": "open3d",
    "nuscenes": "nuscenes",
    "mulran": None,
    "helipr": "pyquaternion",
    "boreas": "natsort",
    "kitti_raw": None,
}


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--loader", required=True, choices=sorted(NEEDS))
    ap.add_argument("--data", required=True)
    ap.add_argument("--sequence", default=None)
    ap.add_argument("--out", required=True)
    ap.add_argument("--pipeline", action="store_true")
    a = ap.parse_args()
    need = NEEDS[a.loader]
    if need is not None:
        try:
            importlib.import_module(need)
        except Exception as e:  # an import error of any kind means: not usable here
            print(f"SKIP: the {a.loader} loader needs {need}, which cannot be imported ({e})")
            return 3
    if a.loader == "ncd" and int(np.__version__.split(".")[0]) >= 2:
        # pyntcloud 0.3 reads binary PCD with np.fromstring, which numpy 2 removed.
        print(f"SKIP: the ncd loader's pyntcloud cannot read binary PCD with numpy {np.__version__}")
        return 3
    from kiss_icp.datasets import dataset_factory

    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    kwargs = {"sequence": a.sequence} if a.sequence is not None else {}
    dataset = dataset_factory(dataloader=a.loader, data_dir=Path(a.data), **kwargs)
    n = len(dataset)
    for i in range(n):
        points, stamps = dataset[i]
        np.ascontiguousarray(points, dtype="<f8").tofile(out / f"points_{i}.f64")
        np.ascontiguousarray(np.asarray(stamps, dtype=np.float64), dtype="<f8").tofile(
            out / f"stamps_{i}.f64"
        )
    gt = np.asarray(dataset.gt_poses, dtype=np.float64).reshape(-1, 16)
    np.ascontiguousarray(gt, dtype="<f8").tofile(out / "gt.f64")
    info = {"frames": n, "gt_rows": int(gt.shape[0]), "numpy": np.__version__}
    (out / "info.json").write_text(json.dumps(info))
    if a.pipeline:
        from kiss_icp.pipeline import OdometryPipeline

        pipeline = OdometryPipeline(dataset=dataset, config=None, visualize=False)
        pipeline._run_pipeline()
        pipeline._run_evaluation()
        # NaN (no 100 m segment for the KITTI errors) is written as null.
        metrics = {r.desc: float(r.value) for r in pipeline.results}
        metrics = {k: (v if np.isfinite(v) else None) for k, v in metrics.items()}
        poses = np.asarray(pipeline.poses, dtype=np.float64).reshape(-1, 16).tolist()
        (out / "pipeline.json").write_text(json.dumps({"metrics": metrics, "poses": poses}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
