"""``KissICP``: kiss-icp 1.3.0's ``KissICP`` surface on kiss-odom's core.

Each ``register_frame`` call runs the whole frame (deskew, crop, both downsamplings, ICP,
map update) in Rust with the GIL released, with the settings and the arithmetic of
``kiss-odom run``: the same frames give the same poses, bit for bit, as ``run``, and agree
with kiss-icp 1.3.0's ``KissICP`` to rounding.

Input handling, each covered by a test in ``python/tests/test_bad_input.py``:

- ``frame`` is an Nx3 array of x, y, z. float32, integer and non-contiguous arrays are
  converted to contiguous float64; any other shape (Nx2, Nx4, 1-D) is a ``ValueError`` (pass
  ``frame[:, :3]`` to drop an intensity column).
- Rows with NaN or inf are skipped and counted (``last_report.dropped["non_finite"]``, flag
  ``invalid_points``).
- An empty frame (or one with no point within range) is not an error: as kiss-icp and
  ``kiss-odom run`` do, the pose advances on the constant-velocity model, both returned
  arrays are empty and ``last_report.status`` is ``"empty"``.
- ``timestamps`` may be empty or ``None`` (no deskewing). Timestamps of the wrong length,
  non-finite or all equal are ignored: the frame is registered without deskewing, with the
  flag ``timestamps_ignored`` and the reason in ``last_report.stamp_problem``.

Localization in a prior map (``map=`` and ``initial_pose=``, as ``kiss-odom run --map
--initial-pose``): after each frame the odometry's registration cloud is registered to the map
by the same localizer as ``run``'s, so ``map_pose`` is ``run``'s map-frame pose bit for bit;
``last_pose`` and ``last_delta`` stay the odometry's own (its first frame at identity), as in
kiss-icp.

Threads: one ``KissICP`` may be shared by several Python threads. Its calls are serialised
by a lock (a second thread's ``register_frame`` waits for the first to finish, with the GIL
released meanwhile); frames still go one after the other, in the order the calls take the
lock. Separate objects run in parallel.
"""

from __future__ import annotations

import json
import os
import threading
import warnings
from dataclasses import dataclass, field
from typing import Any, Mapping, Optional, Tuple, Union

import numpy as np

from kiss_odom import _native
from kiss_odom.config import ConfigLike, settings_from


@dataclass(frozen=True)
class FrameReport:
    """How the last frame went (the core's ``FrameReport``).

    ``status`` is ``"ok"``, ``"empty"`` or the set flags joined by ``|``; ``flags`` lists
    them (``timestamps_ignored``, ``iteration_cap``, ``no_correspondences``, ``singular``,
    ``degenerate``, ``invalid_points``, ``scan_truncated``, ``capacity``, ``budget``,
    ``planes``, ``evicted``, ``one_plane``: the last warns once too). ``dropped``
    counts points and voxels dropped by reason."""

    index: int
    status: str
    flags: Tuple[str, ...] = ()
    iterations: int = 0
    correspondences: int = 0
    #: Of the last iteration's correspondences, the point-to-plane ones (robust mode and the
    #: ``accurate`` preset).
    plane_correspondences: int = 0
    sigma: float = float("nan")
    rms: float = float("nan")
    model_error: float = float("nan")
    observability: Optional[float] = None
    input_points: int = 0
    out_of_range: int = 0
    merge_points: int = 0
    source_points: int = 0
    map_voxels: int = 0
    map_points: int = 0
    pruned_voxels: int = 0
    deskewed: bool = False
    #: Deskewed a second time with the motion its first registration found (the ``accurate``
    #: preset's ``data.redeskew``).
    redeskewed: bool = False
    stamp_problem: Optional[str] = None
    dropped: Mapping[str, int] = field(default_factory=dict)
    #: With the gyroscope prior on: ``"used"`` or why not (``"first"``, ``"no_samples"``,
    #: ``"gap"``, ``"bad_samples"``), the samples it had, the bias estimate after the frame
    #: and how far ICP's rotation rate was from the gyroscope's (rad/s) when it was used;
    #: ``"rejected"`` when the gyroscope's rotation over the frame disagreed with the one ICP
    #: registered (``imu_disagreement``, rad) and the frame went without it (a ``RuntimeWarning``
    #: names the likely cause once).
    imu_prior: Optional[str] = None
    imu_samples: int = 0
    gyro_bias: Optional[Tuple[float, float, float]] = None
    imu_residual: Optional[float] = None
    imu_disagreement: Optional[float] = None
    #: With a prior map (``KissICP(map=...)``, else ``None``): ``"localized"``, ``"degraded"``
    #: or ``"lost"``; of the registration cloud's points off level ground, the share within
    #: half a voxel of a map point at the map-frame pose; the registration's observability
    #: ratio; how far registering to the map moved the prediction (m). ``run --map``'s
    #: ``frames.csv`` columns (docs/maps.md).
    localization: Optional[str] = None
    map_inlier_share: Optional[float] = None
    map_observability: Optional[float] = None
    map_correction_m: Optional[float] = None

    @property
    def ok(self) -> bool:
        """No flag set and not empty."""
        return self.status == "ok"

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> "FrameReport":
        d = {**d, "flags": tuple(d.get("flags", ()))}
        if d.get("gyro_bias") is not None:
            d["gyro_bias"] = tuple(d["gyro_bias"])
        return cls(**d)


class LocalMap:
    """kiss-icp's ``local_map``: the map of a :class:`KissICP` (world frame)."""

    def __init__(self, odometry: "_native.Odometry", lock: threading.Lock):
        self._odom = odometry
        self._lock = lock

    def point_cloud(self) -> np.ndarray:
        """Every map point, Nx3 float64 (voxel by voxel; kiss-icp's order differs)."""
        with self._lock:
            return self._odom.map_points()

    def clear(self) -> None:
        """Empties the map; poses and threshold stay (as in kiss-icp)."""
        with self._lock:
            self._odom.clear_map()

    def empty(self) -> bool:
        with self._lock:
            return self._odom.map_empty()


def _is_kiss_icp_config(config: Any) -> bool:
    return hasattr(config, "model_dump") and hasattr(config, "data")


class KissICP:
    """kiss-icp's ``KissICP(config)`` on kiss-odom.

    ``config`` is anything :func:`kiss_odom.settings_from` accepts (a kiss-icp
    ``KISSConfig``, its YAML, our ``config.toml``, a dict or ``None``); the keyword extras
    pick the preset (``"default"``: kiss-icp's poses; ``"accurate"``: lower error
    on most runs measured, settings the config does not give take its values), the scalar
    (``"f64"``/``"f32"``), the map storage (``"exact"``/``"quantized"``), the capacities (``"full"``/``"small"``/dict) and the thread count. A bad setting is a
    ``ValueError`` naming it.

    ``map`` (a path to a ``.komap`` file of ``kiss-odom map build``) with ``initial_pose`` (the
    sensor at the end of the first sweep in the map frame: a 4x4 rigid transform, or the text
    ``"X,Y,Z,ROLL,PITCH,YAW"`` of ``run --initial-pose``, m and degrees) localizes every frame
    in that map: :attr:`map_pose` and ``last_report.localization``. The start is not searched
    for, so one needs the other; a map this configuration cannot use (another voxel size or
    frame than ``{"output": {"map_frame": ...}}``, default ``"map"``; a truncated or damaged
    header) is a ``ValueError`` naming the reason. The map file's bytes stay in memory until
    the process ends, once per distinct file content whatever the number of objects.
    """

    def __init__(
        self,
        config: ConfigLike = None,
        *,
        preset: Optional[str] = None,
        scalar: Optional[str] = None,
        map_storage: Optional[str] = None,
        capacities: Any = None,
        threads: Optional[int] = None,
        map: Union[str, os.PathLike, None] = None,
        initial_pose: Any = None,
    ):
        if map is not None and initial_pose is None:
            raise ValueError(
                "map needs initial_pose (the sensor at the end of the first sweep in the map "
                "frame): the start is not searched for over the whole map"
            )
        if initial_pose is not None and map is None:
            raise ValueError("initial_pose is the start in a prior map: it needs map")
        self.settings = settings_from(
            config,
            preset=preset,
            scalar=scalar,
            map_storage=map_storage,
            capacities=capacities,
            threads=threads,
        )
        self._odom = _native.Odometry.from_json(json.dumps(self.settings))
        if map is not None:
            self._odom.open_map(os.fspath(map), initial_pose)
        # Every call into `_odom` holds it (see the module doc, "Threads").
        self._lock = threading.Lock()
        # kiss-icp's pipeline reads its own config back (config.data.max_range, ...).
        self.config = config if _is_kiss_icp_config(config) else self.settings
        self.local_map = LocalMap(self._odom, self._lock)
        self.last_report: Optional[FrameReport] = None

    def register_frame(self, frame, timestamps=None) -> Tuple[np.ndarray, np.ndarray]:
        """Registers one scan; returns ``(deskewed_frame, source)`` like kiss-icp: the
        deskewed, cropped frame and the registration points (both sensor frame, Nx3)."""
        with self._lock:
            deskewed, source, report = self._odom.register_frame(frame, timestamps)
            said = report.pop("warnings", [])
            self.last_report = FrameReport.from_dict(report)
        for w in said:
            warnings.warn(w, RuntimeWarning, stacklevel=2)
        return deskewed, source

    def add_imu(self, time: float, gyro, accel) -> None:
        """One IMU sample for the gyroscope prior (on with ``{"imu": {"enabled": True}}`` in
        the config; ``imu.extrinsic`` and ``imu.time_offset`` place it): ``time`` in seconds on
        the clock of the frames' timestamps, ``gyro`` in rad/s, ``accel`` in m/s^2, IMU axes.
        The next ``register_frame`` (with timestamps in seconds) is predicted and deskewed with
        the rotation the samples since the last frame measured; ``last_report.imu_prior``
        says whether it was. Without the prior on, a ``ValueError``."""
        g = [float(v) for v in gyro]
        a = [float(v) for v in accel]
        if len(g) != 3 or len(a) != 3:
            raise ValueError("gyro and accel take three values each")
        with self._lock:
            self._odom.add_imu(float(time), g, a)

    @property
    def gyro_bias(self) -> Optional[np.ndarray]:
        """The gyroscope prior's bias estimate (rad/s, LiDAR axes), ``None`` when it is off."""
        with self._lock:
            b = self._odom.gyro_bias()
        return None if b is None else np.array(b)

    @property
    def last_pose(self) -> np.ndarray:
        """The latest pose, 4x4 (a copy; assign a 4x4 rigid transform to replace it)."""
        with self._lock:
            return self._odom.last_pose()

    @last_pose.setter
    def last_pose(self, pose) -> None:
        with self._lock:
            self._odom.set_last_pose(pose)

    @property
    def last_delta(self) -> np.ndarray:
        """The constant-velocity model, 4x4 (assignable like ``last_pose``)."""
        with self._lock:
            return self._odom.last_delta()

    @last_delta.setter
    def last_delta(self, delta) -> None:
        with self._lock:
            self._odom.set_last_delta(delta)

    @property
    def map_pose(self) -> Optional[np.ndarray]:
        """The last frame's pose in the prior map's frame, 4x4 (``None`` without a map or
        before the first frame)."""
        with self._lock:
            return self._odom.map_pose()

    @property
    def sigma(self) -> float:
        """The adaptive threshold's current sigma (m)."""
        with self._lock:
            return self._odom.sigma()

    @property
    def state_bytes(self) -> int:
        """Bytes of the core's state, fixed at construction."""
        with self._lock:
            return self._odom.state_bytes()

    def high_water(self) -> dict:
        """Largest occupancy of each buffer since start, ``(peak, capacity)``."""
        with self._lock:
            return self._odom.high_water()

    def settings_toml(self) -> str:
        """The settings as the ``config.toml`` ``kiss-odom run`` would write."""
        with self._lock:
            return self._odom.settings_toml()

    def reset(self) -> None:
        """Back to a new odometry's state (empty map, identity pose); with a prior map, the
        next frame is localized from ``initial_pose`` again."""
        with self._lock:
            self._odom.reset()
            self.last_report = None
