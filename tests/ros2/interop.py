"""The other side of `kiss-odom ros2`, on an independent DDS stack (Eclipse Cyclone DDS).

Driven by tests/tests/ros2.rs. Publishes the KITTI .bin scans of a folder as ROS 2
sensor_msgs/PointCloud2 (x, y, z, intensity float32, as KITTI drivers publish them) on `rt/points`,
stamped from times.txt, at a fixed rate or (`--ack`) each once the odometry of the one before
came back, so that a slow node drops none; subscribes to nav_msgs/Odometry and tf2_msgs/TFMessage
and writes every message received as JSON (floats printed by repr(), which reads back to the same
bits). Types are declared the way rosidl lays them out, with ROS 2's DDS names
(`pkg::msg::dds_::Name_`).

Discovery is unicast over loopback: CYCLONEDDS_URI (set below unless already set) restricts
Cyclone to 127.0.0.1, disables multicast and names 127.0.0.1 as the peer, so the participants
find each other through the well-known unicast ports. Each side of a topic matches on its own,
and a reader drops what a writer it has not matched yet sends: this side waits for its own
matches, and with `--go-on-stdin` for a line on standard input from a caller that sees the
node's side (the Rust test, through the node's watch) before the first cloud.

usage: interop.py --folder DIR --domain N (--rate HZ | --ack) --out FILE.json [--frames N]
                  [--go-on-stdin] [--timeout S]
"""

import argparse
import json
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path

LOOPBACK = (
    "<CycloneDDS><Domain Id='any'><General><Interfaces>"
    "<NetworkInterface address='127.0.0.1'/></Interfaces>"
    "<AllowMulticast>false</AllowMulticast></General>"
    "<Discovery><ParticipantIndex>auto</ParticipantIndex>"
    "<MaxAutoParticipantIndex>30</MaxAutoParticipantIndex>"
    "<Peers><Peer address='127.0.0.1'/></Peers></Discovery></Domain></CycloneDDS>"
)
os.environ.setdefault("CYCLONEDDS_URI", LOOPBACK)

from cyclonedds.core import Policy, Qos  # noqa: E402
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.idl import IdlStruct  # noqa: E402
from cyclonedds.idl.types import array, float64, int32, sequence, uint8, uint32  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402
from cyclonedds.util import duration  # noqa: E402


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32
    nanosec: uint32


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time
    frame_id: str


@dataclass
class PointField(IdlStruct, typename="sensor_msgs::msg::dds_::PointField_"):
    name: str
    offset: uint32
    datatype: uint8
    count: uint32


@dataclass
class PointCloud2(IdlStruct, typename="sensor_msgs::msg::dds_::PointCloud2_"):
    header: Header
    height: uint32
    width: uint32
    fields: sequence[PointField]
    is_bigendian: bool
    point_step: uint32
    row_step: uint32
    data: sequence[uint8]
    is_dense: bool


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: float64
    y: float64
    z: float64


@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: float64
    y: float64
    z: float64
    w: float64


@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Vector3  # geometry_msgs/Point: the same three doubles
    orientation: Quaternion


@dataclass
class PoseWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::PoseWithCovariance_"):
    pose: Pose
    covariance: array[float64, 36]


@dataclass
class Twist(IdlStruct, typename="geometry_msgs::msg::dds_::Twist_"):
    linear: Vector3
    angular: Vector3


@dataclass
class TwistWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::TwistWithCovariance_"):
    twist: Twist
    covariance: array[float64, 36]


@dataclass
class Odometry(IdlStruct, typename="nav_msgs::msg::dds_::Odometry_"):
    header: Header
    child_frame_id: str
    pose: PoseWithCovariance
    twist: TwistWithCovariance


@dataclass
class Transform(IdlStruct, typename="geometry_msgs::msg::dds_::Transform_"):
    translation: Vector3
    rotation: Quaternion


@dataclass
class TransformStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TransformStamped_"):
    header: Header
    child_frame_id: str
    transform: Transform


@dataclass
class TFMessage(IdlStruct, typename="tf2_msgs::msg::dds_::TFMessage_"):
    transforms: sequence[TransformStamped]


FLOAT32 = 7


def kitti_cloud(path: Path, stamp: float) -> PointCloud2:
    data = path.read_bytes()
    n = len(data) // 16
    fields = [PointField(name, 4 * i, FLOAT32, 1) for i, name in enumerate("x y z intensity".split())]
    sec = int(stamp // 1)
    return PointCloud2(
        header=Header(Time(sec, round((stamp - sec) * 1e9)), "velodyne"),
        height=1,
        width=n,
        fields=fields,
        is_bigendian=False,
        point_step=16,
        row_step=16 * n,
        data=data[: 16 * n],
        is_dense=True,
    )


def vec(v):
    return [v.x, v.y, v.z]


def quat(q):
    return [q.x, q.y, q.z, q.w]


def wait_for(what, ok, timeout):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if ok():
            return
        time.sleep(0.005)
    sys.exit(f"interop.py: timed out waiting for {what}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--folder", type=Path, required=True)
    ap.add_argument("--domain", type=int, required=True)
    ap.add_argument("--rate", type=float, default=10.0)
    ap.add_argument("--ack", action="store_true",
                    help="send each cloud once the odometry of the one before came (no --rate)")
    ap.add_argument("--frames", type=int, default=None)
    ap.add_argument("--go-on-stdin", action="store_true",
                    help="after the matches, wait for a line on stdin before the first cloud")
    ap.add_argument("--timeout", type=float, default=60.0)
    ap.add_argument("--out", type=Path, required=True)
    a = ap.parse_args()

    scans = sorted((a.folder / "velodyne").glob("*.bin"))[: a.frames]
    times = [float(t) for t in (a.folder / "times.txt").read_text().split()]

    dp = DomainParticipant(a.domain)
    reliable = Qos(
        Policy.Reliability.Reliable(duration(seconds=1)),
        Policy.History.KeepLast(100),
        Policy.Durability.Volatile,
    )
    # rclcpp::SensorDataQoS, in XCDR1 as rmw_cyclonedds writes.
    sensor = Qos(
        Policy.Reliability.BestEffort,
        Policy.History.KeepLast(5),
        Policy.Durability.Volatile,
        Policy.DataRepresentation(use_cdrv0_representation=True),
    )
    odom_r = DataReader(dp, Topic(dp, "rt/kiss/odometry", Odometry), qos=reliable)
    tf_r = DataReader(dp, Topic(dp, "rt/tf", TFMessage), qos=reliable)
    cloud_w = DataWriter(dp, Topic(dp, "rt/points", PointCloud2), qos=sensor)

    wait_for(
        "the node (cloud reader, odometry and tf writers)",
        lambda: cloud_w.get_matched_subscriptions()
        and odom_r.get_matched_publications()
        and tf_r.get_matched_publications(),
        a.timeout,
    )
    if a.go_on_stdin:
        print("matched; waiting for the go on stdin", flush=True)
        sys.stdin.readline()

    odoms, tfs = [], []

    def drain():
        for m in odom_r.take(N=100):
            odoms.append(
                {
                    "stamp": [m.header.stamp.sec, m.header.stamp.nanosec],
                    "frame_id": m.header.frame_id,
                    "child_frame_id": m.child_frame_id,
                    "position": vec(m.pose.pose.position),
                    "orientation": quat(m.pose.pose.orientation),
                    "pose_covariance": list(m.pose.covariance),
                    "linear": vec(m.twist.twist.linear),
                    "angular": vec(m.twist.twist.angular),
                    "twist_covariance": list(m.twist.covariance),
                }
            )
        for m in tf_r.take(N=100):
            for t in m.transforms:
                tfs.append(
                    {
                        "stamp": [t.header.stamp.sec, t.header.stamp.nanosec],
                        "frame_id": t.header.frame_id,
                        "child_frame_id": t.child_frame_id,
                        "translation": vec(t.transform.translation),
                        "rotation": quat(t.transform.rotation),
                    }
                )

    start = time.monotonic()
    for k, path in enumerate(scans):
        if a.ack:
            wait_for(f"the odometry of cloud {k - 1}", lambda: drain() or len(odoms) >= k,
                     a.timeout)
        else:
            # Pacing at --rate (the sleep sets the pace; it waits for nothing).
            due = start + k / a.rate
            while time.monotonic() < due:
                drain()
                time.sleep(0.002)
        cloud_w.write(kitti_cloud(path, times[k]))
        print(f"sent {path.name} stamp {times[k]}", flush=True)

    # Until an odometry and a transform per cloud came (or the timeout: the caller counts).
    end = time.monotonic() + a.timeout
    while time.monotonic() < end and (len(odoms) < len(scans) or len(tfs) < len(scans)):
        drain()
        time.sleep(0.005)
    drain()
    a.out.write_text(json.dumps({"sent": len(scans), "odometry": odoms, "tf": tfs}))
    print(f"received {len(odoms)} odometry and {len(tfs)} tf messages for {len(scans)} clouds")


if __name__ == "__main__":
    main()
