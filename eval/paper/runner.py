"""The sgdicp CLI runs of eval/reproduce.py (failures recorded, never raised), pairs files and
the CSV rows written."""
from __future__ import annotations

import csv
import json
import os
import subprocess

from peers import read_pairs, run_bench

from .config import CONFIGS, PAIRS_DIR


class Runner:
    """Runs the CLI and records failures instead of raising."""

    def __init__(self, sgdicp: str, out: str):
        self.sgdicp = sgdicp
        self.tmp = os.path.join(out, "tmp")
        os.makedirs(self.tmp, exist_ok=True)
        self.failures: list[tuple[str, str]] = []  # (what, why)

    def bench(self, pairs: list, label: str, config: str, extra: list[str], what: str,
              timeout: float = 900) -> list[dict]:
        """`sgdicp bench` on `pairs` (all from pairs file `label`); on failure retried pair by pair."""
        rows, err = self._bench_once(pairs, label, config, extra, timeout)
        if rows is not None:
            return rows
        if len(pairs) == 1:
            self.failures.append((f"{what}: {label}:{pairs[0].line} {config}", err))
            return []
        out = []
        for p in pairs:
            r, err = self._bench_once([p], label, config, extra, timeout)
            if r is None:
                self.failures.append((f"{what}: {label}:{p.line} {config}", err))
            else:
                out += r
        return out

    def _bench_once(self, pairs, label, config, extra, timeout):
        run = run_bench(self.sgdicp, pairs, CONFIGS[config] + extra, self.tmp, timeout)
        if run.status != "ok":
            return None, f"{run.status}: {run.note}"
        for r in run.rows:  # pair_line: the line of the pair in its own pairs file
            r["pairs"] = label
            r["config"] = config
            r.pop("pairs_file", None)
        return run.rows, ""

    def register_json(self, pair, args: list[str], what: str) -> dict | None:
        gt = " ".join(f"{v:.17g}" for v in pair.T_gt[:3, :].reshape(-1))
        cmd = [self.sgdicp, "register", pair.source, pair.reference, "--json", "--ground-truth", gt] + args
        try:
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
        except subprocess.TimeoutExpired:
            self.failures.append((what, "timeout"))
            return None
        if p.returncode != 0:
            self.failures.append((what, f"exit {p.returncode}: {p.stderr.strip()[-300:]}"))
            return None
        try:
            return json.loads(p.stdout)
        except json.JSONDecodeError as e:
            self.failures.append((what, f"bad JSON: {e}"))
            return None


def write_rows(path: str, rows: list[dict]) -> None:
    if not rows:
        open(path, "w").close()
        return
    keys = ["pairs", "pair_line", "config"] + [k for k in rows[0] if k not in ("pairs", "pair_line", "config")]
    for r in rows:
        for k in r:
            if k not in keys:
                keys.append(k)
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)


def load_pairs(stem_or_path: str) -> tuple[str, list]:
    path = stem_or_path if os.path.exists(stem_or_path) else os.path.join(PAIRS_DIR, stem_or_path + ".txt")
    return os.path.splitext(os.path.basename(path))[0], read_pairs(path)
