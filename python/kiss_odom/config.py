"""Configuration: kiss-icp's config objects, plain dicts and ``config.toml`` files, all turned
into the settings of ``kiss-odom run`` (the layout of the ``config.toml`` it writes).

Accepted by :func:`settings_from` (and so by :class:`kiss_odom.KissICP`):

- ``None``: the defaults, which are kiss-icp 1.3.0's (max range 100 m, voxel max_range/100),
  or those of the ``accurate`` preset with ``preset="accurate"`` (voxel max_range/200,
  point-to-plane terms where the map is planar; see the README's "Which preset");
- a kiss-icp ``KISSConfig`` (``kiss_icp.config.load_config(...)``), or the path of one of its
  YAML files (``.yaml``/``.yml``, read by the compiled module as ``kiss-odom run --config``
  reads it: neither PyYAML nor kiss-icp is needed; the voxel size is made explicit at
  ``max_range / 100`` as kiss-icp's ``load_config`` does, but a ``min_range`` above
  ``max_range`` is a ``ValueError`` where kiss-icp resets it to 0 with a printed warning);
- a ``config.toml`` path as ``kiss-odom run`` writes it;
- a dict with any of the sections ``data``, ``mapping``, ``adaptive_threshold``,
  ``registration`` (kiss-icp's keys and ours), ``capacities``, ``runtime`` and ``output``
  (its ``map_frame``: the frame a prior map must be in).

kiss-icp keys map as: ``registration.max_num_threads`` -> ``runtime.threads``; ``out_dir`` is
kiss-icp's pipeline's and is ignored; ``adaptive_threshold.fixed_threshold`` is refused (the
core always adapts). Keys neither side knows are a ``ValueError``, and so are NaN and inf
values, named by their setting.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any, Mapping, Optional, Union

from kiss_odom import _native

ConfigLike = Union[None, Mapping[str, Any], str, os.PathLike, Any]


def defaults(preset: Optional[str] = None) -> dict:
    """The settings of a preset (``"default"``, the default, or ``"accurate"``), those of
    ``kiss-odom run --preset``."""
    return json.loads(_native.default_settings_json(preset))


def _as_dict(config: ConfigLike, preset: Optional[str] = None) -> dict:
    if config is None:
        return {}
    if isinstance(config, (str, os.PathLike)):
        path = Path(config)
        if not path.is_file():
            raise ValueError(f"{path}: no such configuration file")
        if path.suffix.lower() in (".toml", ".yaml", ".yml"):
            return json.loads(_native.load_settings_json(str(path), preset))
        raise ValueError(f"{path}: a configuration is a .toml (kiss-odom) or .yaml (kiss-icp) file")
    if hasattr(config, "model_dump"):  # kiss-icp's pydantic KISSConfig
        return config.model_dump()
    if isinstance(config, Mapping):
        return {k: (dict(v) if isinstance(v, Mapping) else v) for k, v in config.items()}
    raise ValueError(
        f"config must be None, a dict, a kiss-icp KISSConfig or a file path, not {type(config).__name__}"
    )


def _merge(base: dict, over: dict, where: str = "") -> None:
    for key, value in over.items():
        if isinstance(value, Mapping):
            if not isinstance(base.get(key), dict):
                raise ValueError(f"unknown configuration section {where}{key!r}")
            _merge(base[key], value, f"{where}{key}.")
        elif value is not None or key == "voxel_size":
            base[key] = value


def settings_from(
    config: ConfigLike = None,
    *,
    preset: Optional[str] = None,
    scalar: Optional[str] = None,
    map_storage: Optional[str] = None,
    capacities: Union[None, str, Mapping[str, int]] = None,
    threads: Optional[int] = None,
) -> dict:
    """The ``kiss-odom run`` settings for ``config`` plus kiss-odom's extras: ``preset``
    (``"default"`` or ``"accurate"``: the defaults every setting ``config`` does not give
    takes; replaces the config's ``pipeline.preset``), ``scalar`` (``"f64"`` or ``"f32"``),
    ``map_storage`` (``"exact"`` or ``"quantized"``), ``capacities`` (``"full"``,
    ``"small"`` or a dict of the five capacities) and ``threads``
    (0: all cores; results do not depend on it)."""
    given = _as_dict(config, preset)
    given.pop("out_dir", None)
    pipeline = dict(given.pop("pipeline", None) or {})
    preset = preset or pipeline.get("preset") or "default"
    registration = dict(given.get("registration") or {})
    runtime = dict(given.get("runtime") or {})
    if "max_num_threads" in registration:
        runtime.setdefault("threads", registration.pop("max_num_threads") or 0)
    threshold = dict(given.get("adaptive_threshold") or {})
    if threshold.pop("fixed_threshold", None) is not None:
        raise ValueError(
            "adaptive_threshold.fixed_threshold is not supported: kiss-odom's core always "
            "adapts the threshold (set initial_threshold instead)"
        )
    given.update(registration=registration, runtime=runtime, adaptive_threshold=threshold)
    if isinstance(capacities, str):
        capacities = _native.capacity_preset(capacities)
    extras = {"scalar": scalar, "map_storage": map_storage, "threads": threads}
    given["runtime"].update({k: v for k, v in extras.items() if v is not None})
    if capacities is not None:
        given["capacities"] = {**given.get("capacities", {}), **capacities}
    settings = defaults(preset)
    _merge(settings, given)
    settings["pipeline"]["preset"] = preset
    _refuse_non_finite(settings)
    return settings


def _refuse_non_finite(settings: dict, where: str = "") -> None:
    # JSON has no NaN or inf: refused here by name rather than as a parse error later.
    for key, value in settings.items():
        if isinstance(value, dict):
            _refuse_non_finite(value, f"{where}{key}.")
        elif isinstance(value, float) and not math.isfinite(value):
            raise ValueError(f"{where}{key} = {value}: not a finite number")
