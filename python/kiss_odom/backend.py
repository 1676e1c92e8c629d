"""kiss-odom as the backend of kiss-icp 1.3.0's own Python code.

kiss-icp's Python layer (``KissICP``, ``OdometryPipeline``, its 14 dataloaders, its metrics)
does its numerical work through one compiled module, ``kiss_icp.pybind.kiss_icp_pybind``.
:data:`kiss_icp_pybind` provides the same names on kiss-odom's core (``kiss_odom._native``):
``_Vector3dVector``, ``_VoxelHashMap``, ``_Preprocessor``, ``_Registration``,
``_AdaptiveThreshold``, ``_voxel_down_sample``, ``_correct_kitti_scan``, ``_kitti_seq_error``
and ``_absolute_trajectory_error``.

The switch is :func:`install`::

    import kiss_odom.backend
    kiss_odom.backend.install()
    from kiss_icp.pipeline import OdometryPipeline   # now runs on kiss-odom

or, for the command line, ``kiss-odom-pipeline`` in place of ``kiss_icp_pipeline`` (same
arguments, same outputs).
"""

from __future__ import annotations

import sys
import types

from kiss_odom import _native

MODULE = "kiss_icp.pybind.kiss_icp_pybind"
NAMES = (
    "_Vector3dVector",
    "_VoxelHashMap",
    "_Preprocessor",
    "_Registration",
    "_AdaptiveThreshold",
    "_voxel_down_sample",
    "_correct_kitti_scan",
    "_kitti_seq_error",
    "_absolute_trajectory_error",
)

kiss_icp_pybind = types.ModuleType(MODULE, "kiss_icp_pybind on kiss-odom's core")
for _name in NAMES:
    setattr(kiss_icp_pybind, _name, getattr(_native, _name))
kiss_icp_pybind.BACKEND = "kiss-odom"


def install() -> None:
    """Makes kiss-icp's Python code use kiss-odom. Call it before kiss-icp runs anything;
    kiss-icp modules already imported are switched too (their ``kiss_icp_pybind`` name is
    rebound), so the order of imports does not matter."""
    sys.modules[MODULE] = kiss_icp_pybind
    package = sys.modules.get("kiss_icp.pybind")
    if package is not None:
        package.kiss_icp_pybind = kiss_icp_pybind
    for name, module in list(sys.modules.items()):
        if name.startswith("kiss_icp.") and getattr(module, "kiss_icp_pybind", None) is not None:
            module.kiss_icp_pybind = kiss_icp_pybind


def installed() -> bool:
    """Whether kiss-icp currently resolves its bindings to kiss-odom."""
    return sys.modules.get(MODULE) is kiss_icp_pybind
