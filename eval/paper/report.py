"""report.md of eval/reproduce.py: what ran and how, the tables and figures, the failed runs, and
the sanity checks of --quick."""
from __future__ import annotations

import math
import os
import statistics
import time

from .config import CONFIGS, FIG2_SEEDS, FIGURES, PEER_NAME, SEVEN_CONFIGS, SEVEN_PEERS
from .experiments import Peers
from .tables import fig2_table, fig4_table, fnum, is_ok, success, table_md


CHECK_WORD = {True: "PASS", False: "FAIL", None: "SKIP"}


def sanity_checks(out: str, t1: list[dict], t2: list[dict], f2: list[dict], f4: list[dict],
                  peers: Peers) -> list[tuple[str, bool | None, str]]:
    """(name, passed, note) of each check; passed is None for a check that was skipped. The report
    must exist for the first one."""
    res = [("report.md exists", os.path.exists(os.path.join(out, "report.md")), "")]
    for f in FIGURES:
        p = os.path.join(out, f)
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
                "Run on the same pairs in this run by the runners of `bench/compare_peers.py` (`bench/peers`), "
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


def make_report(args, exe, quick, repeat, t1, t7, t2, f1, f1info, f2, f4, runner, peers, times, elapsed,
                checks) -> str:
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
    if t7:
        L.append("## Table I on a real Kinect sequence: 7-Scenes RedKitchen\n")
        L.append("The 600 depth frames of `../shared/data/sevenscenes_redkitchen` (hand-held Kinect, 30 Hz, "
                 "every valid pixel back-projected: ~270k points per frame), pairs 1, 3 and 10 frames apart "
                 "(`sevenscenes_table1_Napart`: every consecutive pair and 100 pairs each 3 and 10 apart, "
                 "none with a repeated depth frame); ground truth from the dense-tracking poses (their "
                 "precision, a few mm, is the floor of the errors). One seed per pair; "
                 + ", ".join(SEVEN_CONFIGS) + " and the peers "
                 + ", ".join(PEER_NAME[w] for w in SEVEN_PEERS) + " where installed.\n")
        L.append(table_md(t7))
        L.append("")
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
