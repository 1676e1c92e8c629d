"""`NuScenes`: the JSON tables of `dataroot/version`, each record by its token."""
import json
import os

TABLES = ["category", "attribute", "visibility", "instance", "sensor", "calibrated_sensor",
          "ego_pose", "log", "scene", "sample", "sample_data", "sample_annotation", "map"]


class NuScenes:
    def __init__(self, version="v1.0-mini", dataroot="/data/sets/nuscenes", verbose=True,
                 map_resolution=0.1):
        self.version = version
        self.dataroot = dataroot
        self.table_root = os.path.join(dataroot, version)
        for name in TABLES:
            with open(os.path.join(self.table_root, f"{name}.json")) as f:
                setattr(self, name, json.load(f))
        self._index = {name: {r["token"]: r for r in getattr(self, name)} for name in TABLES}
        # As the devkit's reverse index: each sample's key frame per channel (the last in table
        # order wins).
        for sample in self.sample:
            sample["data"] = {}
        for sd in self.sample_data:
            cs = self.get("calibrated_sensor", sd["calibrated_sensor_token"])
            sd["channel"] = self.get("sensor", cs["sensor_token"])["channel"]
            if sd["is_key_frame"]:
                self.get("sample", sd["sample_token"])["data"][sd["channel"]] = sd["token"]

    def get(self, table_name, token):
        return self._index[table_name][token]

    def list_scenes(self):
        for scene in self.scene:
            print(scene["name"])
