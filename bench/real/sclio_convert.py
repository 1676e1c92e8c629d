"""Convert a FAST-LIO2 + SC-PGO output folder (Scans/NNNNNN.pcd, optimized_poses.txt, times.txt)
to the generic layout: velodyne/NNNNNN.bin (f32 x y z i), poses.txt relative to frame 0, times.txt,
for BENCHMARKS.md's "Every rule on real data" (bench/ablation.sh with REAL=...):

    python3 bench/real/sclio_convert.py Fast-LIO2_SC-SLAM/output/HKU_1_bag OUT/fastlio-avia-hku1

Source: github daxuanzi515/Fast-LIO2_SC-SLAM, commit d1990f8 (no licence: not shipped)."""
import sys, os, numpy as np
sys.path.insert(0, os.path.dirname(__file__))
from pcd import read_pcd
src, out = sys.argv[1], sys.argv[2]
posefile = sys.argv[3] if len(sys.argv) > 3 else 'optimized_poses.txt'
a = np.loadtxt(os.path.join(src, posefile)).reshape(-1, 3, 4)
T = np.tile(np.eye(4), (len(a), 1, 1)); T[:, :3, :] = a
t = np.loadtxt(os.path.join(src, 'times.txt'))
scans = sorted(f for f in os.listdir(os.path.join(src, 'Scans')) if f.endswith('.pcd'))
assert len(scans) == len(T) == len(t), (len(scans), len(T), len(t))
T0inv = np.linalg.inv(T[0])
os.makedirs(os.path.join(out, 'velodyne'), exist_ok=True)
with open(os.path.join(out, 'poses.txt'), 'w') as fp, open(os.path.join(out, 'times.txt'), 'w') as ft:
    for k, f in enumerate(scans):
        assert f == '%06d.pcd' % k, f
        p, _ = read_pcd(os.path.join(src, 'Scans', f))
        pts = np.stack([p['x'], p['y'], p['z'], p['intensity']], 1).astype('<f4')
        pts = pts[np.isfinite(pts).all(1)]
        pts.tofile(os.path.join(out, 'velodyne', '%06d.bin' % k))
        R = T0inv @ T[k]
        fp.write(' '.join('%.9e' % v for v in R[:3, :].reshape(-1)) + '\n')
        ft.write('%.6f\n' % (t[k] - t[0]))
print(len(T), 'frames')
