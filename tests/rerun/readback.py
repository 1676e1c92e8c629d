"""Reads kiss-odom's outputs back with other tools, for tests/tests/view.rs.

    readback.py rrd FILE.rrd   Rerun's dataframe API on the `frame` timeline: for each entity,
                               the frames that have a row, and every `world/sensor` transform.
    readback.py cloud FILE     The point count and first point of a .ply (plyfile) or .pcd
                               (pypcd4) file.

Prints one JSON object; the Rust test does the checking.
"""

import json
import sys


def rrd(path):
    import pyarrow as pa
    from rerun.experimental import RrdReader

    store = RrdReader(path).stream().collect()
    table = store.reader(index="frame").to_arrow_table()
    frames = table.column("frame").to_pylist()
    entities = {}
    for name in table.column_names:
        # Component columns are named "<entity>:<Archetype>:<field>".
        if ":" not in name:
            continue
        entity = name.split(":", 1)[0]
        present = [f for f, v in zip(frames, table.column(name).to_pylist()) if v is not None]
        rows = entities.setdefault(entity, set())
        rows.update(present)
    sensor = {}
    for field in ("translation", "mat3x3"):
        column = next(n for n in table.column_names if n.startswith("/world/sensor:") and n.endswith(field))
        for f, v in zip(frames, table.column(column).to_pylist()):
            if v is not None:
                sensor.setdefault(str(f), {})[field] = v[0] if isinstance(v[0], list) else v
    return {
        "entities": {e: sorted(f) for e, f in entities.items()},
        "sensor": sensor,
        "columns": table.column_names,
    }


def cloud(path):
    if path.lower().endswith(".ply"):
        from plyfile import PlyData

        v = PlyData.read(path)["vertex"]
        return {"points": int(v.count), "first": [float(v["x"][0]), float(v["y"][0]), float(v["z"][0])] if v.count else None}
    from pypcd4 import PointCloud

    pc = PointCloud.from_path(path)
    xyz = pc.numpy(("x", "y", "z"))
    return {"points": int(len(xyz)), "first": [float(c) for c in xyz[0]] if len(xyz) else None}


if __name__ == "__main__":
    kind, path = sys.argv[1], sys.argv[2]
    print(json.dumps({"rrd": rrd, "cloud": cloud}[kind](path)))
