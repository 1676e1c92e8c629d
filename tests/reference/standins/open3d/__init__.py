"""Stand-in for the part of open3d kiss-icp's Apollo loader uses: `io.read_point_cloud(path)
.points`, float64 x y z (open3d widens float32 fields exactly). Only on the path when open3d
itself cannot be imported; dump_layout.py reports that it was used."""
import sys
import types

import numpy as np

sys.path.insert(0, __path__[0] + "/..")
from pcd import read_fields  # noqa: E402

sys.path.pop(0)


class _Cloud:
    def __init__(self, points):
        self.points = points


def _read_point_cloud(path):
    f = read_fields(path)
    return _Cloud(np.stack([f["x"], f["y"], f["z"]], axis=1).astype(np.float64))


io = types.SimpleNamespace(read_point_cloud=_read_point_cloud)
STAND_IN = True
