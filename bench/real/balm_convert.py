"""Convert hku-mars/BALM datas/benchmark_realworld (full<k>.pcd + alidarPose.csv) to the generic
layout, for BENCHMARKS.md's "Every rule on real data" (bench/ablation.sh with REAL=...):

    python3 bench/real/balm_convert.py BALM/datas/benchmark_realworld OUT/balm-os0-keyframes

BALM is GPL-2.0 (github hku-mars/BALM, commit 5dc1bf9); the converted data is not shipped."""
import sys, os, numpy as np
sys.path.insert(0, os.path.dirname(__file__))
from pcd import write_generic
src, out = sys.argv[1], sys.argv[2]
vals = [list(map(float, l.strip().strip(',').split(','))) for l in open(os.path.join(src, 'alidarPose.csv')) if l.strip()]
A = np.array(vals).reshape(-1, 4, 4)
stamps = A[:, 3, 3].copy()
T = A.copy(); T[:, 3, :] = [0, 0, 0, 1]
write_generic(out, [os.path.join(src, 'full%d.pcd' % k) for k in range(len(T))], T, stamps)
