#!/usr/bin/env python3
"""Reproduce the experiments of Maken, Ramos & Ott, "Speeding up ICP with SGD" (ICRA 2019), sec. IV.

usage: eval/reproduce.py [--quick] [--out DIR] [--sgdicp PATH] [--jobs N] [--fig2-seeds N] [--repeat N]
                         [--no-peers | --peers LIST] [--timeout SECONDS] [PAIRS_FILES ...]

The paper's ETH Kinect sequences (medium-medium-fly/-translation/-rotation) are not available;
this script uses the data of ../shared/data instead (Kinect-class: PCL OpenNI frames and the ETH
Kinect high-complexity map with moved copies; laser: libpointmatcher car; Velodyne: KITTI seq 00)
and says so in the report. Every registration of ours is run by the sgdicp CLI (`bench`,
`register`). Table I also has the peer libraries users would pick instead (small_gicp, Open3D,
PCL through bench/pcl_adapter), measured in the same run on the same pairs by the runners of
bench/compare_peers.py (the package's sgd_icp.peers: each registration in a worker process, stopped
after --timeout); a peer that is not installed or not built is reported as not run. Needs the
sgd_icp package (`pip install .`) and matplotlib.

Writes into --out (default results/reproduce):
  table1.csv / table2.csv / fig2.csv / fig4.csv  raw rows of `sgdicp bench --csv` (+ config column;
                                                 peer rows of table1: + peer_method, status, note)
  fig1.csv                                       error vs points processed per method (car pair)
  fig1_data_efficiency.png, fig2_initial_translation.png, fig2_initial_rotation.png,
  fig4_batch_*.png                               figures (3.5 x 2.6 in, 200 dpi)
  report.md                                      tables, figures, failures, sanity checks
Progress goes to stderr. A failing pair/method/peer is recorded in the report, never fatal.
--quick runs a subset (< 3 min on 2 cores; peers: small_gicp ICP and Open3D point-to-point only)
and ends with `N passed, M failed` of sanity checks (`, K skipped` for checks of peers that are
not installed); the exit status is nonzero if a check fails.
"""
from __future__ import annotations

import argparse
import concurrent.futures as cf
import csv
import importlib.metadata
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

try:
    # pairs files, the `sgdicp bench` runner and the peers' runners (those of bench/compare_peers.py)
    from sgd_icp.peers import (SUCCESS_THRESHOLDS, PeerSettings, Session, build_methods, find_pcl_adapter,
                               read_pairs, run_bench)
except ImportError as e:
    sys.exit(f"eval/reproduce.py needs the sgd_icp Python package ({e}): "
             "run `pip install .` in the repository (docs/python.md)")

import numpy as np  # noqa: E402
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

DATA = os.path.normpath(os.path.join(REPO, "..", "shared", "data"))
PAIRS_DIR = os.path.join(DATA, "pairs")
TABLE1_DEFAULT = ["libpointmatcher_car", "pcl_kinect_frames", "eth_kinect_map_moved_copies", "kitti_seq00"]

# name -> CLI arguments. Batch methods are deterministic from a fixed start: one repeat suffices.
CONFIGS = {
    "SGD-ICP fixed step (paper)": ["--method", "sgd", "--preset", "paper", "--optimizer", "sgd"],
    "SGD-ICP Adam (paper)": ["--method", "sgd", "--preset", "paper", "--optimizer", "adam"],
    "SGD-ICP default": ["--method", "sgd"],
    "ICP": ["--method", "icp"],
    "ICP point-to-plane": ["--method", "icp-plane"],
    "GICP": ["--method", "gicp"],
}
STOCHASTIC = {"SGD-ICP fixed step (paper)", "SGD-ICP Adam (paper)", "SGD-ICP default"}
STYLE = {  # colour, marker, line style
    "SGD-ICP fixed step (paper)": ("#d62728", "o", "-"),
    "SGD-ICP Adam (paper)": ("#ff7f0e", "s", "-"),
    "SGD-ICP default": ("#2ca02c", "^", "-"),
    "ICP": ("#1f77b4", "v", "--"),
    "ICP point-to-plane": ("#9467bd", "D", "--"),
    "GICP": ("#8c564b", "P", "--"),
}
SHORT = {"SGD-ICP fixed step (paper)": "SGD-ICP fixed", "SGD-ICP Adam (paper)": "SGD-ICP Adam",
         "SGD-ICP default": "SGD-ICP default", "ICP": "ICP", "ICP point-to-plane": "ICP-plane",
         "GICP": "GICP"}
# Peer libraries of Table I: name in the report -> method of bench/compare_peers.py, whose runners,
# settings (identity start, max correspondence distance 0.5 m, <= 30 iterations) and timed region
# are used as they are. Single thread, full resolution unless "voxel" (small_gicp's recommended
# downsampling: 0.25 m outdoor, 0.02 m Kinect).
PEERS = {
    "small_gicp ICP": "sg_icp_full_1t",
    "small_gicp GICP": "sg_gicp_full_1t",
    "small_gicp GICP voxel": "sg_gicp_vox_1t",
    "Open3D ICP": "o3d_p2p_1t",
    "Open3D ICP point-to-plane": "o3d_p2plane_1t",
    "PCL ICP": "pcl_icp_1t",
}
PEER_NAME = {v: k for k, v in PEERS.items()}
QUICK_PEERS = ["sg_icp_full_1t", "o3d_p2p_1t"]
ORDER = list(CONFIGS) + list(PEERS)
# Fig. 2, full run: perturbation seeds per pair (6 ETH pairs x 12 = 72 samples per bin and method; the
# paper has ~100). Fig. 2 runs two CLI processes at once and cost 1.1 min per seed on the 2-core VM
# of docs/results.md (1.4-1.9 min on a busier one); the rest of the full run (peers included) took
# ~5 min. 12 seeds: 18 min in all there; under 30 min also in the slow case (15 seeds took 34 min).
FIG2_SEEDS = 12

plt.rcParams.update({
    "font.size": 7, "axes.titlesize": 7, "axes.labelsize": 7, "legend.fontsize": 6,
    "xtick.labelsize": 6, "ytick.labelsize": 6, "lines.linewidth": 1.0, "lines.markersize": 3,
    "figure.dpi": 200, "savefig.dpi": 200, "axes.grid": True, "grid.alpha": 0.3,
    "grid.linewidth": 0.4,
})
FIGSIZE = (3.5, 2.6)


def log(msg: str) -> None:
    print(f"[reproduce {time.strftime('%H:%M:%S')}] {msg}", file=sys.stderr, flush=True)


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


def fnum(x: float) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "nan"
    if x == 0:
        return "0"
    a = abs(x)
    return f"{x:.3g}" if 1e-3 <= a < 1e4 else f"{x:.2e}"


def pm(xs: list[float]) -> str:
    if not xs:
        return "-"
    m = statistics.fmean(xs)
    s = statistics.stdev(xs) if len(xs) > 1 else 0.0
    return f"{fnum(m)} ± {fnum(s)}"


def med(xs):
    return fnum(statistics.median(xs)) if xs else "-"


def col(rows, key):
    return [float(r[key]) for r in rows]


def success(r, t=SUCCESS_THRESHOLDS[0][0], deg=SUCCESS_THRESHOLDS[0][1]) -> bool:
    return float(r["translation_error_m"]) < t and float(r["rotation_error_geodesic_deg"]) < deg


def is_ok(r) -> bool:
    """A row with a result: every CLI row; a peer row whose run ended with status ok."""
    return r.get("status", "ok") == "ok"


def table_md(rows: list[dict], group_by_pairs: bool = True) -> str:
    head = ("| pairs | method | n | t err mean ± std [m] | t err median [m] | r err mean ± std [rad] "
            "| r err median [rad] | success 5 cm & 1° | time mean ± std [s] | time median [s] | passes median |")
    out = [head, "|" + " --- |" * 2 + " ---: |" * 9]
    groups: dict = {}
    for r in rows:
        groups.setdefault((r["pairs"] if group_by_pairs else "all", r["config"]), []).append(r)
    for (pairs, config) in sorted(groups, key=lambda k: (k[0], ORDER.index(k[1]) if k[1] in ORDER else len(ORDER))):
        g = groups[(pairs, config)]
        good = [r for r in g if is_ok(r)]
        # a timed-out peer run counts with its time limit (a lower bound), as in compare_peers
        stopped = [r for r in g if r.get("status") == "timeout"]
        te, re_ = col(good, "translation_error_m"), col(good, "rotation_error_euler_rad")
        tm = [x / 1e3 for x in col(good + stopped, "time_ms")]
        passes = [float(r["points_processed"]) / float(r["source_points"]) for r in good
                  if r.get("points_processed") not in (None, "")]
        ok = sum(success(r) for r in good)
        n_failed = len(g) - len(good) - len(stopped)
        label = config + (f" ({n_failed} failed)" if n_failed else "")
        if stopped:
            label += f" ({len(stopped)} stopped at {float(stopped[0]['time_ms']) / 1e3:.0f} s)"
        out.append(f"| {pairs} | {label} | {len(g)} | {pm(te)} | {med(te)} | {pm(re_)} | {med(re_)} | "
                   f"{100 * ok / len(g):.0f} % | {pm(tm)} | {med(tm)} | {med(passes)} |")
    return "\n".join(out)


# ----------------------------------------------------------------------------------------------
# Experiments
# ----------------------------------------------------------------------------------------------

def load_pairs(stem_or_path: str) -> tuple[str, list]:
    path = stem_or_path if os.path.exists(stem_or_path) else os.path.join(PAIRS_DIR, stem_or_path + ".txt")
    return os.path.splitext(os.path.basename(path))[0], read_pairs(path)


def exp_table(runner: Runner, pairs_files: list[str], configs: list[str], repeat: int, max_pairs: int | None,
              what: str) -> list[dict]:
    rows = []
    for pf in pairs_files:
        try:
            label, pairs = load_pairs(pf)
        except (OSError, ValueError) as e:
            runner.failures.append((f"{what}: {pf}", f"cannot read pairs file: {e}"))
            continue
        if max_pairs:
            pairs = pairs[:max_pairs]
        for c in configs:
            n = repeat if c in STOCHASTIC else 1
            log(f"{what}: {label} ({len(pairs)} pairs x {n}) {c}")
            t0 = time.perf_counter()
            rows += runner.bench(pairs, label, c, ["--repeat", str(n), "--seed", "2019"], what)
            log(f"  {time.perf_counter() - t0:.1f} s")
    return rows


class Peers:
    """The peer libraries of Table I, run by sgd_icp.peers (the runners of bench/compare_peers.py):
    each registration in a worker process of its library, stopped after timeout_s."""

    def __init__(self, wanted: list[str], exe: str, timeout_s: float):
        self.active: list = []                    # sgd_icp.peers.Method that can run
        self.not_run: list[tuple[str, str]] = []  # (method, reason)
        self.versions: dict[str, str] = {}
        self.settings = PeerSettings(timeout_s=timeout_s)
        self.session = None
        if not wanted:
            return
        pcl_adapter = find_pcl_adapter(None, REPO)
        try:
            methods = {m.name: m for m in build_methods(self.settings, exe, pcl_adapter)}
        except Exception as e:  # noqa: BLE001 - a broken peer installation is recorded, not fatal
            self.not_run = [(w, f"setup failed: {e!r}") for w in wanted]
            return
        self.session = Session(self.settings, sgdicp=exe, pcl_adapter=pcl_adapter, log=log)
        for w in wanted:
            m = methods[w]
            if m.available:
                self.active.append(m)
            elif m.family in ("small_gicp", "open3d") and m.why_not.startswith("import"):
                self.not_run.append((w, "not installed: " + m.why_not.rsplit("; pip install", 1)[0]))
            else:
                self.not_run.append((w, m.why_not))
        for mod in ("small_gicp", "open3d"):
            if any(m.family == mod for m in self.active):
                try:
                    self.versions[mod] = importlib.metadata.version(mod)
                except importlib.metadata.PackageNotFoundError:
                    self.versions[mod] = "?"

    def close(self) -> None:
        if self.session is not None:
            self.session.close()


def exp_peers(runner: Runner, peers: Peers, pairs_files: list[str], max_pairs: int | None, what: str) -> list[dict]:
    """Every active peer once on every pair (the peers are deterministic from the identity start),
    after one untimed warm-up run per method; rows in the columns of `sgdicp bench --csv`."""
    if not peers.active:
        return []
    files = []
    for pf in pairs_files:
        try:
            label, pairs = load_pairs(pf)
        except (OSError, ValueError):
            continue  # recorded by exp_table
        files.append((label, pairs[:max_pairs] if max_pairs else pairs))
    everything = [p for _, ps in files for p in ps]
    log(f"{what}: peers {', '.join(PEER_NAME[m.name] for m in peers.active)}: reading clouds")
    try:
        readable = {id(p) for p in peers.session.prepare(everything, peers.active)}
    except Exception as e:  # noqa: BLE001
        peers.not_run += [(m.name, f"setup failed: {e!r}") for m in peers.active]
        peers.active = []
        return []
    rows = []
    for label, pairs in files:
        for m in peers.active:
            name = PEER_NAME[m.name]
            log(f"{what}: {label} ({len(pairs)} pairs x 1) {name}")
            t0 = time.perf_counter()
            for p in pairs:
                row = {"pairs": label, "pair_line": p.line, "config": name, "peer_method": m.name,
                       "source": p.source, "reference": p.reference}
                if id(p) not in readable:
                    row.update(status="error", note="cannot read the clouds")
                else:
                    o = peers.session.run(m, p)
                    n_src = peers.session.points[p.source]
                    used = o.source_points_used if o.source_points_used >= 0 else n_src
                    row.update(status=o.status, source_points=n_src,
                               reference_points=peers.session.points[p.reference],
                               translation_error_m=o.translation_error_m,
                               rotation_error_geodesic_deg=o.rotation_error_geodesic_deg,
                               rotation_error_euler_rad=o.rotation_error_euler_rad,
                               time_ms=o.time_ms, cpu_ms=o.cpu_ms,
                               iterations=o.iterations if o.iterations >= 0 else "",
                               converged="" if o.converged is None else int(o.converged),
                               points_processed=o.iterations * used if o.iterations >= 0 else "",
                               note=o.note)
                if row["status"] != "ok":
                    runner.failures.append((f"{what}: {label}:{p.line} {name}", f"{row['status']}: {row['note']}"))
                rows.append(row)
            log(f"  {time.perf_counter() - t0:.1f} s")
    return rows


def trace_errors(trace_csv: str, T_gt: np.ndarray) -> tuple[list[float], list[float]]:
    pts, err = [], []
    with open(trace_csv, newline="") as f:
        for r in csv.DictReader(f):
            t = np.array([float(r["t03"]), float(r["t13"]), float(r["t23"])])
            pts.append(float(r["points_processed"]))
            err.append(float(np.linalg.norm(t - T_gt[:3, 3])))
    return pts, err


def exp_fig1(runner: Runner, out: str, quick: bool) -> tuple[list[dict], dict]:
    """Translation error vs points processed on the car pair (CSV encoding, line 5)."""
    label, pairs = load_pairs("libpointmatcher_car")
    pair = pairs[0]
    curves = {}
    rows = []
    for i, c in enumerate(CONFIGS):
        log(f"fig1: trace {c}")
        tr = os.path.join(runner.tmp, f"fig1_trace_{i}.csv")
        # `register --trace`: one row per iteration, for the batch methods one per pass
        args = (CONFIGS[c][2:] if CONFIGS[c][:2] == ["--method", "sgd"] else CONFIGS[c]) + ["--trace", tr]
        j = runner.register_json(pair, args, f"fig1: {c}")
        if j is None or not os.path.exists(tr):
            continue
        pts, err = trace_errors(tr, pair.T_gt)
        if not pts:
            runner.failures.append((f"fig1: {c}", "empty trace"))
            continue
        if c in STOCHASTIC:
            # the returned result may be an iterate average (default): append it as the last point
            pts.append(j["points_processed"])
            err.append(j["translation_error_m"])
        curves[c] = (pts, err)
    for c, (pts, err) in curves.items():
        for p_, e in zip(pts, err):
            rows.append({"config": c, "points_processed": p_, "translation_error_m": e})
    n_src = None
    try:
        n_src = int(runner.register_json(pair, ["--max-iterations", "1"], "fig1: size")["source_points"])
    except (TypeError, KeyError):
        pass
    fig, ax = plt.subplots(figsize=FIGSIZE)
    for c, (pts, err) in curves.items():
        col_, mk, ls = STYLE[c]
        sgd = c in STOCHASTIC
        ax.plot(pts, err, color=col_, ls=ls, marker=None if sgd else mk, label=SHORT[c])
        ax.plot(pts[0], err[0], color=col_, marker=mk, ls="none")
        ax.plot(pts[-1], err[-1], color=col_, marker=mk, ls="none", mfc="white")
    if n_src:
        ax.axvline(n_src, color="0.4", lw=0.7, ls=":")
        ax.text(n_src * 1.1, ax.get_ylim()[1] * 0.5 if ax.get_yscale() == "log" else 0.95 * ax.get_ylim()[1],
                "one pass", fontsize=6, color="0.3", va="top")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("points processed")
    ax.set_ylabel("translation error [m]")
    fig.legend(*ax.get_legend_handles_labels(), loc="upper center", ncol=3, frameon=False,
               handlelength=1.8, columnspacing=1.0)
    fig.tight_layout(rect=(0, 0, 1, 0.86))
    fig.savefig(os.path.join(out, "fig1_data_efficiency.png"))
    plt.close(fig)
    return rows, {"n_src": n_src}


def exp_fig2(runner: Runner, out: str, quick: bool, jobs: int, pairs_files: list[str], seeds: int) -> list[dict]:
    """Error vs initial error bins (perturbation of exactly the bin centre from the ground truth),
    `seeds` random perturbation directions per pair, bin and method."""
    configs = ["SGD-ICP fixed step (paper)", "SGD-ICP default", "ICP", "GICP"]
    t_bins = np.linspace(0, 0.675, 11)
    r_bins = np.linspace(0, 1.75, 11)
    idx = range(0, 10, 2) if quick else range(10)
    max_pairs = 2 if quick else None
    repeat = seeds
    tasks = []
    for pf in pairs_files:
        label, pairs = load_pairs(pf)
        pairs = pairs[:max_pairs] if max_pairs else pairs
        for kind, edges in (("translation", t_bins), ("rotation", r_bins)):
            for b in idx:
                centre = 0.5 * (edges[b] + edges[b + 1])
                pert = f"{centre:.6g},0,{100 + b}" if kind == "translation" else f"0,{centre:.6g},{200 + b}"
                for c in configs:
                    tasks.append((label, pairs, kind, b, centre, c, pert))
    log(f"fig2: {len(tasks)} bench calls, {jobs} in parallel")
    rows = []

    def run(t):
        label, pairs, kind, b, centre, c, pert = t
        rs = runner.bench(pairs, label, c, ["--perturb", pert, "--repeat", str(repeat), "--seed", "2019"],
                          f"fig2 {kind} bin {b}")
        for r in rs:
            r.update({"kind": kind, "bin": b, "initial_error": centre})
        return rs

    done = 0
    with cf.ThreadPoolExecutor(max_workers=jobs) as ex:
        for rs in ex.map(run, tasks):
            rows += rs
            done += 1
            if done % 10 == 0 or done == len(tasks):
                log(f"fig2: {done}/{len(tasks)}")
    for kind, unit, key, ylab, edges in (
            ("translation", "m", "translation_error_m", "translation error [m]", t_bins),
            ("rotation", "rad", "rotation_error_euler_rad", "rotation error [rad]", r_bins)):
        fig, ax = plt.subplots(figsize=FIGSIZE)
        bins = list(idx)
        w = 0.8 / len(configs)
        handles = []
        floor = 1e-7 if kind == "translation" else 1e-6
        for i, c in enumerate(configs):
            data, pos = [], []
            for j, b in enumerate(bins):
                v = [max(float(r[key]), floor) for r in rows
                     if r["kind"] == kind and r["bin"] == b and r["config"] == c]
                data.append(v if v else [np.nan])
                pos.append(j + (i - (len(configs) - 1) / 2) * w)
            colr = STYLE[c][0]
            bp = ax.boxplot(data, positions=pos, widths=w * 0.85, patch_artist=True, whis=(5, 95),
                            flierprops=dict(marker=".", markersize=1.5, markeredgecolor=colr),
                            medianprops=dict(color="black", lw=0.7),
                            boxprops=dict(facecolor=colr, edgecolor=colr, alpha=0.75, lw=0.5),
                            whiskerprops=dict(color=colr, lw=0.6), capprops=dict(color=colr, lw=0.6))
            handles.append((bp["boxes"][0], SHORT[c]))
        ax.set_yscale("log")
        ax.set_xticks(range(len(bins)))
        ax.set_xticklabels([f"{0.5 * (edges[b] + edges[b + 1]):.2f}" for b in bins], rotation=0)
        ax.set_xlabel(f"initial {kind} error [{unit}] (bin centre)")
        ax.set_ylabel(f"final {ylab}")
        fig.legend([h for h, _ in handles], [n for _, n in handles], loc="upper center", ncol=4,
                   frameon=False, handlelength=1.2, columnspacing=1.0)
        ax.set_ylim(floor / 3, None)
        fig.tight_layout(rect=(0, 0, 1, 0.92))
        fig.savefig(os.path.join(out, f"fig2_initial_{kind}.png"))
        plt.close(fig)
    return rows


def exp_fig4(runner: Runner, out: str, quick: bool, pairs_files: list[str]) -> list[dict]:
    sizes = [5, 15, 50, 160, 600] if quick else [5, 10, 15, 25, 50, 100, 160, 300, 600, 1000]
    repeat = 2 if quick else 4
    configs = ["SGD-ICP fixed step (paper)", "SGD-ICP Adam (paper)"]
    rows = []
    for pf in pairs_files:
        label, pairs = load_pairs(pf)
        if quick:
            pairs = pairs[:1]
        for m in sizes:
            for c in configs:
                log(f"fig4: {label} m={m} {c}")
                rs = runner.bench(pairs, label, c, ["--batch-size", str(m), "--repeat", str(repeat),
                                                    "--seed", "2019"], f"fig4 m={m}")
                for r in rs:
                    r["batch_size"] = m
                rows += rs
    labels = sorted({r["pairs"] for r in rows})
    panels = [("translation_error_m", "translation error [m]", "trans", True),
              ("rotation_error_euler_rad", "rotation error [rad]", "rot", True),
              ("time_ms", "run time [s]", "time", True),
              ("iterations", "iterations", "iter", True)]
    lss = ["-", "--", ":"]
    for key, ylab, tag, logy in panels:
        fig, ax = plt.subplots(figsize=FIGSIZE)
        for li, lab in enumerate(labels):
            for c in configs:
                x, md, lo, hi = [], [], [], []
                for m in sizes:
                    v = [float(r[key]) / (1e3 if key == "time_ms" else 1) for r in rows
                         if r["pairs"] == lab and r["config"] == c and r["batch_size"] == m]
                    if not v:
                        continue
                    x.append(m)
                    md.append(np.median(v))
                    lo.append(np.percentile(v, 25))
                    hi.append(np.percentile(v, 75))
                colr, mk, _ = STYLE[c]
                name = ("fixed step" if "fixed" in c else "Adam") + (f", {short_label(lab)}" if len(labels) > 1 else "")
                ax.plot(x, md, color=colr, marker=mk, ls=lss[li % 3], label=name)
                ax.fill_between(x, lo, hi, color=colr, alpha=0.15, lw=0)
        ax.set_xscale("log")
        if logy:
            ax.set_yscale("log")
        ax.set_xlabel("mini-batch size m [points]")
        ax.set_ylabel(ylab)
        ax.legend(frameon=True, loc="best")
        fig.tight_layout()
        fig.savefig(os.path.join(out, f"fig4_batch_{tag}.png"))
        plt.close(fig)
    return rows


def short_label(lab: str) -> str:
    return {"libpointmatcher_car": "car", "pcl_kinect_frames": "Kinect frames",
            "eth_kinect_map_moved_copies": "ETH map copies", "kitti_seq00": "KITTI",
            "kitti_seq00_moved_copies": "KITTI copies"}.get(lab, lab)


def fig4_table(rows: list[dict]) -> str:
    out = ["| pairs | step rule | m | n | t err median [m] | r err median [rad] | success 5 cm & 1° | "
           "time median [s] | iterations median |", "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    groups: dict = {}
    for r in rows:
        groups.setdefault((r["pairs"], r["config"], r["batch_size"]), []).append(r)
    for (lab, c, m) in sorted(groups):
        g = groups[(lab, c, m)]
        out.append(f"| {lab} | {SHORT[c]} | {m} | {len(g)} | {med(col(g, 'translation_error_m'))} | "
                   f"{med(col(g, 'rotation_error_euler_rad'))} | {100 * sum(success(r) for r in g) / len(g):.0f} % | "
                   f"{med([x / 1e3 for x in col(g, 'time_ms')])} | {med(col(g, 'iterations'))} |")
    return "\n".join(out)


def fig2_table(rows: list[dict]) -> str:
    out = ["| initial error | method | n | final t err median [m] | final r err median [rad] | success 5 cm & 1° |",
           "| --- | --- | ---: | ---: | ---: | ---: |"]
    groups: dict = {}
    for r in rows:
        groups.setdefault((r["kind"], r["bin"], r["config"]), []).append(r)
    order = list(CONFIGS)
    for (kind, b, c) in sorted(groups, key=lambda k: (k[0] == "rotation", k[1], order.index(k[2]))):
        g = groups[(kind, b, c)]
        unit = "m" if kind == "translation" else "rad"
        out.append(f"| {kind} {float(g[0]['initial_error']):.3f} {unit} | {SHORT[c]} | {len(g)} | "
                   f"{med(col(g, 'translation_error_m'))} | {med(col(g, 'rotation_error_euler_rad'))} | "
                   f"{100 * sum(success(r) for r in g) / len(g):.0f} % |")
    return "\n".join(out)


# ----------------------------------------------------------------------------------------------

def find_sgdicp(explicit: str | None) -> str | None:
    cands = [explicit] if explicit else [os.path.join(REPO, "build", "sgdicp"), os.path.join(REPO, "build-ci", "sgdicp")]
    for c in cands:
        if c and os.path.isfile(c) and os.access(c, os.X_OK):
            return os.path.abspath(c)
    return shutil.which("sgdicp") if not explicit else None


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("pairs_files", nargs="*", help="pairs files for Table I (default: car, Kinect frames, "
                                                   "ETH map copies, KITTI seq 00)")
    ap.add_argument("--quick", action="store_true", help="subset that runs in < 3 min, with sanity checks")
    ap.add_argument("--out", default=os.path.join(REPO, "results", "reproduce"))
    ap.add_argument("--sgdicp", help="path of the sgdicp CLI (default: build/sgdicp, build-ci/sgdicp)")
    ap.add_argument("--jobs", type=int, default=2, help="parallel CLI runs for Fig. 2 (untimed) [2]")
    ap.add_argument("--fig2-seeds", type=int, default=None, help="perturbations per pair, bin and method in "
                    f"Fig. 2 (x 6 ETH pairs = samples per bin) [quick 1, full {FIG2_SEEDS}]")
    ap.add_argument("--repeat", type=int, default=None, help="seeds per pair for SGD methods in the tables "
                                                             "[quick 1, full 3]")
    ap.add_argument("--no-peers", action="store_true", help="do not run the peer libraries in Table I")
    ap.add_argument("--peers", metavar="LIST", help="comma-separated peers for Table I, as named by "
                    f"bench/compare_peers.py: {','.join(PEERS.values())} [all that are installed; "
                    f"--quick: {','.join(QUICK_PEERS)}]")
    ap.add_argument("--timeout", type=float, default=PeerSettings.timeout_s, metavar="SECONDS",
                    help="a peer registration longer than this is stopped and counted with this time "
                         f"[{PeerSettings.timeout_s:g}]")
    args = ap.parse_args(argv)
    if args.peers is not None and args.no_peers:
        ap.error("--peers and --no-peers exclude each other")
    wanted = [] if args.no_peers else (
        [w.strip() for w in args.peers.split(",") if w.strip()] if args.peers is not None
        else QUICK_PEERS if args.quick else list(PEERS.values()))
    unknown = [w for w in wanted if w not in PEER_NAME]
    if unknown:
        ap.error(f"unknown peer(s) {','.join(unknown)}; choose from {','.join(PEERS.values())}")
    t_start = time.perf_counter()
    exe = find_sgdicp(args.sgdicp)
    if not exe and not args.sgdicp:
        # Nothing built yet: the README's setup and build scripts (apt-get dependencies, Release
        # build into build/), then look again.
        log("sgdicp CLI not found: running scripts/setup.sh and scripts/build.sh")
        for script in ("setup.sh", "build.sh"):
            if subprocess.run([os.path.join(REPO, "scripts", script)], cwd=REPO).returncode != 0:
                print(f"error: scripts/{script} failed; build sgd-icp (README) or pass --sgdicp PATH",
                      file=sys.stderr)
                return 2
        exe = find_sgdicp(None)
    if not exe:
        print("error: sgdicp CLI not found (build it, or pass --sgdicp PATH)", file=sys.stderr)
        return 2
    os.makedirs(args.out, exist_ok=True)
    runner = Runner(exe, args.out)
    quick = args.quick
    repeat = args.repeat or (1 if quick else 3)
    log(f"sgdicp = {exe}; out = {args.out}; mode = {'quick' if quick else 'full'}")
    times = {}

    # Table I
    t0 = time.perf_counter()
    t1_files = args.pairs_files or (["libpointmatcher_car", "eth_kinect_map_moved_copies"] if quick else TABLE1_DEFAULT)
    t1 = exp_table(runner, t1_files, list(CONFIGS), repeat, 3 if quick else None, "table1")
    times["Table I"] = time.perf_counter() - t0

    # Table I: the peers, same pairs
    t0 = time.perf_counter()
    peers = Peers(wanted, exe, args.timeout)
    for w, why in peers.not_run:
        log(f"table1: {PEER_NAME[w]} ({w}) not run: {why}")
    try:
        t1 += exp_peers(runner, peers, t1_files, 3 if quick else None, "table1")
    finally:
        peers.close()
    write_rows(os.path.join(args.out, "table1.csv"), t1)
    times["Table I peers"] = time.perf_counter() - t0

    # Table II
    t0 = time.perf_counter()
    t2 = exp_table(runner, ["kitti_seq00_moved_copies"], list(CONFIGS), repeat, 2 if quick else None, "table2")
    write_rows(os.path.join(args.out, "table2.csv"), t2)
    times["Table II"] = time.perf_counter() - t0

    # Fig. 1
    t0 = time.perf_counter()
    try:
        f1, f1info = exp_fig1(runner, args.out, quick)
    except Exception as e:  # noqa: BLE001 - a figure failing is recorded, not fatal
        runner.failures.append(("fig1", repr(e)))
        f1, f1info = [], {}
    write_rows(os.path.join(args.out, "fig1.csv"), [dict(pairs="libpointmatcher_car", pair_line=5, **r) for r in f1])
    times["Fig. 1"] = time.perf_counter() - t0

    # Fig. 2
    t0 = time.perf_counter()
    try:
        f2 = exp_fig2(runner, args.out, quick, max(1, args.jobs), ["eth_kinect_map_moved_copies"],
                      max(1, args.fig2_seeds or (1 if quick else FIG2_SEEDS)))
    except Exception as e:  # noqa: BLE001
        runner.failures.append(("fig2", repr(e)))
        f2 = []
    write_rows(os.path.join(args.out, "fig2.csv"), f2)
    times["Fig. 2"] = time.perf_counter() - t0

    # Fig. 4
    t0 = time.perf_counter()
    try:
        f4 = exp_fig4(runner, args.out, quick, ["libpointmatcher_car"] if quick else
                      ["libpointmatcher_car", "pcl_kinect_frames"])
    except Exception as e:  # noqa: BLE001
        runner.failures.append(("fig4", repr(e)))
        f4 = []
    write_rows(os.path.join(args.out, "fig4.csv"), f4)
    times["Fig. 4"] = time.perf_counter() - t0

    elapsed = time.perf_counter() - t_start
    figs = ["fig1_data_efficiency.png", "fig2_initial_translation.png", "fig2_initial_rotation.png",
            "fig4_batch_trans.png", "fig4_batch_rot.png", "fig4_batch_time.png", "fig4_batch_iter.png"]

    # Sanity checks (the report must exist for the first one: write it, then check, then rewrite)
    def checks() -> list[tuple[str, bool, str]]:
        res = [("report.md exists", os.path.exists(os.path.join(args.out, "report.md")), "")]
        for f in figs:
            p = os.path.join(args.out, f)
            res.append((f"{f} exists", os.path.exists(p) and os.path.getsize(p) > 1000, ""))
        moved = [r for r in t1 + t2 if r["pairs"].endswith("moved_copies")
                 and r["config"] in ("SGD-ICP default", "SGD-ICP fixed step (paper)")]
        bad = [f"{r['pairs']}:{r['pair_line']} {r['config']}" for r in moved if not success(r)]
        res.append(("SGD-ICP (default, paper fixed step) within 5 cm & 1° on every moved-copy pair",
                    bool(moved) and not bad, f"{len(moved)} runs; failed: {', '.join(bad[:5])}" if bad else f"{len(moved)} runs"))
        allrows = [r for r in t1 + t2 + f2 + f4 if is_ok(r)]
        nonfinite = [r for r in allrows if not all(math.isfinite(float(r[k])) for k in
                                                  ("translation_error_m", "rotation_error_euler_rad", "time_ms"))]
        res.append(("errors and times finite in every row", bool(allrows) and not nonfinite,
                    f"{len(allrows)} rows, {len(nonfinite)} non-finite"))
        res.append(("Table I and II have rows for every configuration",
                    set(CONFIGS) <= {r["config"] for r in t1} and {r["config"] for r in t2} == set(CONFIGS), ""))
        # The peers must have been run on exactly the pairs of our rows, with usable results.
        name = "every peer that ran has a row for each Table I pair and finite errors and times"
        if not peers.active:
            why = "; ".join(f"{PEER_NAME[w]}: {r}" for w, r in peers.not_run) or "--no-peers"
            res.append((name, None, f"skipped, no peer ran: {why}"))
        else:
            ours = {(r["pairs"], str(r["pair_line"])) for r in t1 if "peer_method" not in r}
            bad = []
            for m in peers.active:
                pr = [r for r in t1 if r.get("peer_method") == m.name]
                good = [r for r in pr if is_ok(r)]
                if {(r["pairs"], str(r["pair_line"])) for r in pr} != ours:
                    bad.append(f"{PEER_NAME[m.name]}: pairs differ from ours")
                if not good or not all(math.isfinite(float(r[k])) for r in good for k in
                                       ("translation_error_m", "rotation_error_euler_rad", "time_ms")):
                    bad.append(f"{PEER_NAME[m.name]}: no result or a non-finite one")
            n_failed = sum(not is_ok(r) for r in t1 if "peer_method" in r)
            res.append((name, not bad, "; ".join(bad) if bad else
                        f"{len(peers.active)} peers x {len(ours)} pairs, {n_failed} failed runs (under Failed runs)"))
        return res

    report = make_report(args, exe, quick, repeat, t1, t2, f1, f1info, f2, f4, runner, peers, times, elapsed, [])
    with open(os.path.join(args.out, "report.md"), "w") as f:
        f.write(report)
    res = checks()
    report = make_report(args, exe, quick, repeat, t1, t2, f1, f1info, f2, f4, runner, peers, times, elapsed, res)
    with open(os.path.join(args.out, "report.md"), "w") as f:
        f.write(report)
    shutil.rmtree(runner.tmp, ignore_errors=True)
    n_ok = sum(ok is True for _, ok, _ in res)
    n_skip = sum(ok is None for _, ok, _ in res)
    for name, ok, note in res:
        log(f"check {CHECK_WORD[ok]}: {name} {note}")
    log(f"done in {elapsed:.0f} s; {len(runner.failures)} failed runs recorded; report: "
        f"{os.path.join(args.out, 'report.md')}")
    print(f"{n_ok} passed, {len(res) - n_ok - n_skip} failed" + (f", {n_skip} skipped" if n_skip else ""))
    return 0 if n_ok + n_skip == len(res) else 1


CHECK_WORD = {True: "PASS", False: "FAIL", None: "SKIP"}


def peers_md(peers: Peers, t1: list[dict]) -> str:
    """The report's paragraph on the peers: what ran, how it is timed, what did not run and why."""
    L = []
    if peers.active:
        a = peers.settings
        names = {m.name for m in peers.active}
        fam = {m.family for m in peers.active}
        ran = ", ".join(f"**{PEER_NAME[m.name]}** (`{m.name}`: {m.description})" for m in peers.active)
        vers = "".join(f", {k} {v}" for k, v in peers.versions.items())
        text = [f"**Peers** (Table I only{vers}): {ran}.",
                "Run on the same pairs in this run by the runners of `bench/compare_peers.py` (`sgd_icp.peers`), "
                "each registration in a warm worker process of its library"
                + (" (PCL in its persistent C++ adapter `bench/pcl_adapter`)" if "pcl" in fam else "")
                + f", after one untimed warm-up run per method; identity start, maximum correspondence distance "
                f"{a.max_distance_m:g} m, at most {a.max_iterations} iterations, one thread (`OMP_NUM_THREADS=1`"
                + (", small_gicp `num_threads=1`" if "small_gicp" in fam else "") + "), one run per pair "
                "(deterministic, like our batch methods)."]
        if "sg_gicp_vox_1t" in names:
            text.append("small_gicp GICP voxel is small_gicp's recommended pipeline: voxel downsampling of both "
                        "clouds (0.25 m outdoor, 0.02 m Kinect), covariances of 10 neighbours.")
        text.append("**Time** = search structure (KD-tree) + normals/covariances (+ voxel downsampling) + "
                    "registration, the same parts as in our rows; file I/O and the conversion of the numpy "
                    "arrays into each library's cloud type are excluded.")
        text.append("Passes = iterations × source points used / source points"
                    + (" (Open3D reports no iteration count: -)." if "open3d" in fam else "."))
        text.append(f"A run longer than {a.timeout_s:g} s is stopped and counted with that time; one that "
                    "crashes its process is a failed run.")
        cpu = []
        for m in peers.active:
            x = [float(r["cpu_ms"]) / float(r["time_ms"]) for r in t1 if r.get("peer_method") == m.name
                 and is_ok(r) and math.isfinite(float(r["cpu_ms"])) and float(r["time_ms"]) > 0]
            if x:
                cpu.append((PEER_NAME[m.name], statistics.median(x)))
        if cpu:
            text.append("Threads actually used (process CPU time / wall time, median over runs): "
                        + ", ".join(f"{n} {x:.2f}" for n, x in cpu) + "."
                        + (" Above 1: that library used its own threads despite the settings, which favours "
                           "its times." if any(x > 1.2 for _, x in cpu) else ""))
        L.append(" ".join(text) + "\n")
    elif peers.not_run:
        L.append("**Peers**: none of the requested peers ran.\n")
    else:
        L.append("**Peers**: not run (`--no-peers`).\n")
    for w, why in peers.not_run:
        L.append(f"- {PEER_NAME[w]} (`{w}`): not run: {why}")
    if peers.not_run:
        L.append("")
    return "\n".join(L)


def make_report(args, exe, quick, repeat, t1, t2, f1, f1info, f2, f4, runner, peers, times, elapsed, checks) -> str:
    L = []
    L.append("# Reproduction of the SGD-ICP paper's experiments (Maken, Ramos & Ott, ICRA 2019, sec. IV)\n")
    L.append(f"Generated by `eval/reproduce.py{' --quick' if quick else ''}` with `{exe}` on "
             f"{time.strftime('%Y-%m-%d %H:%M')}, {os.cpu_count()} CPUs, in {elapsed:.0f} s "
             f"({', '.join(f'{k} {v:.0f} s' for k, v in times.items())}).\n")
    L.append("**Data.** The paper's ETH Kinect sequences (medium-medium-fly/-translation/-rotation, 1000 "
             "pairs with Vicon+ICP ground truth) are *not available* here. Substitutes from `../shared/data`: "
             "PCL OpenNI Kinect frames (3 real pairs, pseudo-GT), the ETH Kinect high-complexity map "
             "against copies of itself moved by up to 0.5 m / 30° (exact GT), the libpointmatcher car "
             "laser scans (2 encodings of one real pair), KITTI seq 00 frames 0-5 (real consecutive "
             "pairs, maintainers' ICP pseudo-GT good to 2-9 cm) and the paper's KITTI protocol (scan vs. "
             "copy moved by up to 30 m / 30°). The paper's peers are PCL ICP/GICP and libpointmatcher: "
             "Table I has our own batch `icp`, `icp-plane` and `gicp` and, where installed, the libraries "
             "users would pick instead (small_gicp, Open3D, PCL ICP; see *Peers*); libpointmatcher and "
             "PCL GICP are not run, and Table II and the figures have our methods only.\n")
    L.append("**Definitions.** Translation error = ‖t − t_gt‖ (m); rotation error = sum of |Δroll|, "
             "|Δpitch|, |Δyaw| (rad), the paper's definition; success = translation error < 5 cm and "
             "geodesic rotation error < 1°. Time = KD-tree build (+ normals/covariances for icp-plane/gicp) "
             "+ registration, single thread, file I/O excluded (`sgdicp bench` column time_ms). Every "
             "registration of the tables starts from the identity. SGD methods run "
             f"{repeat} seed(s) per pair (2019, 2020, ...); batch methods are deterministic and run once.\n")
    L.append("Configurations: **SGD-ICP fixed step (paper)** = `--preset paper --optimizer sgd` (m = 160, "
             "d_max = 0.5 scaled, α = 2, last iterate); **SGD-ICP Adam (paper)** = `--preset paper "
             "--optimizer adam`; **SGD-ICP default** = the library's defaults (Adam, paper coarse phase then "
             "refinement stages, iterate average); **ICP / ICP point-to-plane / GICP** = `--method "
             "icp|icp-plane|gicp` with their defaults (d_max = 0.05 scaled, ≤ 100 iterations).\n")
    L.append(peers_md(peers, t1))
    L.append("## Table I analogue: accuracy and run time\n")
    L.append(table_md(t1) if t1 else "_no rows_")
    L.append("\nPaper (ETH Kinect, 1000 pairs, mean ± std): SGD-ICP 0.134 ± 0.190 m, 0.123 ± 0.143 rad, "
             "0.330 ± 0.522 s; ICP 0.104 ± 0.162 m, 0.102 ± 0.132 rad, 5.156 ± 2.325 s; GICP 0.069 ± 0.164 m, "
             "0.051 ± 0.116 rad, 84.065 ± 44.438 s.\n")
    L.append("## Table II analogue: KITTI scans vs. copies moved by up to 30 m / 30°\n")
    L.append(table_md(t2) if t2 else "_no rows_")
    L.append("\nPaper: SGD-ICP 1.2e-5 ± 1.76e-5 m, 2.4e-6 ± 5.78e-6 rad; ICP 8.986 ± 7.366 m, 0.152 ± 0.116 rad; "
             "GICP 9.442 ± 6.911 m, 0.165 ± 0.115 rad.\n")
    L.append("## Fig. 1 analogue: data efficiency\n")
    L.append("![Fig. 1](fig1_data_efficiency.png)\n")
    if f1:
        L.append("Translation error against points processed on the car pair (line 5 of "
                 "libpointmatcher_car.txt, identity start ~0.2 m / 14.5° from the truth). Every curve is the "
                 "per-iteration trace of one run (`register --trace`: one point per mini-batch for SGD, per "
                 "pass for the batch methods; the last point of *default* is its returned iterate average). "
                 "Filled marker: after the first iteration, open marker: the result.\n")
        L.append("| method | points processed at the end | passes | final translation error [m] |")
        L.append("| --- | ---: | ---: | ---: |")
        last = {}
        for r in f1:
            last[r["config"]] = r
        n = f1info.get("n_src") or float("nan")
        for c, r in last.items():
            L.append(f"| {c} | {fnum(float(r['points_processed']))} | {fnum(float(r['points_processed']) / n)} | "
                     f"{fnum(float(r['translation_error_m']))} |")
        L.append("")
    L.append("## Fig. 2 analogue: error vs. initial error\n")
    L.append("![Fig. 2 translation](fig2_initial_translation.png) ![Fig. 2 rotation](fig2_initial_rotation.png)\n")
    L.append("ETH Kinect map vs. its moved copies, started from the ground truth composed with a seeded random "
             "perturbation of exactly the bin centre (`bench --perturb T,0,SEED` / `--perturb 0,R,SEED`); "
             "ten bins of 0-0.675 m and 0-1.75 rad as in the paper"
             f"{' (every other bin in --quick)' if quick else ''}. Boxes: quartiles, whiskers 5-95 %; errors "
             "below 1e-7 m / 1e-6 rad are drawn at that floor (exact copies are solved to ~1e-9).")
    if f2:
        sizes: dict = {}
        for r in f2:
            sizes.setdefault((r["kind"], r["bin"], r["config"]), set()).add((r["pair_line"], r["repeat"]))
        n = [len(v) for v in sizes.values()]
        n_pairs = len({r["pair_line"] for r in f2})
        L[-1] += (f" {min(n)}{'' if min(n) == max(n) else f'-{max(n)}'} samples per bin and method "
                  f"({n_pairs} pairs × {args.fig2_seeds or (1 if quick else FIG2_SEEDS)} seeds).")
    L[-1] += "\n"
    if f2:
        L.append("<details><summary>per-bin medians and success rates</summary>\n")
        L.append(fig2_table(f2))
        L.append("\n</details>\n")
    L.append("## Fig. 4 analogue: mini-batch size\n")
    L.append("![t](fig4_batch_trans.png) ![r](fig4_batch_rot.png)\n![time](fig4_batch_time.png) "
             "![iterations](fig4_batch_iter.png)\n")
    L.append("Paper preset, fixed step α = 2 vs. Adam, identity start; median over pairs and seeds, band = "
             "interquartile range.\n")
    if f4:
        L.append("<details><summary>table</summary>\n")
        L.append(fig4_table(f4))
        L.append("\n</details>\n")
    L.append("## Failed runs\n")
    if runner.failures:
        for what, why in runner.failures:
            L.append(f"- {what}: {why}")
    else:
        L.append("None: every CLI call exited 0 and every peer run that was started returned a transform "
                 "(non-converged registrations are results, not failures).")
    L.append("")
    if checks:
        L.append("## Sanity checks\n")
        for name, ok, note in checks:
            L.append(f"- {CHECK_WORD[ok]}: {name}{' (' + note + ')' if note else ''}")
        L.append("")
    return "\n".join(L) + "\n"


if __name__ == "__main__":
    sys.exit(main())
