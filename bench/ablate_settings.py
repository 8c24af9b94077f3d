#!/usr/bin/env python3
"""What each heuristic setting of the SGD default buys: the default against the default with that
setting switched off, on every pairs file (issue 35, "fewer knobs"). Standard library only.

usage: bench/ablate_settings.py [PAIRS_FILE ...] [--sgdicp PATH] [--rounds 3] [--max-pairs 20]
                                [--only NAME,...] [--csv RUNS.csv] [--from RUNS.csv] [--list]

Pairs files: default every ../shared/data/pairs/*.txt next to the repository plus the 7-Scenes
pairs of bench/make_sevenscenes_pairs.py when generated (as bench/compare_peers.py), at most
--max-pairs (20) pairs of each, the first ones. Each configuration is one `sgdicp bench PAIRS
--csv ... --seed S --repeat 1 --threads 1 OPTIONS` process per pairs file; round r (1..--rounds)
uses seed r, and within a round the configurations alternate pairs file by pairs file (their
order rotates each time), so that a slow spell of the machine hits them all alike. "default" runs
twice per pairs file and round: "default" and "default-again", an identical control (its errors
are the default's, bit for bit) whose time ratio shows the noise of the timing.

Per pairs file and configuration (stdout, Markdown): runs, success (translation < 0.05 m and
geodesic rotation < 1 deg, the bench's first threshold), median translation error [mm] and
rotation error [deg] over every run, median time [ms] (the CLI's time_ms: preparation +
registration, file I/O excluded), the time ratio to "default" (per pair the median time over the
rounds divided by the default's, then the median over the pairs), the CPU ratio (the CLI
process's CPU time, file reading included, divided by the default's on the same pairs file and
seed, median over the rounds: less sensitive to other load on a shared machine, but diluted by
the file reading), median mini-batches, the share converged, and "same": the share of runs whose
errors and mini-batches are those of the default's run on the same pair and seed to every printed
digit (100 % = the setting changed nothing there). --csv writes every run's row (the CLI's
columns plus config, round, seed, pair_line: the line in the original pairs file, and
process_cpu_ms); --from reports on such a file without running anything.

Exit status 1 when a CLI run failed (non-zero exit, no CSV, or longer than --timeout); the other
runs go on and the report names the failures. See docs/registration.md, "Why each setting is
there", for a run's results.
"""
from __future__ import annotations

import argparse
import csv
import math
import os
import resource
import subprocess
import sys
import tempfile
import time

BENCH = os.path.dirname(os.path.abspath(__file__))
if BENCH not in sys.path:
    sys.path.insert(0, BENCH)
# The pure helpers of the peer comparison (importable without the sgd_icp package).
from compare_peers import default_pairs_files, fmt, log, machine_info, median  # noqa: E402
from summarize import rows_of  # noqa: E402

REPO = os.path.dirname(BENCH)

# The bench's first success threshold (`sgdicp bench --success` default): translation [m] and
# geodesic rotation [deg] both strictly below.
SUCCESS = (0.05, 1.0)

# (name, CLI options that switch the setting off, what the default does instead). The first two
# are the default itself; the rest are its heuristics, then choices where the default departs
# from the paper preset (for scale: what the method's main parts buy). check_degeneracy was one
# of them until this ablation showed it changed no pose; it is no longer a setting. The rules
# that became fixed or paper()-only since (the small-source rules, settle_tolerance, the
# refinement's Gauss-Newton steps, flat_k, robust scaling, max_path_efficiency) were ablated with
# the CLI of 9d694cd: their figures are in docs/registration.md, *Why each setting is there*.
CONFIGS = [
    ("default", [], "the defaults"),
    ("default-again", [], "the defaults again: the noise of the timing"),
    ("coarse-plane", ["--coarse-cost", "point-to-plane"],
     "coarse_cost point-to-point: the coarse stage on the paper's cost"),
    ("no-average", ["--average", "false"],
     "average_iterates: the mean of the stationary window's iterates"),
    ("all-eval-points", ["--evaluation-points", "0"],
     "evaluation_points 2000: final statistics on 2000 source points (time only)"),
    ("corner-origin", ["--scaling-origin", "lower-corner"],
     "scaling_origin center: pivot at the scene's centre (the paper: its lower corner)"),
    ("no-tolerances", ["--translation-tolerance", "0", "--rotation-tolerance", "0"],
     "convergence tolerances 1e-6: the absolute stop for exact data"),
    ("no-downsample", ["--downsample-to", "0"],
     "downsample_to 20000: the voxel grid that keeps ~20k reference points"),
    ("cost-point", ["--method", "sgd-point"],
     "cost point-to-plane: the refinement stages' cost (the paper: point-to-point)"),
    ("fixed-step", ["--optimizer", "sgd"],
     "optimizer adam: the coarse stage's step rule (the paper: fixed step 2)"),
    ("no-refine", ["--refine-stages", "0"],
     "refinement.stages 3: the refinement stages after the coarse phase"),
]
BASE = "default"
CONTROL = "default-again"
# The error columns compared by "same" (the CLI prints them to 9 significant digits).
RESULT_COLUMNS = ("translation_error_m", "rotation_error_geodesic_deg", "iterations")


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("pairs", nargs="*", help="pairs files (default: ../shared/data/pairs/*.txt and the 7-Scenes pairs)")
    ap.add_argument("--sgdicp", default=os.environ.get("SGDICP", os.path.join(REPO, "build", "sgdicp")),
                    help="sgdicp CLI (default $SGDICP or build/sgdicp)")
    ap.add_argument("--rounds", type=int, default=3, help="rounds; round r uses seed r (default 3)")
    ap.add_argument("--max-pairs", type=int, default=20, help="at most this many pairs per pairs file, the first (0 = all; default 20)")
    ap.add_argument("--only", default=None, metavar="NAME,...",
                    help="only these configurations (default and default-again always run; see --list)")
    ap.add_argument("--csv", default=None, metavar="RUNS.csv", help="write every run's row to this file")
    ap.add_argument("--from", dest="from_csv", default=None, metavar="RUNS.csv",
                    help="run nothing: the report of an earlier run's --csv file")
    ap.add_argument("--timeout", type=float, default=600.0, metavar="SECONDS",
                    help="a CLI process (one pairs file, one configuration) longer than this is stopped and counted as failed (default 600)")
    ap.add_argument("--list", action="store_true", help="list the configurations and exit")
    return ap


def select_configs(only: str | None) -> list[tuple[str, list[str], str]] | None:
    """The configurations of --only (with the default and its control first); None for an unknown name."""
    if not only:
        return list(CONFIGS)
    known = {c[0]: c for c in CONFIGS}
    wanted = [w.strip() for w in only.split(",") if w.strip()]
    unknown = [w for w in wanted if w not in known]
    if unknown:
        log(f"unknown configurations: {unknown} (see --list)")
        return None
    names = dict.fromkeys([BASE, CONTROL] + wanted)
    return [known[n] for n in names]


def read_pairs_lines(path: str) -> list[tuple[int, str]]:
    """(line number, line with absolute paths) of each pair of a pairs file (PAIRS.md)."""
    folder = os.path.dirname(os.path.abspath(path))
    out = []
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            fields = line.split()
            if not fields or fields[0].startswith("#"):
                continue
            if len(fields) != 14:
                raise SystemExit(f"{path}: line {number}: expected SOURCE REFERENCE and 12 numbers")
            fields[0] = os.path.normpath(os.path.join(folder, fields[0]))
            fields[1] = os.path.normpath(os.path.join(folder, fields[1]))
            out.append((number, " ".join(fields)))
    return out


def prepare_pairs(files: list[str], max_pairs: int, work: str) -> list[tuple[str, str, list[int]]]:
    """(stem, pairs file to run, original line of each of its pairs): the first max_pairs pairs of
    each file, written to work with absolute paths."""
    out = []
    for path in files:
        stem = os.path.splitext(os.path.basename(path))[0]
        lines = read_pairs_lines(path)
        if max_pairs:
            lines = lines[:max_pairs]
        if not lines:
            log(f"[setup] {path}: no pairs, skipped")
            continue
        run_file = os.path.join(work, f"{stem}.txt")
        with open(run_file, "w", encoding="utf-8") as f:
            f.writelines(text + "\n" for _, text in lines)
        out.append((stem, run_file, [n for n, _ in lines]))
    return out


def children_cpu_ms() -> float:
    """User + system CPU time of the finished child processes so far, ms."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return 1000.0 * (r.ru_utime + r.ru_stime)


def run_one(exe: str, pairs_file: str, options: list[str], seed: int, out_csv: str,
            timeout_s: float) -> tuple[list[dict], str]:
    """One CLI process: its CSV rows (each with process_cpu_ms, the process's CPU time, file
    reading included) and "" or, when it failed, no rows and why."""
    cmd = [exe, "bench", pairs_file, "--csv", out_csv, "--seed", str(seed), "--repeat", "1",
           "--threads", "1"] + options
    if os.path.exists(out_csv):
        os.remove(out_csv)
    cpu0 = children_cpu_ms()
    try:
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=timeout_s)
    except subprocess.TimeoutExpired:
        return [], f"no answer within {timeout_s:g} s: {' '.join(cmd)}"
    cpu = children_cpu_ms() - cpu0
    if p.returncode != 0 or not os.path.exists(out_csv):
        why = (p.stderr or p.stdout).strip().replace("\n", " ")[-300:]
        return [], f"exit {p.returncode}: {why} ({' '.join(cmd)})"
    rows = rows_of(out_csv)
    for r in rows:
        r["process_cpu_ms"] = f"{cpu:.3f}"
    return rows, ""


def run_all(args, configs, pairs) -> tuple[list[dict], list[str]]:
    """--rounds rounds of every configuration on every pairs file; rows and failures."""
    rows: list[dict] = []
    failures: list[str] = []
    total = args.rounds * len(pairs) * len(configs)
    done = 0
    t_start = time.time()
    with tempfile.TemporaryDirectory(prefix="ablate_") as work:
        out_csv = os.path.join(work, "rows.csv")
        for rnd in range(args.rounds):
            seed = rnd + 1
            for i, (stem, run_file, original_lines) in enumerate(pairs):
                k = (rnd * len(pairs) + i) % len(configs)
                for name, options, _ in configs[k:] + configs[:k]:  # rotate: no configuration always first
                    got, why = run_one(args.sgdicp, run_file, options, seed, out_csv, args.timeout)
                    done += 1
                    if why:
                        failures.append(f"{name} {stem} seed {seed}: {why}")
                        log(f"[run] FAILED {name} {stem} seed {seed}: {why}")
                    for r in got:
                        r["pairs_file"] = stem
                        r["pair_line"] = original_lines[int(r["line"]) - 1]
                        r["config"] = name
                        r["round"] = rnd + 1
                        r["seed"] = seed
                        rows.append(r)
                log(f"[run] round {rnd + 1}/{args.rounds} {stem:32s} {done}/{total} processes, "
                    f"{time.time() - t_start:.0f} s elapsed")
    return rows, failures


def number(v) -> float:
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


def summarize(rows: list[dict], config_names: list[str]) -> list[dict]:
    """Per (pairs file, configuration): the report's figures (see the module's docstring)."""
    by: dict[tuple[str, str], list[dict]] = {}
    for r in rows:
        by.setdefault((r["pairs_file"], r["config"]), []).append(r)
    base_result = {(r["pairs_file"], r["pair_line"], r["seed"]): tuple(r[c] for c in RESULT_COLUMNS)
                   for r in rows if r["config"] == BASE}
    base_cpu = {(r["pairs_file"], r["seed"]): number(r.get("process_cpu_ms")) for r in rows if r["config"] == BASE}

    def pair_times(rs):
        per: dict[str, list[float]] = {}
        for r in rs:
            per.setdefault(r["pair_line"], []).append(number(r["time_ms"]))
        return {k: median(v) for k, v in per.items()}

    files = list(dict.fromkeys(r["pairs_file"] for r in rows))
    out = []
    for f in files:
        base_times = pair_times(by.get((f, BASE), []))
        for c in config_names:
            rs = by.get((f, c), [])
            if not rs:
                continue
            te = [number(r["translation_error_m"]) for r in rs]
            re = [number(r["rotation_error_geodesic_deg"]) for r in rs]
            ok = sum(t < SUCCESS[0] and a < SUCCESS[1] for t, a in zip(te, re))
            times = pair_times(rs)
            ratios = [times[k] / base_times[k] for k in times if k in base_times and base_times[k] > 0]
            cpu = {r["seed"]: number(r.get("process_cpu_ms")) for r in rs}
            cpu_ratios = [v / base_cpu[(f, k)] for k, v in cpu.items() if base_cpu.get((f, k), 0) > 0]
            same = [base_result.get((f, r["pair_line"], r["seed"])) == tuple(r[col] for col in RESULT_COLUMNS)
                    for r in rs]
            out.append(dict(pairs_file=f, config=c, runs=len(rs), pairs=len(times), success=ok / len(rs),
                            t_err_mm=1000 * median(te), r_err_deg=median(re),
                            time_ms=median([number(r["time_ms"]) for r in rs]),
                            time_ratio=median(ratios) if ratios else math.nan,
                            cpu_ratio=median(cpu_ratios) if cpu_ratios else math.nan,
                            iterations=median([number(r["iterations"]) for r in rs]),
                            converged=sum(r["converged"] in ("1", 1, "true") for r in rs) / len(rs),
                            same=sum(same) / len(rs)))
    return out


def report(summary: list[dict], configs, header: str) -> str:
    lines = [header, ""]
    out = lines.append
    out(f"Success: translation < {SUCCESS[0]:g} m and rotation < {SUCCESS[1]:g}°. Errors, time, iterations: medians over "
        "every run of the pairs file. Ratio: per pair the median time over the rounds / the default's, median over "
        "the pairs. CPU ratio: the CLI process's CPU time (user + system, file reading included, so it understates "
        "a change of the registration's own time) / the default's on the same pairs file and seed, median over the "
        "rounds: less sensitive than the time to other load on the machine. Same: share of runs whose errors and iterations equal the default's on the same pair and seed.")
    out("")
    out("Configurations (each switches one setting of the default off):")
    out("")
    for name, options, what in configs:
        out(f"- `{name}` ({' '.join(options) or 'no option'}): {what}")
    for f in dict.fromkeys(s["pairs_file"] for s in summary):
        sub = [s for s in summary if s["pairs_file"] == f]
        n = sub[0]["pairs"]
        out(f"\n### {f} ({n} pair{'' if n == 1 else 's'})\n")
        out("| configuration | runs | success | t err [mm] | r err [°] | time [ms] | ratio | CPU ratio | iterations | converged | same |")
        out("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
        for s in sub:
            out(f"| {s['config']} | {s['runs']} | {100 * s['success']:.0f} % | {fmt(s['t_err_mm'])} | {fmt(s['r_err_deg'])} | "
                f"{fmt(s['time_ms'])} | {fmt(s['time_ratio'], 2)} | {fmt(s['cpu_ratio'], 2)} | {fmt(s['iterations'])} | "
                f"{100 * s['converged']:.0f} % | {100 * s['same']:.0f} % |")
    return "\n".join(lines) + "\n"


def write_csv(path: str, rows: list[dict]) -> None:
    keys = list(dict.fromkeys(k for r in rows for k in r))
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)


def main(argv=None) -> int:
    args = build_parser().parse_args(sys.argv[1:] if argv is None else argv)
    configs = select_configs(args.only)
    if configs is None:
        return 2
    if args.list:
        for name, options, what in CONFIGS:
            print(f"{name:20s} {' '.join(options) or '(no option)':50s} {what}")
        return 0
    failures: list[str] = []
    if args.from_csv:
        rows = rows_of(args.from_csv)
        present = dict.fromkeys(r["config"] for r in rows)
        configs = [c for c in configs if c[0] in present]
        header = f"## Settings switched off one at a time ({args.from_csv})"
    else:
        if args.rounds < 1:
            log("--rounds must be at least 1")
            return 2
        args.sgdicp = os.path.abspath(args.sgdicp)
        if not os.path.exists(args.sgdicp):
            log(f"{args.sgdicp} not found (scripts/build.sh, or --sgdicp PATH)")
            return 2
        files = args.pairs or default_pairs_files()
        if not files:
            log("no pairs files (expected ../shared/data/pairs/*.txt next to the repository)")
            return 2
        log(f"[setup] {machine_info()}")
        t_start = time.time()
        with tempfile.TemporaryDirectory(prefix="ablate_pairs_") as work:
            pairs = prepare_pairs(files, args.max_pairs, work)
            rows, failures = run_all(args, configs, pairs)
        elapsed = time.time() - t_start
        if args.csv:
            write_csv(args.csv, rows)
        command = " ".join(["bench/ablate_settings.py"] + (sys.argv[1:] if argv is None else list(argv)))
        header = (f"## Settings switched off one at a time\n\n`{command}`: {args.sgdicp}, {args.rounds} rounds "
                  f"(seeds 1-{args.rounds}), at most {args.max_pairs or 'all'} pairs per file, one thread; "
                  f"{machine_info()}; wall time {elapsed:.0f} s.")
    names = [c[0] for c in configs]
    print(report(summarize(rows, names), configs, header), end="")
    if failures:
        print("\n## Failed runs\n")
        for f in failures:
            print(f"- {f}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
