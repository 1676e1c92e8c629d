"""`kiss_odom.batch` on a local Ray: four kitti-mini sequences, two generated ones and a
corrupt one. Each sequence's outputs are byte-equal to `kiss-odom run`'s, the aggregate table
is written, and the corrupt sequence is reported with its reason while the others complete."""

from __future__ import annotations

import csv
import math

import pytest

from conftest import KITTI_SEQUENCES, kiss_odom, kitti_root
from kiss_odom.batch import Result, run_batch, totals

pytest.importorskip("ray", reason="SKIP: ray not installed")


@pytest.fixture(scope="module")
def batch(generated_short, tmp_path_factory):
    root = tmp_path_factory.mktemp("batch")
    corrupt = root / "corrupt.mcap"
    corrupt.write_bytes(b"\x89MCAP0\r\n" + bytes(range(256)) * 4)
    sequences = [kitti_root() / "sequences" / s for s in KITTI_SEQUENCES]
    sequences += list(generated_short) + [corrupt]
    out = root / "out"
    result = run_batch([str(s) for s in sequences], str(out), num_cpus=2, progress=False)
    return sequences, out, result


def test_every_sequence_writes_what_kiss_odom_run_writes(batch, tmp_path):
    sequences, out, result = batch
    ok = [r for r in result.results if r.status == "ok"]
    assert len(ok) == 6
    for seq, r in zip(sequences, result.results):
        if r.status != "ok":
            continue
        ref = tmp_path / r.sequence
        kiss_odom("run", seq, "--out", ref, "--quiet")
        for name in ("poses_kitti.txt", "poses_tum.txt", "config.toml"):
            same = (out / r.sequence / name).read_bytes() == (ref / name).read_bytes()
            print(f"{r.sequence}/{name}: byte-equal to kiss-odom run: {same}")
            assert same
        assert (out / r.sequence / "summary.json").is_file()
        assert (out / r.sequence / "frames.csv").is_file()


def test_the_corrupt_sequence_is_reported_with_its_reason(batch):
    _, _, result = batch
    (failed,) = result.failed
    print(f"{failed.sequence}: {failed.reason}")
    assert failed.sequence == "corrupt.mcap" and "corrupt.mcap" in failed.reason
    # The command's own one-line reason, not a Ray traceback.
    assert "PointCloud2" in failed.reason and "\n" not in failed.reason
    assert "Traceback" not in failed.reason


def test_the_aggregate_table_has_every_sequence_and_both_kitti_totals(batch):
    sequences, out, result = batch
    rows = list(csv.DictReader(open(out / "aggregate.csv")))
    per_seq = [r for r in rows if not r["sequence"].startswith("total:")]
    assert [r["sequence"] for r in per_seq] == [s.name for s in sequences]
    for r in per_seq:
        if r["status"] == "ok":
            assert float(r["ate_m"]) >= 0 and float(r["hz"]) > 0 and float(r["peak_rss_mib"]) > 0
    scored = [r for r in result.results if r.kitti_segments > 0]
    assert [r.sequence for r in scored] == ["fast-s1"], "only the fast drive passes 100 m"
    t = result.totals
    assert t["kitti_segments"] == scored[0].kitti_segments
    assert t["kitti_t_err_pct_devkit"] == pytest.approx(scored[0].kitti_t_err_pct)
    assert "kitti_t_err_pct_devkit" in (out / "aggregate.md").read_text()


def test_the_devkit_total_weighs_segments_and_the_mean_weighs_sequences():
    rows = [Result("a", "ok", kitti_t_err_pct=1.0, kitti_r_err_deg_per_m=0.1, kitti_segments=30),
            Result("b", "ok", kitti_t_err_pct=2.0, kitti_r_err_deg_per_m=0.2, kitti_segments=10),
            Result("c", "ok"), Result("d", "failed", reason="x")]
    t = totals(rows)
    assert t["kitti_t_err_pct_devkit"] == pytest.approx((30 * 1.0 + 10 * 2.0) / 40)
    assert t["kitti_t_err_pct_mean"] == pytest.approx(1.5)
    assert t["kitti_r_err_deg_per_m_devkit"] == pytest.approx(0.125)
    assert t["sequences_scored"] == 2 and t["kitti_segments"] == 40
    assert math.isnan(totals([])["kitti_t_err_pct_devkit"])


def test_the_console_script_reports_the_failure_and_exits_1(tmp_path):
    import subprocess
    import sys
    from pathlib import Path

    corrupt = tmp_path / "corrupt.mcap"
    corrupt.write_bytes(b"not an mcap file")
    script = Path(sys.executable).parent / "kiss-odom-batch"
    seq = kitti_root() / "sequences" / "05"
    out = subprocess.run([str(script), str(seq), str(corrupt), "--out", str(tmp_path / "out"),
                          "--num-cpus", "2", "--", "--threads", "1"],
                         capture_output=True, text=True)
    print(out.stdout)
    assert out.returncode == 1, out.stderr[-2000:]
    assert "failed: corrupt.mcap:" in out.stderr
    assert "| 05 | ok |" in out.stdout
    kiss_odom("run", seq, "--out", tmp_path / "ref", "--quiet")
    assert (tmp_path / "out" / "05" / "poses_kitti.txt").read_bytes() == \
        (tmp_path / "ref" / "poses_kitti.txt").read_bytes()


def test_output_names_come_from_the_paths_and_a_collision_is_refused_before_any_task(tmp_path):
    from kiss_odom.batch import _names

    for d in ("a/00", "b/00", "c/00-2", "x/b-00", "y/b/00"):
        (tmp_path / d).mkdir(parents=True)
    t = tmp_path
    assert _names([t / "a/00", t / "b/00", t / "c/00-2"]) == ["a-00", "b-00", "00-2"]
    # From each path alone: the order does not change a name.
    assert _names([t / "c/00-2", t / "b/00", t / "a/00"]) == ["00-2", "b-00", "a-00"]
    with pytest.raises(ValueError, match="given twice"):
        _names([t / "a/00", t / "b/../a/00"])
    with pytest.raises(ValueError, match="would both write to b-00"):
        _names([t / "x/b-00", t / "b/00", t / "a/00"])
    # The console script says so and starts nothing.
    import subprocess
    import sys
    from pathlib import Path

    script = Path(sys.executable).parent / "kiss-odom-batch"
    out = subprocess.run([str(script), str(t / "a/00"), str(t / "a/00"), "--out", str(t / "out")],
                         capture_output=True, text=True)
    assert out.returncode == 2 and "given twice" in out.stderr, out.stderr
    assert "Traceback" not in out.stderr and not (t / "out").exists()


def test_the_same_name_in_two_folders_gives_two_outputs_and_two_rows(tmp_path):
    import shutil

    from conftest import REPO

    a, b = tmp_path / "a" / "05", tmp_path / "b" / "05"
    for d in (a, b):
        shutil.copytree(REPO / "fixtures" / "kitti-05-reduced", d)
    result = run_batch([str(a), str(b)], str(tmp_path / "out"), ["--frames", "0..3"],
                       num_cpus=2, progress=False)
    assert [r.sequence for r in result.results] == ["a-05", "b-05"]
    assert all(r.status == "ok" for r in result.results)
    rows = list(csv.DictReader(open(tmp_path / "out" / "aggregate.csv")))
    assert [r["sequence"] for r in rows if not r["sequence"].startswith("total:")] == \
        ["a-05", "b-05"]
    for n in ("a-05", "b-05"):
        assert (tmp_path / "out" / n / "poses_kitti.txt").is_file()


def test_sigint_writes_the_tables_of_what_finished_and_exits_130_without_a_traceback(tmp_path):
    import os
    import signal
    import subprocess
    import sys
    import time
    from pathlib import Path

    # A long sequence (minutes of frames: links to the sample's scans, forth and back) beside
    # a short one.
    sample = kitti_root() / "sequences" / "05" / "velodyne"
    scans = sorted(sample.glob("*.bin"))
    long = tmp_path / "long" / "velodyne"
    long.mkdir(parents=True)
    for k in range(6000):
        lap, i = divmod(k, len(scans))
        os.symlink(scans[i if lap % 2 == 0 else len(scans) - 1 - i], long / f"{k:06}.bin")
    short = kitti_root() / "sequences" / "05"
    out = tmp_path / "out"
    script = Path(sys.executable).parent / "kiss-odom-batch"
    child = subprocess.Popen([str(script), str(short), str(long.parent), "--out", str(out),
                              "--num-cpus", "2", "--quiet", "--", "--threads", "1"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    # The short sequence's summary is its acknowledgement: it finished.
    start = time.monotonic()
    while not (out / "05" / "summary.json").is_file():
        assert child.poll() is None, child.communicate()
        assert time.monotonic() - start < 600, "the short sequence never finished"
        time.sleep(0.1)
    assert not (out / "long" / "summary.json").exists(), "the long one finished first"
    child.send_signal(signal.SIGINT)
    try:
        # A guard against a hang, not a speed test: idle, the exit takes a few seconds, and
        # the batch gives Ray's cancel and shutdown at most 20 s.
        stdout, stderr = child.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        child.send_signal(signal.SIGUSR1)  # its threads' Python stacks, to stderr
        time.sleep(2)
        child.kill()
        _, stderr = child.communicate()
        raise AssertionError(f"no exit 120 s after SIGINT; its stacks:\n{stderr[-6000:]}")
    print(stderr[-2000:])
    assert child.returncode == 130, stderr[-2000:]
    assert "Traceback" not in stderr and "KeyboardInterrupt" not in stderr
    rows = {r["sequence"]: r for r in csv.DictReader(open(out / "aggregate.csv"))}
    assert rows["05"]["status"] == "ok" and float(rows["05"]["frames"]) == 10
    assert rows["long"]["status"] == "interrupted"
    assert "| 05 | ok |" in (out / "aggregate.md").read_text()


def test_an_interrupted_batch_stops_waiting_for_a_ray_that_never_stops():
    import threading
    import time

    from kiss_odom import batch

    release = threading.Event()
    calls = []

    class Stuck:
        def cancel(self, ref, force):
            calls.append(("cancel", ref, force))
            release.wait(10)

        def shutdown(self):
            calls.append(("shutdown",))
            release.wait(10)

    start = time.monotonic()
    batch._stop_ray(Stuck(), ["task"], bounded=True, seconds=0.3)
    took = time.monotonic() - start
    release.set()
    assert 0.3 <= took < 5, took
    assert calls[0] == ("cancel", "task", True)

    # Not interrupted: the shutdown is waited for, however long it takes.
    slow_calls = []

    class Slow:
        def cancel(self, ref, force):
            slow_calls.append(("cancel", ref, force))

        def shutdown(self):
            time.sleep(0.5)
            slow_calls.append(("shutdown",))

    batch._stop_ray(Slow(), [], bounded=False)
    assert slow_calls == [("shutdown",)]
