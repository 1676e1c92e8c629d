"""Per-frame relative-motion error of an estimate (poses_kitti.txt) against a reference (poses.txt)."""
import sys, numpy as np
from scipy.spatial.transform import Rotation as R
def load(p):
    a = np.loadtxt(p); n = len(a); T = np.tile(np.eye(4), (n, 1, 1)); T[:, :3, :] = a.reshape(n, 3, 4); return T
E, G = load(sys.argv[1]), load(sys.argv[2])
thr_t = float(sys.argv[3]) if len(sys.argv) > 3 else 0.2
rows = []
for k in range(1, len(E)):
    e = np.linalg.inv(E[k-1]) @ E[k]; g = np.linalg.inv(G[k-1]) @ G[k]; d = np.linalg.inv(g) @ e
    te = np.linalg.norm(d[:3, 3]); re = np.degrees(np.linalg.norm(R.from_matrix(d[:3, :3]).as_rotvec()))
    gt_t = np.linalg.norm(g[:3, 3]); gt_r = np.degrees(np.linalg.norm(R.from_matrix(g[:3, :3]).as_rotvec()))
    rows.append((k, gt_t, gt_r, te, re))
r = np.array(rows)
print('frames with step error > %.2f m or > 3 deg: %d of %d' % (thr_t, np.sum((r[:, 3] > thr_t) | (r[:, 4] > 3)), len(r)))
print('gt step: median %.3f m %.2f deg, max %.3f m %.2f deg' % (np.median(r[:, 1]), np.median(r[:, 2]), r[:, 1].max(), r[:, 2].max()))
for k, a, b, c, d in rows:
    if c > thr_t or d > 3:
        print('%d gt %.2f m %.1f deg  err %.2f m %.1f deg' % (k, a, b, c, d))
