"""ouster-sdk 1.0.1's reading of an Ouster recording's IMU packets, as JSON on stdout:
one object per packet, in capture order, with the times (ns) and values as ouster-sdk
returns them (acceleration in m/s^2, angular velocity in rad/s: it converts the packet's g and
deg/s).

    python dump_imu.py RECORDING.pcap METADATA.json
"""

import json
import sys

from ouster.sdk import core, open_packet_source


def main():
    pcap, meta = sys.argv[1], sys.argv[2]
    out = []
    for item in open_packet_source(pcap, meta=[meta]):
        packet = item[1] if isinstance(item, tuple) else item
        if isinstance(packet, core.ImuPacket):
            out.append(
                {
                    "sys_ts": int(packet.sys_ts()),
                    "accel_ts": int(packet.accel_ts()),
                    "gyro_ts": int(packet.gyro_ts()),
                    "accel": [float(v) for v in packet.accel().ravel()],
                    "gyro": [float(v) for v in packet.gyro().ravel()],
                }
            )
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main()
