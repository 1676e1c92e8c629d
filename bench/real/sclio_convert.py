"""Convert a FAST-LIO2 + SC-PGO output folder (Scans/NNNNNN.pcd, optimized_poses.txt, times.txt)
to the generic layout: velodyne/NNNNNN.bin (f32 x y z i), poses.txt relative to frame 0, times.txt,
for BENCHMARKS.md's "Every rule on real data" (bench/ablation.sh with REAL=...):

    python3 bench/real/sclio_convert.py Fast-LIO2_SC-SLAM/output/HKU_1_bag OUT/fastlio-avia-hku1

Source: github daxuanzi515/Fast-LIO2_SC-SLAM, commit d1990f8 (no licence: not shipped)."""
import sys, os, numpy as np
sys.path.insert(0, os.path.dirname(__file__))
from pcd import write_generic
src, out = sys.argv[1], sys.argv[2]
posefile = sys.argv[3] if len(sys.argv) > 3 else 'optimized_poses.txt'
a = np.loadtxt(os.path.join(src, posefile)).reshape(-1, 3, 4)
T = np.tile(np.eye(4), (len(a), 1, 1)); T[:, :3, :] = a
t = np.loadtxt(os.path.join(src, 'times.txt'))
scans = sorted(f for f in os.listdir(os.path.join(src, 'Scans')) if f.endswith('.pcd'))
assert len(scans) == len(T) == len(t), (len(scans), len(T), len(t))
for k, f in enumerate(scans):
    assert f == '%06d.pcd' % k, f
write_generic(out, [os.path.join(src, 'Scans', f) for f in scans], T, t)
