"""The sgdicp CLI's `bench` on a list of pairs, as a child process with a time limit."""

from __future__ import annotations

import csv
import math
import os
import shutil
import signal
import subprocess
import tempfile
import time
from dataclasses import dataclass, field

from .pairs import Pair, write_pairs

GNU_TIME = "/usr/bin/time"


@dataclass
class BenchRun:
    """One `sgdicp bench --csv` run: its rows, or why there are none."""

    status: str  # "ok", "error" (nonzero exit, no CSV), "timeout", "crashed" (killed by a signal)
    rows: list[dict] = field(default_factory=list)  # CSV rows + "pair_line": line in the pair's own file
    note: str = ""
    peak_rss_mb: float = math.nan  # of the CLI process (GNU time), when asked for
    wall_ms: float = math.nan  # of the whole process


def run_bench(exe: str, pairs: list[Pair], args: list[str], tmp_dir: str, timeout_s: float,
              peak_rss: bool = False) -> BenchRun:
    """`exe bench PAIRS --csv CSV ARGS` on `pairs` (written to a pairs file in a fresh folder of
    tmp_dir, removed afterwards). The process (and what it started) is killed after timeout_s.
    peak_rss: measure the CLI's peak RSS with GNU time (a child forked from a large Python
    process reports the parent's RSS as its own maximum)."""
    work = tempfile.mkdtemp(prefix="bench_", dir=tmp_dir)
    try:
        pairs_file = os.path.join(work, "pairs.txt")
        out_csv = os.path.join(work, "rows.csv")
        rss_file = os.path.join(work, "maxrss")
        write_pairs(pairs_file, pairs)
        cmd = [exe, "bench", pairs_file, "--csv", out_csv] + list(args)
        if peak_rss and os.path.exists(GNU_TIME):
            cmd = [GNU_TIME, "-f", "%M", "-o", rss_file] + cmd
        t0 = time.perf_counter()
        # A session of its own: on a timeout the whole group goes (GNU time and the CLI).
        p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             start_new_session=True)
        try:
            out, err = p.communicate(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            p.communicate()
            note = f"no answer within {timeout_s:g} s (sgdicp bench {' '.join(args)})"
            return BenchRun("timeout", note=note, wall_ms=(time.perf_counter() - t0) * 1e3)
        wall_ms = (time.perf_counter() - t0) * 1e3
        run = BenchRun("ok", wall_ms=wall_ms, peak_rss_mb=_peak_rss_mb(rss_file))
        if p.returncode != 0 or not os.path.exists(out_csv):
            # GNU time exits with 128 + the signal that ended the CLI
            sig = -p.returncode if p.returncode < 0 else p.returncode - 128 if cmd[0] == GNU_TIME else 0
            why = (err or out).strip().replace("\n", " ")[-300:]
            if sig > 0:
                run.status, run.note = "crashed", f"killed by signal {sig}: {why}"
            else:
                run.status, run.note = "error", f"exit {p.returncode}: {why}"
            return run
        with open(out_csv, newline="") as f:
            run.rows = list(csv.DictReader(f))
        for r in run.rows:  # the temporary file has one pair per line, in order
            r["pair_line"] = pairs[int(r["line"]) - 1].line
        return run
    finally:
        shutil.rmtree(work, ignore_errors=True)


def _peak_rss_mb(path: str) -> float:
    try:
        with open(path) as f:
            return float(f.read().split()[-1]) / 1024.0
    except (OSError, ValueError, IndexError):
        return math.nan
