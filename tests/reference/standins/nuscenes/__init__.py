"""Stand-in for the part of nuscenes-devkit kiss-icp's nuScenes loader uses, written from the
nuScenes table schema: the `NuScenes` tables with `get` and the key frames of each sample
(`sample["data"][channel]`), the mini splits' logs, `LidarPointCloud.from_file` and
`transform_matrix`. Only on the path when the devkit itself cannot be imported (it needs numpy
below 2 and several hundred MB of dependencies); dump_layout.py reports that it was used, and
bench/layouts.sh runs the same comparison with the devkit."""
STAND_IN = True
