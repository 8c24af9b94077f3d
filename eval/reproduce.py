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
bench/compare_peers.py (the harness bench/peers/: each registration in a worker process, stopped
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

The experiments, the figures and the report are in eval/paper/ (its __init__ lists the modules).
"""
from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# The harness bench/peers/ (not installed with the package, which it needs).
sys.path.insert(0, os.path.join(REPO, "bench"))
try:
    import sgd_icp  # noqa: F401 - the harness reads clouds and scores with the package
    # the harness eval/paper uses: pairs files, the `sgdicp bench` runner and the peers' runners
    # (those of bench/compare_peers.py)
    from peers import PeerSettings
except ImportError as e:
    sys.exit(f"eval/reproduce.py needs the sgd_icp Python package ({e}): "
             "run `pip install .` in the repository (docs/python.md)")

from paper.config import (CONFIGS, DATA, FIG2_SEEDS, PEER_NAME, PEERS, QUICK_PEERS,  # noqa: E402
                          TABLE1_DEFAULT, log)
from paper.experiments import Peers, exp_peers, exp_sevenscenes, exp_table  # noqa: E402
from paper.figures import exp_fig1, exp_fig2, exp_fig4  # noqa: E402
from paper.report import CHECK_WORD, make_report, sanity_checks  # noqa: E402
from paper.runner import Runner, write_rows  # noqa: E402


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
    ap.add_argument("--no-sevenscenes", action="store_true",
                    help="skip Table I on the 7-Scenes sequence (full mode; ~2 GB of frames generated "
                         "beside the repository on first use)")
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

    # Table I on the 7-Scenes sequence (full mode, when ../shared/data has it)
    t0 = time.perf_counter()
    t7: list[dict] = []
    if not quick and not args.no_sevenscenes and os.path.isdir(os.path.join(DATA, "sevenscenes_redkitchen")):
        try:
            t7 = exp_sevenscenes(runner, wanted, exe, args.timeout)
        except Exception as e:  # noqa: BLE001 - recorded, the other experiments go on
            runner.failures.append(("sevenscenes", repr(e)))
        write_rows(os.path.join(args.out, "table1_sevenscenes.csv"), t7)
        times["Table I 7-Scenes"] = time.perf_counter() - t0

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

    # Sanity checks (the report must exist for the first one: write it, then check, then rewrite)
    report = make_report(args, exe, quick, repeat, t1, t7, t2, f1, f1info, f2, f4, runner, peers, times, elapsed, [])
    with open(os.path.join(args.out, "report.md"), "w") as f:
        f.write(report)
    res = sanity_checks(args.out, t1, t2, f2, f4, peers)
    report = make_report(args, exe, quick, repeat, t1, t7, t2, f1, f1info, f2, f4, runner, peers, times, elapsed, res)
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


if __name__ == "__main__":
    sys.exit(main())
