"""Decodes one pcap that `kiss-odom simulate --format pcap` wrote with the independent
references, for tests/tests/sensors_simulated.rs to compare with the simulator's exact points.

  python dump_generated.py PCAP OUT.bin [--metadata JSON] [--cut DEG]

With --metadata, ouster-sdk decodes it (as `ouster` in dump_reference.py); otherwise
velodyne-decoder does (as `velodyne` there, cut at --cut degrees). OUT.bin gets the records of
dump_reference.RECORD; OUT.json the per-sweep point counts.
"""

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import dump_reference  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("pcap", type=Path)
    ap.add_argument("out", type=Path)
    ap.add_argument("--metadata", type=Path)
    ap.add_argument("--cut", type=float)
    a = ap.parse_args()
    pcap = a.pcap.resolve()
    if a.metadata:
        rec, counts, extra = dump_reference.ouster(pcap, a.metadata.resolve())
    else:
        rec, counts, extra = dump_reference.velodyne(pcap, a.cut)
    rec.tofile(a.out)
    a.out.with_suffix(".json").write_text(json.dumps({"counts": counts, **extra}))
    print(f"{pcap.name}: {len(counts)} sweeps, {len(rec)} points {counts}", file=sys.stderr)


if __name__ == "__main__":
    main()
