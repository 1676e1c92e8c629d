"""``kiss_odom.batch``: ``kiss-odom run`` over many sequences as Ray tasks, and one table.

One Ray task per sequence runs the ``kiss-odom`` command, ``kiss-odom run SEQUENCE --out
OUT/NAME``, so each sequence's outputs (``poses_kitti.txt``, ``poses_tum.txt``,
``summary.json``, ``frames.csv``, ...) are the command's own. The command is the one
``KISS_ODOM_BIN`` names, else ``kiss-odom`` on ``PATH`` (``cargo install --path host/cli``);
on a cluster every node needs it. A task that fails (a corrupt sequence) is
reported with the command's reason; the others complete. Then ``OUT/aggregate.csv`` and
``OUT/aggregate.md`` list per sequence the KITTI relative errors, ATE, Hz and peak memory,
and two totals for the KITTI errors: the devkit's (every 100-800 m segment of every sequence
weighs the same) and the mean of the per-sequence values.

Ray starts locally (``ray.init()``) unless ``address`` is given (``"auto"`` or
``ray://host:10001`` for a cluster). ``peak_rss_bytes`` is that sequence's command alone.

Output folders are named after the sequences: a sequence's folder or file name, with as many
of its parent folders before it (joined by ``-``) as it takes to tell it apart from the others
of that name (``a/00``, ``b/00`` -> ``a-00``, ``b-00``). A path given twice, or names that
still collide, are a ``ValueError`` before any task starts.

Ctrl-C (SIGINT) cancels the tasks still running, writes the tables of the sequences whose run
completed (also one whose task was cut short after its ``summary.json``; the others are listed
as ``interrupted``) and, on the command line, exits with 130; a second Ctrl-C ends it at once.

Command line: ``kiss-odom-batch SEQUENCE... --out DIR [--address A] [--num-cpus N]
[-- RUN FLAGS]``.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import shutil
import subprocess
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import numpy as np

COLUMNS = (
    "sequence", "status", "frames", "kitti_t_err_pct", "kitti_r_err_deg_per_m",
    "kitti_segments", "ate_m", "hz", "peak_rss_mib", "state_mib", "reason",
)


@dataclass
class Result:
    """One sequence's row of the aggregate table."""

    sequence: str
    status: str  # "ok", "failed" or "interrupted"
    frames: int = 0
    kitti_t_err_pct: float = math.nan
    kitti_r_err_deg_per_m: float = math.nan
    kitti_segments: int = 0
    ate_m: float = math.nan
    hz: float = math.nan
    peak_rss_mib: float = math.nan
    state_mib: float = math.nan
    reason: str = ""
    out: str = ""


@dataclass
class Batch:
    """Every sequence's result and the totals."""

    results: List[Result]
    totals: Dict[str, float] = field(default_factory=dict)
    #: Whether Ctrl-C stopped the batch (the unfinished sequences are ``interrupted``).
    interrupted: bool = False

    @property
    def failed(self) -> List[Result]:
        return [r for r in self.results if r.status != "ok"]


def _kitti_lines(path: Path) -> np.ndarray:
    rows = np.loadtxt(path, ndmin=2)
    out = np.tile(np.eye(4), (len(rows), 1, 1))
    out[:, :3, :4] = rows.reshape(-1, 3, 4)
    return out


def kiss_odom_command() -> str:
    """The ``kiss-odom`` executable: ``KISS_ODOM_BIN``, else ``kiss-odom`` on ``PATH``. Raises
    ``FileNotFoundError`` saying how to get it."""
    given = os.environ.get("KISS_ODOM_BIN")
    found = given or shutil.which("kiss-odom")
    if not found or not os.access(found, os.X_OK):
        where = f"KISS_ODOM_BIN={given} is not an executable" if given else \
            "no kiss-odom on PATH"
        raise FileNotFoundError(
            f"kiss-odom-batch runs the kiss-odom command: {where} (build it with "
            "`cargo install --path host/cli`, or set KISS_ODOM_BIN)")
    return found


def _die_with_parent() -> None:
    """In the child: SIGTERM when the task's worker goes (a cancelled task), so no run is left
    behind it; the command then writes what it has, as on any SIGTERM. Linux only."""
    import ctypes
    import signal

    try:
        ctypes.CDLL(None).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


def run_sequence(path: str, out: str, run_args: Sequence[str] = (),
                 command: Optional[str] = None) -> Result:
    """``kiss-odom run path --out out``, then this sequence's row. Raises ``RuntimeError``
    with the command's reason when it fails."""
    argv = [command or kiss_odom_command(), "run", str(path), "--out", str(out), "--quiet",
            *run_args]
    done = subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                          preexec_fn=_die_with_parent if sys.platform == "linux" else None)
    if done.returncode != 0:
        lines = done.stderr.strip().splitlines()
        reason = (lines[-1].removeprefix("error: ") if lines
                  else f"{path}: exit status {done.returncode}")
        raise RuntimeError(reason)
    return _row(path, out)


def _row(path: str, out: str) -> Result:
    """The row of a sequence whose ``kiss-odom run`` completed into ``out``."""
    from kiss_odom import _native

    name = Path(out).name
    summary = json.loads((Path(out) / "summary.json").read_text())
    metrics = summary.get("metrics") or {}
    row = Result(
        sequence=name,
        status="ok",
        frames=summary["frames"],
        ate_m=metrics.get("ate_m", math.nan),
        hz=summary["hz"],
        peak_rss_mib=(summary.get("peak_rss_bytes") or math.nan) / 2**20,
        state_mib=summary["state_bytes"] / 2**20,
        out=str(out),
    )
    gt = _native.ground_truth(str(path))
    if gt is not None and metrics:
        est = _kitti_lines(Path(out) / "poses_kitti.txt")
        gt = np.linalg.inv(gt[0]) @ gt[: len(est)]  # re-based to the first frame, as run does
        t, r, n = _native.kitti_relative_error_segments(est, gt)
        row.kitti_t_err_pct, row.kitti_r_err_deg_per_m, row.kitti_segments = t, r, n
    return row


def _names(paths: Sequence[Path]) -> List[str]:
    """Output folder names (see the module doc): unique, each from its own path."""
    seen: Dict[Path, Path] = {}
    for given in paths:
        real = given.resolve()
        if real in seen:
            raise ValueError(f"{given}: given twice (as {seen[real]})")
        seen[real] = given
    # Named as given (made absolute), links not followed.
    absolute = [Path(os.path.abspath(p)) for p in paths]
    names = []
    for p in absolute:
        parts = p.parts[1:] or ("sequence",)
        same = [q.parts[1:] for q in absolute if q.name == p.name]
        depth = 1
        while len({q[-depth:] for q in same}) < len(same):
            depth += 1
        names.append("-".join(parts[-depth:]))
    first: Dict[str, int] = {}
    for i, name in enumerate(names):
        j = first.setdefault(name.casefold(), i)
        if j != i:
            raise ValueError(
                f"{paths[j]} and {paths[i]} would both write to {name}/: rename one of them")
    return names


def totals(results: Sequence[Result]) -> Dict[str, float]:
    """The devkit's segment-weighted KITTI errors over all sequences, and the per-sequence
    means (over sequences that have segments)."""
    scored = [r for r in results if r.status == "ok" and r.kitti_segments > 0]
    n = sum(r.kitti_segments for r in scored)
    weighted = lambda k: sum(getattr(r, k) * r.kitti_segments for r in scored) / n if n else math.nan
    mean = lambda k: float(np.mean([getattr(r, k) for r in scored])) if scored else math.nan
    return {
        "kitti_t_err_pct_devkit": weighted("kitti_t_err_pct"),
        "kitti_r_err_deg_per_m_devkit": weighted("kitti_r_err_deg_per_m"),
        "kitti_t_err_pct_mean": mean("kitti_t_err_pct"),
        "kitti_r_err_deg_per_m_mean": mean("kitti_r_err_deg_per_m"),
        "kitti_segments": n,
        "sequences_scored": len(scored),
    }


def _fmt(v) -> str:
    if isinstance(v, float):
        return "" if math.isnan(v) else f"{v:.6g}"
    return str(v)


def write_tables(out: Path, batch: Batch) -> None:
    """``aggregate.csv`` (one row per sequence, then the totals) and ``aggregate.md``."""
    with open(out / "aggregate.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(COLUMNS)
        for r in batch.results:
            d = asdict(r)
            w.writerow([_fmt(d[c]) for c in COLUMNS])
        for k, v in batch.totals.items():
            w.writerow([f"total:{k}", "", _fmt(v)] + [""] * (len(COLUMNS) - 3))
    lines = ["| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    for r in batch.results:
        d = asdict(r)
        lines.append("| " + " | ".join(_fmt(d[c]).replace("|", "/") for c in COLUMNS) + " |")
    lines += ["", "| total | value |", "|---|---|"]
    lines += [f"| {k} | {_fmt(v)} |" for k, v in batch.totals.items()]
    (out / "aggregate.md").write_text("\n".join(lines) + "\n")


def run_batch(
    sequences: Sequence[str],
    out: str,
    run_args: Sequence[str] = (),
    address: Optional[str] = None,
    num_cpus: Optional[int] = None,
    progress: bool = True,
) -> Batch:
    """Runs every sequence as a Ray task, writes the tables and returns the results (failed
    sequences included, with their reason)."""
    import ray

    paths = [Path(s) for s in sequences]
    names = _names(paths)  # a collision is an error before anything starts
    command = kiss_odom_command()  # so is a missing command
    out_dir = Path(out)
    out_dir.mkdir(parents=True, exist_ok=True)
    by_name: Dict[str, Result] = {}
    interrupted = False
    began = time.time()
    pending: Dict = {}
    started = not ray.is_initialized()
    try:
        if started:
            if address:
                ray.init(address=address, log_to_driver=False)
            else:
                ray.init(num_cpus=num_cpus, include_dashboard=False, log_to_driver=False)
        task = ray.remote(num_cpus=1, max_retries=0)(run_sequence)
        pending = {
            task.remote(str(p.resolve()), str((out_dir / n).resolve()), list(run_args),
                        command): n
            for p, n in zip(paths, names)
        }
        bar = _bar(len(pending), progress)
        # Ctrl-C sets a flag that the loop reads between waits: a KeyboardInterrupt raised
        # inside ray.wait can be lost there (seen under load: the batch waited on, the signal
        # gone), a flag cannot.
        stop = _sigint_flag()
        try:
            while pending:
                if stop.is_set():
                    raise KeyboardInterrupt
                # A timeout, so that Ctrl-C is seen while every task is still running.
                done, _ = ray.wait(list(pending), num_returns=1, timeout=0.2)
                if not done:
                    continue
                ref = done[0]
                name = pending.pop(ref)
                try:
                    by_name[name] = ray.get(ref)
                except Exception as e:  # a failed task: keep its reason, the others go on
                    cause = getattr(e, "cause", None) or e
                    by_name[name] = Result(sequence=name, status="failed",
                                           reason=str(cause).strip().splitlines()[-1])
                bar.set_postfix_str(f"{name}: {by_name[name].status}")
                bar.update(1)
        except KeyboardInterrupt:
            interrupted = True
            _second_interrupt_ends_the_process()
            # A run that completed before the signal finished, whether or not its task got
            # to return; the others are cancelled on the way out.
            for ref, name in pending.items():
                i = names.index(name)
                if _completed_since(out_dir / name, began):
                    try:
                        by_name[name] = _row(str(paths[i].resolve()),
                                             str((out_dir / name).resolve()))
                    except Exception:  # noqa: BLE001 - its outputs are not whole: unfinished
                        pass
        bar.close()
    except KeyboardInterrupt:  # before the tasks started (Ray starting)
        interrupted = True
        _second_interrupt_ends_the_process()
    finally:
        if not interrupted:
            _default_sigint()
        if started and ray.is_initialized():
            _stop_ray(ray, list(pending) if interrupted else [], bounded=interrupted)
    results = [by_name.get(n) or Result(sequence=n, status="interrupted",
                                        reason="interrupted before it finished")
               for n in names]
    batch = Batch(results=results, totals=totals(results), interrupted=interrupted)
    write_tables(out_dir, batch)
    return batch


def _sigint_flag():
    """An event that SIGINT sets from now on (in the main thread; elsewhere one never set)."""
    import signal
    import threading

    flag = threading.Event()
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, lambda *_: flag.set())
    return flag


def _default_sigint() -> None:
    """Ctrl-C raises KeyboardInterrupt again (in the main thread)."""
    import signal
    import threading

    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.default_int_handler)


# Seconds an interrupted batch gives Ray's cancel and shutdown before it writes its tables
# and exits without them: once, under heavy load, they never returned.
STOP_S = 20.0


def _stop_ray(ray, cancel, bounded: bool, seconds: float = STOP_S) -> None:
    """Cancels the tasks in ``cancel`` (their runs get SIGTERM and write what they have) and
    shuts Ray down; when ``bounded``, gives up waiting after ``seconds`` (the processes
    ``ray.init`` started die with this one on Linux: Ray makes them share its fate)."""
    def stop():
        try:
            for ref in cancel:
                ray.cancel(ref, force=True)
        except Exception:  # noqa: BLE001 - a task that ended meanwhile: nothing to cancel
            pass
        ray.shutdown()

    if not bounded:
        stop()
        return
    import threading

    worker = threading.Thread(target=stop, daemon=True)
    worker.start()
    worker.join(seconds)


def _completed_since(out: Path, began: float) -> bool:
    """Whether ``out`` holds a complete run written after ``began``."""
    path = out / "summary.json"
    try:
        if path.stat().st_mtime < began:
            return False  # an earlier batch's
        summary = json.loads(path.read_text())
    except (OSError, ValueError):
        return False
    return not summary.get("interrupted") and summary.get("stop_reason") is None


def _second_interrupt_ends_the_process() -> None:
    import signal

    signal.signal(signal.SIGINT, lambda *_: os._exit(130))


def _bar(total: int, enabled: bool):
    from tqdm import tqdm

    return tqdm(total=total, unit="seq", desc="kiss-odom-batch", disable=not enabled)


def main(argv: Optional[Sequence[str]] = None) -> int:
    import faulthandler
    import signal

    # SIGUSR1 prints every thread's Python stack: what a run that does not stop is doing.
    if hasattr(signal, "SIGUSR1"):
        faulthandler.register(signal.SIGUSR1, all_threads=True)
    argv = list(sys.argv[1:] if argv is None else argv)
    run_args: List[str] = []
    if "--" in argv:
        i = argv.index("--")
        argv, run_args = argv[:i], argv[i + 1:]
    p = argparse.ArgumentParser(
        prog="kiss-odom-batch",
        description="kiss-odom run over many sequences as Ray tasks, with an aggregate table. "
        "Flags after -- go to every `kiss-odom run`.",
    )
    p.add_argument("sequences", nargs="+", help="dataset folders or files, as for kiss-odom run")
    p.add_argument("--out", required=True, help="output folder: one subfolder per sequence")
    p.add_argument("--address", help="Ray cluster address (default: start Ray locally)")
    p.add_argument("--num-cpus", type=int, help="CPUs for a local Ray (default: all)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    a = p.parse_args(argv)
    try:
        batch = run_batch(a.sequences, a.out, run_args, a.address, a.num_cpus, not a.quiet)
    except (ValueError, FileNotFoundError) as e:
        p.error(str(e))
    except KeyboardInterrupt:  # before Ray was imported: nothing ran, nothing to write
        print("interrupted before any sequence started", file=sys.stderr)
        return 130
    print((Path(a.out) / "aggregate.md").read_text())
    for r in batch.failed:
        if r.status == "failed":
            print(f"failed: {r.sequence}: {r.reason}", file=sys.stderr)
    if batch.interrupted:
        done = sum(r.status != "interrupted" for r in batch.results)
        print(f"interrupted: the tables hold the {done} of {len(batch.results)} sequences "
              "that finished", file=sys.stderr)
        # Not through the interpreter's exit: Ray's own exit hook would wait for the shutdown
        # that `_stop_ray` may have given up on.
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(130)
    return 1 if batch.failed else 0


if __name__ == "__main__":
    sys.exit(main())
