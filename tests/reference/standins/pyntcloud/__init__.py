"""Stand-in for the part of pyntcloud kiss-icp's Newer College loader uses:
`PyntCloud.from_file(path).points[["x", "y", "z"]].to_numpy()`, the float32 fields as stored.
Used when pyntcloud cannot be imported or cannot read binary PCD (pyntcloud 0.3 calls
`np.fromstring`, which numpy 2 removed); dump_layout.py reports that it was used."""
import sys

import numpy as np

sys.path.insert(0, __path__[0] + "/..")
from pcd import read_fields  # noqa: E402

sys.path.pop(0)
STAND_IN = True


class _Columns:
    def __init__(self, fields):
        self._fields = fields

    def __getitem__(self, names):
        return _Columns({n: self._fields[n] for n in names})

    def to_numpy(self):
        return np.stack(list(self._fields.values()), axis=1)


class PyntCloud:
    def __init__(self, points):
        self.points = points

    @classmethod
    def from_file(cls, path):
        f = read_fields(path)
        return cls(_Columns({n: f[n] for n in f.dtype.names}))
