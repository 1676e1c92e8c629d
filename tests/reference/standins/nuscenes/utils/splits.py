"""The mini splits' scenes (as the devkit lists them) and their logs."""

MINI = {
    "mini_train": ["scene-0061", "scene-0553", "scene-0655", "scene-0757", "scene-0796",
                   "scene-1077", "scene-1094", "scene-1100"],
    "mini_val": ["scene-0103", "scene-0916"],
}


def create_splits_logs(split, nusc):
    assert split in MINI and nusc.version.endswith("mini"), (split, nusc.version)
    scene_to_log = {s["name"]: nusc.get("log", s["log_token"])["logfile"] for s in nusc.scene}
    return list({scene_to_log[name] for name in MINI[split]})
