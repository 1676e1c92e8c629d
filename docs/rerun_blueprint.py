"""Writes docs/kiss-odom.rbl, a Rerun viewer layout for `kiss-odom run --rerun` recordings:
the 3D world (map, scan, source points, trajectories) beside latency, ICP iterations and the
map size. Open a recording with it: `rerun out/run.rrd docs/kiss-odom.rbl`.

Run with a Python that has rerun-sdk==0.36.3 (tests/rerun/requirements.txt).
"""

import pathlib

import rerun.blueprint as rrb

series = [
    rrb.TimeSeriesView(origin=f"/metrics/{name}", name=name)
    for name in ("latency_ms", "iterations", "map_points", "observability")
]
blueprint = rrb.Blueprint(
    rrb.Horizontal(
        rrb.Spatial3DView(origin="/world", name="world"),
        rrb.Vertical(*series),
        column_shares=[3, 2],
    ),
    rrb.BlueprintPanel(state="collapsed"),
    rrb.SelectionPanel(state="collapsed"),
    rrb.TimePanel(state="collapsed"),
)
out = pathlib.Path(__file__).with_name("kiss-odom.rbl")
blueprint.save("kiss-odom", out)
print(out)
