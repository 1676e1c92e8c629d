"""One `KissICP` shared by Python threads (its calls are serialised, none fails), and the
memory a huge frame takes given back after it."""

from __future__ import annotations

import gc
import os
import threading

import numpy as np
import pytest

import kiss_odom
from conftest import kitti_frames


def test_threads_sharing_one_object_wait_for_each_other_and_every_frame_registers():
    frames = list(kitti_frames("05"))[:8]
    odom = kiss_odom.KissICP(threads=1)
    errors, done = [], threading.Event()

    def register():
        try:
            for f in frames:
                odom.register_frame(f, np.array([]))
        except Exception as e:  # noqa: BLE001 - the test reports whatever a thread raised
            errors.append(repr(e))

    def read():
        while not done.is_set():
            try:
                odom.last_pose, odom.local_map.empty(), odom.sigma
            except Exception as e:  # noqa: BLE001
                errors.append(repr(e))
                return

    workers = [threading.Thread(target=register) for _ in range(2)]
    reader = threading.Thread(target=read)
    for t in workers + [reader]:
        t.start()
    for t in workers:
        t.join()
    done.set()
    reader.join()
    print(f"errors from the threads: {errors}")
    assert errors == []
    assert odom.last_report.index == 2 * len(frames) - 1, "every frame of both threads"


def _rss_bytes() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


@pytest.mark.skipif(not os.path.exists("/proc/self/statm"), reason="SKIP: no /proc")
def test_a_ten_million_point_frame_gives_its_memory_back():
    odom = kiss_odom.KissICP()
    scan = next(iter(kitti_frames("05")))
    odom.register_frame(scan, np.array([]))
    gc.collect()
    before, state_before = _rss_bytes(), odom.state_bytes
    huge = np.random.default_rng(7).uniform(-50.0, 50.0, (10_000_000, 3))
    deskewed, source = odom.register_frame(huge, np.array([]))
    assert len(deskewed) > 0 and odom.last_report.input_points == len(huge)
    del huge, deskewed, source
    gc.collect()
    # The core's state grew to hold the frame and its map, as kiss-icp's would (state_bytes
    # says by how much); everything else the frame needed is given back, but for the frame
    # buffers' usual size and what the allocator keeps of the arenas the moves freed.
    grown = odom.state_bytes - state_before
    after = _rss_bytes()
    print(f"RSS after the 10M-point frame: {(after - before) / 2**20:+.1f} MiB, of which the "
          f"core's state grew {grown / 2**20:+.1f} MiB (allowed +96 MiB beyond it)")
    assert grown > 0
    assert after - before - grown < 96 * 2**20
