#!/usr/bin/env python3
"""A generated drive (`kiss-odom simulate --imu-rate`) with a wrong but plausible IMU: the
drive's frames, times and ground truth linked, its `imu.csv` rewritten as VARIANT says.
Used by bench/imu_check.sh; standard library only.

    bench/imu_wrong.py DRIVE VARIANT OUT [OTHER]

VARIANT: right (the file as it is), degs (gyroscope in deg/s), flipx / flipz (that axis's
sign flipped), dead (gyroscope all zeros), spike (one sample of 1e6 rad/s at 0.5 s), other
(OTHER's imu.csv: another flight's), dup (each sample followed by another at the same time
with OTHER's rates), stopT (the right samples before T s, then none).
"""
import math
import os
import sys

HEADER = "time,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z"


def rows(path):
    with open(path) as f:
        lines = f.read().split("\n")
    assert lines[0].strip() == HEADER, path
    return [l.split(",") for l in lines[1:] if l.strip()]


def main():
    drive, variant, out = sys.argv[1:4]
    other = sys.argv[4] if len(sys.argv) > 4 else None
    os.makedirs(out, exist_ok=True)
    for name in os.listdir(drive):
        if name != "imu.csv" and not os.path.exists(os.path.join(out, name)):
            os.symlink(os.path.realpath(os.path.join(drive, name)), os.path.join(out, name))
    r = rows(os.path.join(drive, "imu.csv"))
    gyro = lambda row, f: [row[0]] + [repr(f(i, float(row[1 + i]))) for i in range(3)] + row[4:]
    if variant == "right":
        pass
    elif variant == "degs":
        r = [gyro(x, lambda i, g: math.degrees(g)) for x in r]
    elif variant in ("flipx", "flipy", "flipz"):
        axis = "xyz".index(variant[-1])
        r = [gyro(x, lambda i, g: -g if i == axis else g) for x in r]
    elif variant == "dead":
        r = [gyro(x, lambda i, g: 0.0) for x in r]
    elif variant == "spike":
        k = min(range(len(r)), key=lambda j: abs(float(r[j][0]) - 0.5))
        r[k] = gyro(r[k], lambda i, g: 1e6 if i == 0 else g)
    elif variant == "other":
        r = rows(os.path.join(other, "imu.csv"))
    elif variant == "dup":
        o = rows(os.path.join(other, "imu.csv"))
        r = [row for a, b in zip(r, o) for row in (a, [a[0]] + b[1:])]
    elif variant.startswith("stop"):
        r = [x for x in r if float(x[0]) < float(variant[4:])]
    else:
        sys.exit(f"unknown variant {variant}")
    with open(os.path.join(out, "imu.csv"), "w") as f:
        f.write(HEADER + "\n" + "".join(",".join(x) + "\n" for x in r))


main()
