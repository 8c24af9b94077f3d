"""Fig. 1 (data efficiency), Fig. 2 (error vs. initial error) and Fig. 4 (mini-batch size): their
runs and plots (3.5 x 2.6 in, 200 dpi)."""
from __future__ import annotations

import concurrent.futures as cf
import csv
import os

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from .config import CONFIGS, SHORT, STOCHASTIC, STYLE, log  # noqa: E402
from .runner import Runner, load_pairs  # noqa: E402
from .tables import short_label  # noqa: E402

plt.rcParams.update({
    "font.size": 7, "axes.titlesize": 7, "axes.labelsize": 7, "legend.fontsize": 6,
    "xtick.labelsize": 6, "ytick.labelsize": 6, "lines.linewidth": 1.0, "lines.markersize": 3,
    "figure.dpi": 200, "savefig.dpi": 200, "axes.grid": True, "grid.alpha": 0.3,
    "grid.linewidth": 0.4,
})
FIGSIZE = (3.5, 2.6)


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
