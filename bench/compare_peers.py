#!/usr/bin/env python3
"""End-to-end speed and accuracy of sgd-icp against small_gicp, Open3D and PCL (issue 6).

usage: bench/compare_peers.py [PAIRS_FILE ...] [--reps 5] [--quick] [--out DIR] [options]

Runs every method on the same pairs (default: every ../shared/data/pairs/*.txt next to the
repository, plus the 7-Scenes pairs of bench/make_sevenscenes_pairs.py when generated), alternating the methods pair by pair (the order rotates each time) for --reps
rounds, and writes per-run rows (runs.csv), a summary (summary.csv) and Markdown tables
(report.md) to --out. Progress goes to stderr, the report to stdout. Needs the sgd_icp package
(`pip install .`); the runners are the harness bench/peers/ beside this script.

Timed region ("time"): building the search structure + normals/covariances (+ voxel downsampling
where used) + registration, from clouds already in the library's own container. File I/O and
the conversion of numpy arrays into a library's cloud type are excluded. sgd-icp is timed by
its own CLI (`sgdicp bench --csv`, column time_ms = KD-tree build + align()), one process per
registration, warmed as the peers are by an untimed registration of the pair before it (the
round's seed - 1); each Python peer in a warm worker process of its library after an untimed
warm-up run, PCL in its C++ adapter the same way.
Every method starts from the identity; peers use a maximum correspondence distance of 0.5 m and
30 iterations; sgd-icp runs with its defaults (d_max = 0.5 *scaled* units, i.e. half the largest
side of the joint bounding box, 60-100 m on KITTI) and, as "sgdicp_dmax0.5m", with d_max = 0.5 m
like the peers.

Errors against each pairs file's ground truth: translation error ||t - t_gt|| and geodesic
rotation error. A failing method/pair is recorded (status column), never fatal: a registration
longer than --timeout (30 s) is stopped ("timeout", not retried on that pair), a peer that
crashes its process is recorded as "crashed".

Budget (default ~12 min on a 2-core VM): a method slower than --slow-ms (1 s) on a pair in the
first round runs only --slow-reps (2) rounds there, slower than --very-slow-ms (5 s) only one.
small_gicp's multi-threaded variants only with --all-threads. See docs/performance.md for the
results and how to read them.

--pareto adds a "Pareto" section to report.md: per pairs file, each method's median time against
its median errors and success rate, the methods no other one dominates (faster or as fast, at
least as successful, at least as precise in rotation) and what each sgd-icp method dominates;
and a plot pareto.png (with matplotlib). --pareto-from DIR makes both from an earlier run's
DIR/runs.csv without running anything (this alone works without the sgd_icp package).
"""
from __future__ import annotations

import argparse
import csv
import glob
import math
import os
import platform
import statistics
import sys
import time
from typing import NamedTuple

# The harness bench/peers/ (not installed with the package): importable from this script's folder.
BENCH = os.path.dirname(os.path.abspath(__file__))
if BENCH not in sys.path:
    sys.path.insert(0, BENCH)
try:
    import sgd_icp  # noqa: F401 - the harness reads clouds and scores with the package
    import peers
    NEEDS_PACKAGE = None
except ImportError as e:  # only --pareto-from (and the pure functions of this file) work without it
    peers = None
    NEEDS_PACKAGE = (f"bench/compare_peers.py needs the sgd_icp Python package ({e}): "
                     "run `pip install .` in the repository (docs/python.md)")

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

DEFAULT_METHODS = ("sgdicp,sgdicp_dmax0.5m,sgdicp_plane,sgdicp_gicp,sg_icp_full_1t,sg_gicp_full_1t,sg_icp_vox_1t,sg_gicp_vox_1t,"
                   "o3d_p2p_1t,o3d_p2plane_1t,pcl_icp_1t,sg_kdtree_build")
ALL_THREADS_METHODS = ",sg_icp_full_{nt}t,sg_gicp_full_{nt}t,sg_icp_vox_{nt}t,sg_gicp_vox_{nt}t"
QUICK_METHODS = "sgdicp,sg_icp_full_1t,sg_gicp_vox_1t,o3d_p2p_1t,pcl_icp_1t,sg_kdtree_build"
# Statuses after which a method is not run again on that pair (the peers are deterministic).
NOT_RETRIED = ("timeout", "crashed")


def log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def fmt(v, digits=3):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "–"
    if isinstance(v, float):
        return f"{v:.{digits}g}"
    return str(v)


def median(xs):
    xs = [x for x in xs if x is not None and math.isfinite(x)]
    return statistics.median(xs) if xs else float("nan")


def geomean(xs):
    xs = [x for x in xs if x is not None and math.isfinite(x) and x > 0]
    return math.exp(sum(math.log(x) for x in xs) / len(xs)) if xs else float("nan")


def machine_info() -> str:
    cpu = "?"
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(l.split(":", 1)[1].strip() for l in f if l.startswith("model name"))
    except Exception:
        pass
    mem = "?"
    try:
        with open("/proc/meminfo") as f:
            mem = f"{int(next(l for l in f if l.startswith('MemTotal')).split()[1]) / 1048576:.1f} GiB"
    except Exception:
        pass
    return f"{platform.node()}: {os.cpu_count()} CPUs, {cpu}, {mem} RAM, Python {platform.python_version()}, load average {os.getloadavg()[0]:.2f} at the start"


def build_parser() -> argparse.ArgumentParser:
    d = peers.PeerSettings
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("pairs", nargs="*", help="pairs files (default: ../shared/data/pairs/*.txt from the repository root)")
    ap.add_argument("--reps", type=int, default=None, help="rounds over all pairs and methods (default 5; --quick: 2)")
    ap.add_argument("--quick", action="store_true", help="first pair of each pairs file, 2 rounds, a few methods (~1-2 min)")
    ap.add_argument("--methods", default=None, help="comma-separated method names (see --list)")
    ap.add_argument("--list", action="store_true", help="list the methods and exit")
    ap.add_argument("--out", default=os.path.join(REPO, "results", "compare_peers"), help="output folder (default results/compare_peers)")
    ap.add_argument("--sgdicp", default=os.environ.get("SGDICP", os.path.join(REPO, "build", "sgdicp")), help="sgdicp CLI (default $SGDICP or build/sgdicp)")
    ap.add_argument("--pcl-adapter", default=None, help="sgdicp_pcl_adapter (default: build-bench/bench/pcl_adapter/ or any build*/)")
    ap.add_argument("--max-distance", type=float, default=d.max_distance_m, help=f"peers' max correspondence distance, m (default {d.max_distance_m:g})")
    ap.add_argument("--max-iterations", type=int, default=d.max_iterations, help=f"peers' iteration limit (default {d.max_iterations}, Open3D's default)")
    ap.add_argument("--all-threads", action="store_true", help="also run small_gicp's multi-threaded variants (sg_*_Nt; not in the default: meaningful only on an idle machine)")
    ap.add_argument("--threads", type=int, default=os.cpu_count() or 1, help="threads of the multi-threaded small_gicp variants (default: all)")
    ap.add_argument("--voxel", action="append", default=[], metavar="PAIRS=METRES", help="voxel size for a pairs file stem (default: 0.25 m outdoor, 0.02 m Kinect, 0.002 m bunny)")
    ap.add_argument("--success", default="{:g},{:g}".format(*peers.SUCCESS_THRESHOLDS[0]), help="success threshold TRANS_M,ROT_DEG (default {:g},{:g}, the CLI's); {:g},{:g} is also reported".format(*peers.SUCCESS_THRESHOLDS[0], *peers.SUCCESS_THRESHOLDS[1]))
    ap.add_argument("--slow-ms", type=float, default=1000.0, help="a method slower than this on a pair in the first round ...")
    ap.add_argument("--slow-reps", type=int, default=2, help="... runs only this many rounds on that pair (default: 1000 ms, 2 rounds; keeps the default run near 15 min; the peers are deterministic, only their timing varies)")
    ap.add_argument("--very-slow-ms", type=float, default=5000.0, help="a method slower than this on a pair in the first round runs only that round on it (default 5000)")
    ap.add_argument("--timeout", type=float, default=d.timeout_s, metavar="SECONDS", help=f"a registration (a peer's, or a sgdicp CLI process) longer than this is stopped, recorded as 'timeout' and not retried on that pair (default {d.timeout_s:g})")
    ap.add_argument("--max-pairs", type=int, default=0, help="use at most this many pairs per pairs file (0 = all)")
    ap.add_argument("--no-install", dest="install", action="store_false", help="do not pip install missing peers")
    ap.add_argument("--pareto", action="store_true", help=PARETO_HELP)
    ap.add_argument("--pareto-from", metavar="DIR", default=None, help=PARETO_FROM_HELP)
    return ap


PARETO_HELP = "also append the Pareto section (per pairs file) to report.md and plot pareto.png in --out (default: off)"
PARETO_FROM_HELP = ("run nothing: append the Pareto section of an earlier run's DIR/runs.csv (or, without it, "
                    "DIR/summary.csv) to DIR/report.md and plot DIR/pareto.png (default: off)")
# peers.SUCCESS_THRESHOLDS[0], the default of --success when --pareto-from runs without the package
# (tests/python/test_compare_peers_pareto.py checks that the two agree).
SUCCESS_WITHOUT_PACKAGE = (0.05, 1.0)


def build_pareto_parser() -> argparse.ArgumentParser:
    """The options of --pareto-from alone: what main() parses when the sgd_icp package is missing."""
    ap = argparse.ArgumentParser(description="The Pareto section and plot of an earlier run of bench/compare_peers.py "
                                             "(the sgd_icp package is not installed: nothing else can run).")
    ap.add_argument("--pareto-from", metavar="DIR", required=True, help=PARETO_FROM_HELP)
    ap.add_argument("--success", default="{:g},{:g}".format(*SUCCESS_WITHOUT_PACKAGE),
                    help="success threshold TRANS_M,ROT_DEG (default {:g},{:g}, the CLI's)".format(*SUCCESS_WITHOUT_PACKAGE))
    return ap


def wants_pareto_from(argv: list[str]) -> bool:
    """Whether the command line asks for --pareto-from (checked before the sgd_icp package is needed)."""
    return any(a == "--pareto-from" or a.startswith("--pareto-from=") for a in argv)


# Peer voxel sizes of pairs files the harness's table does not name: the hand-held BALM LiDAR
# scans (../shared/data/pairs/balm_handheld_lidar.txt) are outdoor LiDAR, small_gicp's 0.25 m.
EXTRA_VOXEL_M = {"balm_handheld_lidar": 0.25}


def settings_of(args: argparse.Namespace) -> peers.PeerSettings:
    """The peers' settings of the command line (--voxel PAIRS=METRES overrides the defaults)."""
    s = peers.PeerSettings(max_distance_m=args.max_distance, max_iterations=args.max_iterations,
                           timeout_s=args.timeout, threads=args.threads)
    for k, val in EXTRA_VOXEL_M.items():
        s.voxel_m.setdefault(k, val)
    for v in args.voxel:
        k, _, val = v.partition("=")
        s.voxel_m[k] = float(val)
    return s


def select_methods(args, methods: list[peers.Method]) -> list[peers.Method] | None:
    """The methods of --methods (or the default set) that can run; None for an unknown name."""
    default = DEFAULT_METHODS + (ALL_THREADS_METHODS if args.all_threads else "")
    wanted = (args.methods or default).format(nt=args.threads).split(",")
    by_name = {m.name: m for m in methods}
    unknown = [w for w in wanted if w not in by_name]
    if unknown:
        log(f"unknown methods: {unknown} (see --list)")
        return None
    chosen = [by_name[w] for w in dict.fromkeys(wanted)]
    for m in chosen:
        if not m.available:
            log(f"[setup] skipping {m.name}: {m.why_not}")
    return [m for m in chosen if m.available]


def default_pairs_files() -> list[str]:
    """Every ../shared/data/pairs/*.txt, and the 7-Scenes pairs of bench/make_sevenscenes_pairs.py
    when they have been generated (../generated/sevenscenes_redkitchen or $SGDICP_GENERATED_DATA)."""
    files = sorted(glob.glob(os.path.join(REPO, "..", "shared", "data", "pairs", "*.txt")))
    generated = os.environ.get("SGDICP_GENERATED_DATA") or os.path.join(REPO, "..", "generated", "sevenscenes_redkitchen")
    seven = os.path.join(generated, "sevenscenes_redkitchen.txt")
    if os.path.isfile(seven):
        files.append(seven)
    else:
        log(f"[setup] no 7-Scenes pairs at {seven}: run bench/make_sevenscenes_pairs.py to include them")
    return files


def load_pairs(args) -> list[peers.Pair]:
    pairs_files = args.pairs or default_pairs_files()
    pairs: list[peers.Pair] = []
    for pf in pairs_files:
        ps = peers.read_pairs(pf)
        pairs += ps[: args.max_pairs] if args.max_pairs else ps
    for i, p in enumerate(pairs):
        p.index = i
    return pairs


def row_of(p: peers.Pair, m: peers.Method, rep: int, o: peers.Outcome, session: peers.Session) -> dict:
    return dict(pairs_file=p.pairs_file, line=p.line, source=os.path.basename(p.source),
                reference=os.path.basename(p.reference), source_points=session.points[p.source],
                reference_points=session.points[p.reference], method=m.name, family=m.family,
                threads=m.threads, rep=rep, status=o.status, time_ms=o.time_ms, cpu_ms=o.cpu_ms,
                build_ms=o.build_ms, translation_error_m=o.translation_error_m,
                rotation_error_deg=o.rotation_error_geodesic_deg, iterations=o.iterations,
                converged=o.converged, peak_rss_mb=o.peak_rss_mb, call_ms=o.call_ms, note=o.note)


def run_rounds(args, session: peers.Session, pairs: list[peers.Pair], active: list[peers.Method],
               live_csv: str) -> list[dict]:
    """--reps rounds of every method on every pair (the order of the methods rotates pair by pair);
    each row is also appended to live_csv as it comes."""
    rows = []
    slow: dict[int, set] = {}  # pair index -> methods slower than --slow-ms in the first round
    very_slow: dict[int, set] = {}  # pair index -> methods slower than --very-slow-ms in the first round
    stopped: dict[int, set] = {}  # pair index -> methods that timed out or crashed there
    total = args.reps * len(pairs) * len(active)
    t_start = time.time()
    with open(live_csv, "w", newline="") as live:
        writer = None
        for rep in range(args.reps):
            for p in pairs:
                k = (rep * len(pairs) + p.index) % len(active)
                for m in active[k:] + active[:k]:  # rotate so no method always runs first
                    if m.name in stopped.get(p.index, set()):
                        continue  # timed out or crashed once on this pair: not retried
                    if rep >= 1 and m.name in very_slow.get(p.index, set()):
                        continue  # one round of a very slow method is enough
                    if rep >= args.slow_reps and m.name in slow.get(p.index, set()):
                        continue  # a slow method: --slow-reps rounds are enough for its median
                    o = session.run(m, p, rep)
                    if o.status in NOT_RETRIED:
                        stopped.setdefault(p.index, set()).add(m.name)
                        log(f"[run] {m.name} {p.label}: {o.status} {o.note}")
                    rows.append(row_of(p, m, rep, o, session))
                    if writer is None:
                        writer = csv.DictWriter(live, fieldnames=list(rows[-1].keys()))
                        writer.writeheader()
                    writer.writerow(rows[-1])
                    live.flush()
                    if rep == 0 and o.status == "ok" and o.time_ms > args.slow_ms:
                        slow.setdefault(p.index, set()).add(m.name)
                    if rep == 0 and o.status == "ok" and o.time_ms > args.very_slow_ms:
                        very_slow.setdefault(p.index, set()).add(m.name)
                log(f"[run] round {rep + 1}/{args.reps} {p.label:34s} {len(rows)}/{total} runs (at most), "
                    f"{time.time() - t_start:.0f} s elapsed")
    return rows


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if peers is None:
        if not wants_pareto_from(argv):
            sys.exit(NEEDS_PACKAGE)
        args = build_pareto_parser().parse_args(argv)
        return pareto_from(args.pareto_from, parse_success(args.success))
    args = build_parser().parse_args(argv)
    if args.pareto_from:
        return pareto_from(args.pareto_from, parse_success(args.success))
    if args.quick:
        args.reps = args.reps or 2
        args.max_pairs = args.max_pairs or 1
        args.methods = args.methods or QUICK_METHODS
    args.reps = args.reps or 5
    args.sgdicp = os.path.abspath(args.sgdicp)
    settings = settings_of(args)
    pcl_adapter = peers.find_pcl_adapter(args.pcl_adapter, REPO)
    methods = peers.build_methods(settings, args.sgdicp, pcl_adapter, install=args.install)
    if args.list:
        for m in methods:
            print(f"{m.name:20s} {m.description}" + ("" if m.available else f"  [unavailable: {m.why_not}]"))
        return 0
    active = select_methods(args, methods)
    if active is None:
        return 2
    if not active:
        log("no method can run (see --list)")
        return 2
    pairs = load_pairs(args)
    if not pairs:
        log("no pairs files (expected ../shared/data/pairs/*.txt next to the repository)")
        return 2
    log(f"[setup] {machine_info()}")
    os.makedirs(args.out, exist_ok=True)
    t_start = time.time()
    with peers.Session(settings, sgdicp=args.sgdicp, pcl_adapter=pcl_adapter, log=log) as session:
        pairs = session.prepare(pairs, active)
        live_csv = os.path.join(args.out, "runs.partial.csv")
        rows = run_rounds(args, session, pairs, active, live_csv)
    os.replace(live_csv, os.path.join(args.out, "runs.csv"))

    report = make_report(rows, active, pairs, args, time.time() - t_start)
    plotted = False
    if args.pareto:
        success = parse_success(args.success)
        stats = dataset_stats(rows, success)
        report = with_pareto_section(report, pareto_section(stats, success))
        plotted = plot_pareto(stats, os.path.join(args.out, "pareto.png"))
    with open(os.path.join(args.out, "report.md"), "w") as f:
        f.write(report)
    print(report)
    log(f"[done] {args.out}/runs.csv, summary.csv, report.md" + (", pareto.png" if plotted else ""))
    return 0


def make_report(rows, methods, pairs, args, elapsed) -> str:
    succ_t, succ_r = (float(x) for x in args.success.split(","))
    reg_methods = [m for m in methods if m.family != "build-only"]
    # Per (method, pair): median time, errors over the rounds.
    per = {}
    for r in rows:
        per.setdefault((r["method"], r["pairs_file"], r["line"]), []).append(r)
    pair_keys = [(p.pairs_file, p.line) for p in pairs]

    def timed_rows(rs):  # a timeout counts with the timeout as its time (a lower bound)
        return [r for r in rs if r["status"] in ("ok", "timeout")]

    def med_time(m, key):
        return median([r["time_ms"] for r in timed_rows(per.get((m, *key), []))])

    def ok(r, t=succ_t, d=succ_r):
        return r["status"] == "ok" and r["translation_error_m"] < t and r["rotation_error_deg"] < d

    groups = sorted({p.pairs_file for p in pairs})
    lines = []
    out = lines.append
    out("# sgd-icp vs peers: end-to-end registration\n")
    out(f"{machine_info()}; {args.reps} rounds, methods alternated per pair; wall time of this run {elapsed / 60:.1f} min.\n")
    out("Time = search-structure build + normals/covariances (+ voxel downsampling where used) + registration; "
        "file I/O excluded. Identity start. Peers: max correspondence distance "
        f"{args.max_distance} m, at most {args.max_iterations} iterations. sgd-icp: its defaults "
        "(d_max 0.5 *scaled* = half the scene's largest side), and `sgdicp_dmax0.5m` with d_max = 0.5 m.\n")
    out(f"Ratio = method time / sgd-icp time on the same pair (medians over rounds), then the median over the pairs: "
        f"> 1 means sgd-icp is faster. Success: translation < {succ_t} m and rotation < {succ_r} deg (and < 2 m, 5 deg). "
        "cpu/time ~ threads actually used (process CPU time / wall time; below 1 for one thread means the machine was busy). "
        f"A method slower than {args.slow_ms:.0f} ms on a pair in the first round runs {args.slow_reps} rounds on it, slower than "
        f"{args.very_slow_ms:.0f} ms only 1 (column runs); a run longer than {args.timeout:g} s is stopped (timeout, counted with that time).\n")
    summary_rows = []
    for g in groups + ["ALL"]:
        keys = [k for k in pair_keys if g == "ALL" or k[0] == g]
        if not keys:
            continue
        n_src = median([len_ for len_ in (r["source_points"] for r in rows if (r["pairs_file"], r["line"]) in keys)])
        out(f"\n## {g} ({len(keys)} pairs, ~{n_src:.0f} source points)\n" if g != "ALL" else f"\n## All pairs ({len(keys)})\n")
        out("| method | threads | runs | success | success 2 m/5° | median t err [m] | median r err [°] | median time [ms] | ratio vs sgdicp (median over pairs) | ratio geo-mean | cpu/time | median iters |")
        out("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
        for m in reg_methods + [m for m in methods if m.family == "build-only"]:
            rs = [r for k in keys for r in per.get((m.name, *k), [])]
            if not rs:
                continue
            good = [r for r in rs if r["status"] == "ok"]
            ratios = []
            for k in keys:
                a, b = med_time(m.name, k), med_time("sgdicp", k)
                if m.family == "build-only":
                    b = median([r["build_ms"] for r in per.get(("sgdicp", *k), []) if r["status"] == "ok"])
                if math.isfinite(a) and math.isfinite(b) and b > 0:
                    ratios.append(a / b)
            cpu = [r["cpu_ms"] / r["time_ms"] for r in good if math.isfinite(r["cpu_ms"]) and r["time_ms"] > 0]
            s1 = sum(ok(r) for r in rs) / len(rs)
            s2 = sum(ok(r, *peers.SUCCESS_THRESHOLDS[1]) for r in rs) / len(rs)
            errs = sum(r["status"] not in ("ok", "timeout") for r in rs)
            touts = sum(r["status"] == "timeout" for r in rs)
            label = m.name + (f" ({errs} failed)" if errs else "") + (f" ({touts} timed out, counted as {args.timeout:.0f} s)" if touts else "")
            if m.family == "build-only":
                out(f"| {label} (vs sgdicp build_ms) | {m.threads} | {len(rs)} | – | – | – | – | {fmt(median([r['time_ms'] for r in good]))} | {fmt(median(ratios))} | {fmt(geomean(ratios))} | {fmt(median(cpu), 2)} | – |")
                continue
            out(f"| {label} | {m.threads} | {len(rs)} | {100 * s1:.0f} % | {100 * s2:.0f} % | "
                f"{fmt(median([r['translation_error_m'] for r in good]))} | {fmt(median([r['rotation_error_deg'] for r in good]))} | "
                f"{fmt(median([r['time_ms'] for r in timed_rows(rs)]))} | {fmt(median(ratios))} | {fmt(geomean(ratios))} | "
                f"{fmt(median(cpu), 2)} | {fmt(median([float(r['iterations']) for r in good if r['iterations'] >= 0]))} |")
            summary_rows.append(dict(group=g, method=m.name, threads=m.threads, runs=len(rs), failed=errs,
                                     success=s1, success_2m5deg=s2,
                                     median_t_err_m=median([r["translation_error_m"] for r in good]),
                                     median_r_err_deg=median([r["rotation_error_deg"] for r in good]),
                                     median_time_ms=median([r["time_ms"] for r in timed_rows(rs)]), timeouts=touts,
                                     ratio_median=median(ratios), ratio_geomean=geomean(ratios)))
        if g == "ALL":
            continue
    # sgd-icp build share
    build = [r["build_ms"] / r["time_ms"] for r in rows if r["method"] == "sgdicp" and r["status"] == "ok" and r["time_ms"] > 0]
    if build:
        out(f"\nsgd-icp: KD-tree build = {100 * median(build):.0f} % of its time (median over runs); "
            f"peak RSS of the CLI process (file reading included): median {fmt(median([r['peak_rss_mb'] for r in rows if r['method'] == 'sgdicp']))} MB, "
            f"max {fmt(max([r['peak_rss_mb'] for r in rows if r['method'] == 'sgdicp' and math.isfinite(r['peak_rss_mb'])], default=float('nan')))} MB.\n")
    # What a run costs outside its timed region: the CLI process (start, file reading), the
    # worker round trip + conversion into the library's cloud type.
    untimed = []
    for m in methods:
        d = [r["call_ms"] - r["time_ms"] for r in rows if r["method"] == m.name and r["status"] == "ok"]
        if any(math.isfinite(x) for x in d):
            untimed.append(f"{m.name} {fmt(median(d))}")
    if untimed:
        out("\nUntimed part of a run (the caller's wall time of the call - time, median, ms): " + ", ".join(untimed) + ".\n")
    # Per-pair table
    out("\n## Per pair: median time [ms] (ratio vs sgdicp)\n")
    names = [m.name for m in methods]
    out("| pair | " + " | ".join(names) + " |")
    out("| --- | " + " | ".join("---:" for _ in names) + " |")
    for k in pair_keys:
        base = med_time("sgdicp", k)
        base_build = median([r["build_ms"] for r in per.get(("sgdicp", *k), []) if r["status"] == "ok"])
        cells = []
        for m in methods:
            t = med_time(m.name, k)
            b = base_build if m.family == "build-only" else base
            cells.append(f"{fmt(t)} ({fmt(t / b, 2)})" if math.isfinite(t) and math.isfinite(b) and b > 0 else fmt(t))
        src = next((r["source"] for r in rows if (r["pairs_file"], r["line"]) == k), "")
        out(f"| {k[0]}:{k[1]} {src} | " + " | ".join(cells) + " |")
    failures = [r for r in rows if r["status"] != "ok"]
    if failures:
        out("\n## Failed runs\n")
        for r in failures[:50]:
            out(f"- {r['method']} {r['pairs_file']}:{r['line']} round {r['rep']}: {r['status']} {r['note']}")
    with open(os.path.join(args.out, "summary.csv"), "w", newline="") as f:
        if summary_rows:
            w = csv.DictWriter(f, fieldnames=list(summary_rows[0].keys()))
            w.writeheader()
            w.writerows(summary_rows)
    return "\n".join(lines) + "\n"


# --- Pareto: median time against median errors and success, per pairs file (--pareto, --pareto-from)

SGDICP_PREFIX = "sgdicp"  # the sgd-icp methods: the ones whose dominated methods are listed
PARETO_MARKERS = "os^vDP*X<>hpd8H"


class MethodStats(NamedTuple):
    """One method on one pairs file: medians over all its runs there (time: ok and timed-out runs,
    a timeout counting with its limit; errors: ok runs) and the share of its runs that succeed.
    (A NamedTuple, not a dataclass: the tests load this file without registering it as a module.)"""

    method: str
    time_ms: float
    t_err_m: float
    r_err_deg: float
    success: float  # 0..1
    runs: int = 0


def parse_success(text: str) -> tuple[float, float]:
    """TRANS_M,ROT_DEG of --success."""
    t, r = (float(x) for x in text.split(","))
    return t, r


def _worst_if_nan(x: float) -> float:
    """A missing median (no run to take it from) counts as the worst value."""
    return x if x is not None and math.isfinite(x) else math.inf


def dominates(a: MethodStats, b: MethodStats) -> bool:
    """Whether a dominates b: a's median time <= b's, its success >= b's and its median rotation
    error <= b's, at least one of the three strictly. A missing time or error counts as infinite."""
    ta, tb = _worst_if_nan(a.time_ms), _worst_if_nan(b.time_ms)
    ra, rb = _worst_if_nan(a.r_err_deg), _worst_if_nan(b.r_err_deg)
    if not (ta <= tb and a.success >= b.success and ra <= rb):
        return False
    return ta < tb or a.success > b.success or ra < rb


def dominated_by(stats: list[MethodStats]) -> dict[str, list[str]]:
    """For each method of one pairs file, the methods that dominate it (in the order of stats)."""
    return {b.method: [a.method for a in stats if a is not b and dominates(a, b)] for b in stats}


def pareto_front(stats: list[MethodStats]) -> list[str]:
    """The methods of one pairs file that no other method dominates, in the order of stats."""
    by = dominated_by(stats)
    return [s.method for s in stats if not by[s.method]]


def dataset_stats(rows: list[dict], success: tuple[float, float]) -> dict[str, list[MethodStats]]:
    """Per pairs file (sorted), each registration method's MethodStats over the rows of runs.csv
    (the build-only methods left out), fastest first: the medians and the success of the report's
    per-pairs-file tables (summary.csv). success = (translation m, rotation deg) thresholds."""
    succ_t, succ_r = success
    runs: dict[str, dict[str, list[dict]]] = {}
    for r in rows:
        if r.get("family") == "build-only":
            continue
        runs.setdefault(r["pairs_file"], {}).setdefault(r["method"], []).append(r)
    out = {}
    for g in sorted(runs):
        stats = []
        for m, rs in runs[g].items():
            good = [r for r in rs if r["status"] == "ok"]
            n_ok = sum(r["translation_error_m"] < succ_t and r["rotation_error_deg"] < succ_r for r in good)
            stats.append(MethodStats(method=m, runs=len(rs), success=n_ok / len(rs),
                                     time_ms=median([r["time_ms"] for r in rs if r["status"] in ("ok", "timeout")]),
                                     t_err_m=median([r["translation_error_m"] for r in good]),
                                     r_err_deg=median([r["rotation_error_deg"] for r in good])))
        out[g] = sorted(stats, key=lambda s: (_worst_if_nan(s.time_ms), s.method))
    return out


def read_csv(path: str) -> list[dict]:
    """The rows of a CSV file of this script, the numbers as floats (an empty cell is NaN)."""
    def value(v):
        try:
            return float(v) if v != "" else float("nan")
        except ValueError:
            return v
    with open(path, newline="") as f:
        return [{k: value(v) if k not in ("pairs_file", "method", "status", "family", "group") else v
                 for k, v in r.items()} for r in csv.DictReader(f)]


def summary_stats(summary: list[dict]) -> dict[str, list[MethodStats]]:
    """dataset_stats() of the rows of summary.csv (its success is the run's --success)."""
    out: dict[str, list[MethodStats]] = {}
    for r in summary:
        if r["group"] == "ALL":
            continue
        out.setdefault(r["group"], []).append(MethodStats(
            method=r["method"], time_ms=r["median_time_ms"], t_err_m=r["median_t_err_m"],
            r_err_deg=r["median_r_err_deg"], success=r["success"], runs=int(r["runs"])))
    return {g: sorted(s, key=lambda x: (_worst_if_nan(x.time_ms), x.method)) for g, s in sorted(out.items())}


def pareto_section(stats: dict[str, list[MethodStats]], success: tuple[float, float] | None) -> str:
    """The Markdown section "Pareto" of dataset_stats(): per pairs file a table of the methods and
    a line per sgd-icp method with the methods it dominates. success None: thresholds unknown."""
    lines = ["## Pareto\n"]
    out = lines.append
    thresholds = (f"translation < {success[0]:g} m and rotation < {success[1]:g} deg" if success
                  else "the run's --success thresholds (from summary.csv)")
    out("Per pairs file: a method dominates another when its median time is at most the other's, its success "
        "at least the other's and its median rotation error at most the other's, one of them strictly (the "
        "translation error is shown, not compared). Front: dominated by no other method. Medians over every run "
        "on the pairs file (time: ok and timed-out runs; errors: ok runs); success: "
        f"{thresholds}. No median (no ok run) counts as the worst.")
    for g, st in stats.items():
        by = dominated_by(st)
        out(f"\n### {g}\n")
        out("| method | median time [ms] | median t err [mm] | median r err [°] | success | Pareto front | dominated by |")
        out("| --- | ---: | ---: | ---: | ---: | --- | --- |")
        for s in st:
            out(f"| {s.method} | {fmt(s.time_ms)} | {fmt(s.t_err_m * 1000)} | {fmt(s.r_err_deg)} | "
                f"{100 * s.success:.0f} % | {'no' if by[s.method] else 'yes'} | {', '.join(by[s.method]) or '–'} |")
        out("")
        sgd = [s.method for s in st if s.method.startswith(SGDICP_PREFIX)]
        for m in sgd:
            beaten = [b for b, a in by.items() if m in a]
            out(f"- {m} dominates " + (", ".join(beaten) if beaten else "nothing"))
        if not sgd:
            out("- no sgd-icp method on this pairs file")
    return "\n".join(lines) + "\n"


def with_pareto_section(report: str, section: str) -> str:
    """report with its "## Pareto" section (up to the next level-2 heading) replaced by section, or
    section appended: a repeated --pareto-from does not add a second one."""
    lines = report.splitlines()
    if "## Pareto" in lines:
        start = lines.index("## Pareto")
        end = next((i for i in range(start + 1, len(lines)) if lines[i].startswith("## ")), len(lines))
        lines = lines[:start] + lines[end:]
    text = "\n".join(lines).rstrip("\n")
    return (text + "\n\n" if text else "") + section


def plot_pareto(stats: dict[str, list[MethodStats]], path: str) -> bool:
    """pareto.png: median time (log x) against median rotation error (log y), a marker shape per
    method, a colour per pairs file, filled on the pairs file's front; False (and a note on stderr)
    without matplotlib. Points without a positive time and error are left out."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from matplotlib.lines import Line2D
    except ImportError:
        log("plot skipped: matplotlib not installed")
        return False
    methods = list(dict.fromkeys(s.method for st in stats.values() for s in st))
    marker = {m: PARETO_MARKERS[i % len(PARETO_MARKERS)] for i, m in enumerate(methods)}
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    colour = {g: colours[i % len(colours)] for i, g in enumerate(stats)}
    fig, ax = plt.subplots(figsize=(8, 5))
    left_out = []
    for g, st in stats.items():
        front = set(pareto_front(st))
        for s in st:
            if not (s.time_ms > 0 and s.r_err_deg > 0):  # also False for NaN
                left_out.append(f"{g}/{s.method}")
                continue
            ax.plot([s.time_ms], [s.r_err_deg], linestyle="none", marker=marker[s.method], markersize=7,
                    markeredgecolor=colour[g], markerfacecolor=colour[g] if s.method in front else "none")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("median time [ms]")
    ax.set_ylabel("median rotation error [°]")
    ax.set_title("Time vs rotation error per pairs file (filled: on its Pareto front)")
    ax.grid(True, which="both", alpha=0.3)
    handles = [Line2D([], [], linestyle="none", marker=marker[m], color="0.3", markerfacecolor="none",
                      label=m) for m in methods]
    handles += [Line2D([], [], linestyle="none", marker="s", color=colour[g], label=g) for g in stats]
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0,
              fontsize="small", frameon=False)
    fig.savefig(path, dpi=150, bbox_inches="tight")
    plt.close(fig)
    if left_out:
        log(f"[pareto] not plotted (no positive time or rotation error): {', '.join(left_out)}")
    return True


def pareto_from(folder: str, success: tuple[float, float]) -> int:
    """--pareto-from: the Pareto section of folder/runs.csv (else folder/summary.csv, whose success
    is the run's) appended to folder/report.md (made if missing) and printed, and folder/pareto.png."""
    runs_csv, summary_csv = os.path.join(folder, "runs.csv"), os.path.join(folder, "summary.csv")
    if os.path.isfile(runs_csv):
        stats = dataset_stats(read_csv(runs_csv), success)
    elif os.path.isfile(summary_csv):
        log(f"[pareto] no {runs_csv}: the medians and success of {summary_csv}")
        stats, success = summary_stats(read_csv(summary_csv)), None
    else:
        log(f"[pareto] neither {runs_csv} nor {summary_csv}")
        return 2
    if not stats:
        log(f"[pareto] no registration runs in {folder}")
        return 2
    section = pareto_section(stats, success)
    report_md = os.path.join(folder, "report.md")
    report = ""
    if os.path.isfile(report_md):
        with open(report_md) as f:
            report = f.read()
    with open(report_md, "w") as f:
        f.write(with_pareto_section(report, section))
    print(section)
    plotted = plot_pareto(stats, os.path.join(folder, "pareto.png"))
    log(f"[done] {report_md} (Pareto section)" + (f", {folder}/pareto.png" if plotted else ""))
    return 0



if __name__ == "__main__":
    sys.exit(main())
