"""kiss-odom from Python: KISS-ICP LiDAR odometry on kiss-odom's bounded, deterministic core.

- :class:`KissICP` has the surface of kiss-icp 1.3.0's ``KissICP`` (``register_frame``,
  ``last_pose``, ``last_delta``, ``local_map``, ``config``) and runs each frame in Rust with
  the GIL released; :attr:`KissICP.last_report` says how the frame went.
- :mod:`kiss_odom.backend` puts kiss-odom under kiss-icp's own Python code
  (``kiss_odom.backend.install()``, or the ``kiss-odom-pipeline`` command).
- :mod:`kiss_odom.batch` runs ``kiss-odom run`` over many sequences as Ray tasks
  (``kiss-odom-batch``).
"""

from kiss_odom._native import __version__, correct_kitti_scan
from kiss_odom.config import settings_from
from kiss_odom.odometry import FrameReport, KissICP, LocalMap

__all__ = [
    "FrameReport",
    "KissICP",
    "LocalMap",
    "__version__",
    "correct_kitti_scan",
    "settings_from",
]
