"""`transform_matrix`: the float64 4x4 of a translation and a pyquaternion rotation."""
import numpy as np


def transform_matrix(translation=np.array([0, 0, 0]), rotation=None, inverse=False):
    assert not inverse, "the stand-in builds forward transforms only"
    tm = np.eye(4)
    tm[:3, :3] = rotation.rotation_matrix
    tm[:3, 3] = np.transpose(np.array(translation))
    return tm
