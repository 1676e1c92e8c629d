"""`LidarPointCloud.from_file`: a `.pcd.bin` of float32 x y z intensity ring, the first four
as rows of `points`."""
import numpy as np


class LidarPointCloud:
    def __init__(self, points):
        self.points = points

    @classmethod
    def from_file(cls, file_name):
        scan = np.fromfile(file_name, dtype=np.float32)
        return cls(scan.reshape((-1, 5))[:, :4].T)
