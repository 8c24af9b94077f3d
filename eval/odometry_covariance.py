#!/usr/bin/env python3
"""Is the odometry's per-frame covariance the spread of its frame-to-frame errors? (NEES)

Against exact ground truth (issue 50: mean NEES in [4, 9], chi-square with 6 dof: 6 when right).

    python3 eval/odometry_covariance.py                          # built 1 cm + both real sequences
    python3 eval/odometry_covariance.py --sequences built --noise 0.003,0.01,0.03
    python3 eval/odometry_covariance.py --sequences handheld,7scenes --json /tmp/odo_cov.json

**The built sequence (exact ground truth from real scans).** The hand-held LiDAR's scans
(../shared/data/balm_handheld_lidar: scans/*.bin, poses.txt, the reference poses P_k = T_world_scan)
are moved by their reference poses into one static world cloud, thinned to one point per
--world-voxel (2 cm) voxel (a random one of the voxel's points, not a centroid: a centroid of two
surfaces seen from two poses is a point on neither), so that the world is one sample of the surface.
Frame k is a set of world points w, resampled, expressed in frame k's coordinates, T_k^-1 w with
T_k = P_k, plus i.i.d. Gaussian noise of --noise metres per coordinate (drawn per frame). Its
ground truth is P_k exactly, whatever the reference poses' own error (they only place the world):
the relative pose of frames i, j is P_i^-1 P_j by construction. Which world points (--sampling):
  nearest  (default) the world point nearest to each point of the real scan k placed by P_k, each
           taken once: the real scan's visibility (what a wall hides stays hidden), coverage and
           density, which falls with the range as a spinning LiDAR's does; a point repeated by
           several scan points (near range, where the scan is denser than the world) once. A
           better copy of a scan than `range`: frame and map then overlap as the real ones do
           (partially), and the near surfaces, which hold the rotation, weigh as in the real data.
  range    the world points within the real scan k's range interval [min, max] of P_k (what the
           issue describes), a uniform random subset: every surface within range, walls no
           obstacle, uniform density (far surfaces weigh as much as near ones).
Then a random subset of --points points when fewer (0: nearest keeps its selection, range the real
scan k's point count). Frames every --step-th scan, --frames of them.

**The error and its NEES.** The covariance C_k of frame k (odometry.reports[k].covariance) is that
of its registration to the local map, in covariance_se3's convention: xi = (rho, phi),
translation first, right perturbation T_true = T_est Exp(xi), xi in frame k's own tangent space.
The relative pose of frame k from its predecessor (the anchor) is R_k = T_{k-1}^-1 T_k (estimated:
odometry.poses; true: the reference), and its error
    xi_k = Log(R_k,est^-1 R_k,true) = -Log(E_k),   E_k = R_k,true^-1 R_k,est,
so that R_k,true = R_k,est Exp(xi_k): the covariance's convention (the sign does not change the
NEES). When both frames are registered against one map and their errors against it are xi_k and
xi_{k-1}, xi_k(relative) = xi_k - Ad(R_k^-1) xi_{k-1} to first order, so two NEES are reported:
  NEES_k       xi^T C_k^-1 xi: the frame's own registration alone (as if the map were frame k-1);
  NEES_k+prev  xi^T (C_k + Ad(R_k^-1) C_{k-1} Ad(R_k^-1)^T)^-1 xi: plus the anchor's error carried
               into frame k's tangent space (independent errors against a common map).
Read the target against NEES_k+prev: the local map a frame meets is mostly the earlier frames'
(a map cell keeps its first 20 points, so a full cell takes nothing from frame k-1), so frames k-1
and k are two registrations to largely one map, and R_k carries both their errors. The lag-1
correlation column checks it: consecutive relative errors share the anchor's error with opposite
signs, -0.5 for independent errors against a common map, 0 for a map that moves with each anchor
(measured -0.33 to -0.45 on the hand-held scans, built and real). C_k alone is the lower bound of
the relative pose's predicted variance (exact when the map moved with frame k-1), the sum its
upper bound; NEES_k is then the upper bound of the NEES.
Pairs are left out of the statistics when either frame is lost (report.failed) or has no finite
covariance, and on 7-Scenes when either frame is a byte-identical repeat of the frame before it
(PROVENANCE.md: its data are the previous pose's, its reference pose is not).

**Reported per sequence** (one row per sequence and noise): frames, lost frames (report.failed)
and pairs used; per NEES variant the mean and median NEES, the 1- and 2-sigma coverage (the share
of NEES below chi2(6)'s 68.3 % and 95.4 % quantiles), the variance ratio per block (tr of the mean
predicted covariance / tr E[xi xi^T], translation and rotation: 1 = calibrated, < 1
over-confident) and the bias share per block (|mean xi|^2 / E|xi|^2: the part of the second moment
a constant offset makes, which no per-frame covariance holds); the lag-1 correlation per block
(above); the median predicted standard deviations (sqrt of the block's trace of C_k, mm and
deg) and the median actual errors (|rho| mm, |phi| deg); the whole run's wall time with
uncertainty='none' and with --uncertainty's (register_frame calls only, frames already in
memory, one thread unless --threads; one run each). The real sequences (the hand-held LiDAR's
scans against poses.txt; the first --sevenscenes-frames 7-Scenes depth frames, read with
sgd_icp.read_depth_image and camera-intrinsics.txt, against their camera-to-world poses,
re-orthonormalised) are a figure to report, not the target: their references are good to ~5 mm /
0.05 deg (hand-held) and ~1 mm (7-Scenes) between neighbours (PROVENANCE.md), the size of the
predicted standard deviations or larger; that stated error is printed beside them.
--no-temper runs the untempered covariance (temper=False) instead, to see what the tempering adds.
--json writes the rows and the protocol; --frames-csv one row per pair (xi, predicted std, both
NEES). Needs sgd_icp, numpy and scipy (the world's KD-tree).
"""
from __future__ import annotations

import argparse
import csv
import hashlib
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

import sgd_icp

sys.path.insert(0, str(Path(__file__).resolve().parent))
import calibrate_uncertainty as cal  # noqa: E402  (NEES, the calibration statistics, the report)

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
# Issue 50's target for the mean NEES, and the report's number format: the calibration's.
TARGET_NEES = cal.TARGET_NEES
fmt = cal.fmt
SEQUENCES = ("built", "handheld", "7scenes")
SAMPLINGS = ("nearest", "range")
# The references' own frame-to-frame error, as PROVENANCE.md states it (m, deg; None: not stated).
REFERENCE_ERROR = {"handheld": (0.005, 0.05), "7scenes": (0.001, None)}
SEED = 2026


# ---- SE(3), xi = (rho, phi), translation first

def hat(v: np.ndarray) -> np.ndarray:
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def so3_exp(phi: np.ndarray) -> np.ndarray:
    theta = np.linalg.norm(phi)
    K = hat(phi)
    if theta < 1e-8:
        return np.eye(3) + K + 0.5 * K @ K
    return (np.eye(3) + math.sin(theta) / theta * K
            + (1 - math.cos(theta)) / theta**2 * K @ K)


def so3_log(R: np.ndarray) -> np.ndarray:
    c = np.clip((np.trace(R) - 1) / 2, -1.0, 1.0)
    theta = math.acos(c)
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    if theta < 1e-8:
        return 0.5 * w
    if math.pi - theta < 1e-6:  # near a half-turn: the axis from R + I
        M = (R + np.eye(3)) / 2
        axis = M[:, int(np.argmax(np.diag(M)))]
        axis = axis / np.linalg.norm(axis)
        return theta * axis * (1.0 if axis @ w >= 0 else -1.0)
    return theta / (2 * math.sin(theta)) * w


def left_jacobian(phi: np.ndarray) -> np.ndarray:
    theta = np.linalg.norm(phi)
    K = hat(phi)
    if theta < 1e-6:
        return np.eye(3) + 0.5 * K + K @ K / 6
    return (np.eye(3) + (1 - math.cos(theta)) / theta**2 * K
            + (theta - math.sin(theta)) / theta**3 * K @ K)


def se3_exp(xi: np.ndarray) -> np.ndarray:
    """Exp of xi = (rho, phi) (metres, radians) as a 4x4 transform."""
    T = np.eye(4)
    T[:3, :3] = so3_exp(xi[3:])
    T[:3, 3] = left_jacobian(xi[3:]) @ xi[:3]
    return T


def se3_log(T: np.ndarray) -> np.ndarray:
    """Log of a 4x4 transform as xi = (rho, phi)."""
    phi = so3_log(T[:3, :3])
    return np.r_[np.linalg.solve(left_jacobian(phi), T[:3, 3]), phi]


def adjoint(T: np.ndarray) -> np.ndarray:
    """Ad_T for xi = (rho, phi): T Exp(xi) T^-1 = Exp(Ad_T xi)."""
    R, t = T[:3, :3], T[:3, 3]
    A = np.zeros((6, 6))
    A[:3, :3] = A[3:, 3:] = R
    A[:3, 3:] = hat(t) @ R
    return A


def inverse(T: np.ndarray) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3] = T[:3, :3].T
    out[:3, 3] = -T[:3, :3].T @ T[:3, 3]
    return out


def orthonormal(T: np.ndarray) -> np.ndarray:
    """T with its rotation block projected onto the nearest rotation (SVD)."""
    U, _, Vt = np.linalg.svd(T[:3, :3])
    out = np.array(T, dtype=float)
    out[:3, :3] = U @ np.diag([1, 1, np.linalg.det(U @ Vt)]) @ Vt
    return out


def transform(T: np.ndarray, points: np.ndarray) -> np.ndarray:
    """T applied to (n, 3) row points."""
    return points @ T[:3, :3].T + T[:3, 3]


# ---- the built sequence

def thin_random(points: np.ndarray, voxel_m: float, rng: np.random.Generator) -> np.ndarray:
    """One point per voxel of voxel_m metres, a random one of the voxel's points."""
    order = rng.permutation(len(points))
    ijk = np.floor(points[order] / voxel_m).astype(np.int64)
    ijk -= ijk.min(axis=0)
    dims = ijk.max(axis=0) + 1
    key = (ijk[:, 0] * dims[1] + ijk[:, 1]) * dims[2] + ijk[:, 2]
    _, first = np.unique(key, return_index=True)
    return points[order[np.sort(first)]]


def build_world(scans: list[np.ndarray], poses: np.ndarray, voxel_m: float,
                rng: np.random.Generator) -> np.ndarray:
    """Every scan moved by its pose into one cloud, thinned to one point per voxel."""
    world = np.concatenate([transform(P, s.astype(np.float64)) for s, P in zip(scans, poses)])
    return thin_random(world, voxel_m, rng)


def select_world_points(world: np.ndarray, tree, scan: np.ndarray, pose: np.ndarray,
                        sampling: str, rng: np.random.Generator) -> np.ndarray:
    """Indices into world of the points frame k sees (see the docstring's --sampling)."""
    if sampling == "nearest":
        _, idx = tree.query(transform(pose, scan.astype(np.float64)))
        return np.unique(idx)
    if sampling == "range":
        r = np.linalg.norm(scan, axis=1)
        d = np.linalg.norm(world - pose[:3, 3], axis=1)
        inside = np.flatnonzero((d >= r.min()) & (d <= r.max()))
        return rng.choice(inside, size=min(len(scan), len(inside)), replace=False)
    raise ValueError(f"unknown sampling {sampling!r}: one of {', '.join(SAMPLINGS)}")


def make_frame(world: np.ndarray, idx: np.ndarray, pose: np.ndarray, points: int, noise_m: float,
               rng: np.random.Generator) -> np.ndarray:
    """World points idx (a random subset of `points` when fewer; 0: all) in the frame's
    coordinates, pose^-1 w, with N(0, noise_m^2) per coordinate; float32 as a scan is read."""
    if 0 < points < len(idx):
        idx = rng.choice(idx, size=points, replace=False)
    local = transform(inverse(pose), world[idx])
    return (local + rng.normal(0.0, noise_m, local.shape)).astype(np.float32)


def built_frames(scans: list[np.ndarray], poses: np.ndarray, *, voxel_m: float, sampling: str,
                 points: int, noise_m: float, seed: int) -> list[np.ndarray]:
    """The built sequence's frames (ground truth: poses, exactly)."""
    from scipy.spatial import cKDTree

    rng = np.random.default_rng([seed, round(noise_m * 1e6)])
    world = build_world(scans, poses, voxel_m, np.random.default_rng(seed))
    tree = cKDTree(world) if sampling == "nearest" else None
    frames = []
    for scan, pose in zip(scans, poses):
        idx = select_world_points(world, tree, scan, pose, sampling, rng)
        frames.append(make_frame(world, idx, pose, points, noise_m, rng))
    return frames


# ---- the sequences

def homogeneous(rows: np.ndarray) -> np.ndarray:
    P = np.asarray(rows, float).reshape(-1, 3, 4)
    return np.concatenate([P, np.tile([[[0, 0, 0, 1.0]]], (len(P), 1, 1))], axis=1)


def pick(count: int, step: int, frames: int) -> list[int]:
    """Every step-th of count indices, the first `frames` of them (0: all)."""
    out = list(range(0, count, step))
    return out[:frames] if frames > 0 else out


def load_handheld(data: Path, step: int, frames: int):
    """(scans (n, 3) float32 in the sensor frame, reference poses (K, 4, 4), names)."""
    folder = data / "balm_handheld_lidar"
    files = sorted((folder / "scans").glob("*.bin"))
    poses = homogeneous(np.loadtxt(folder / "poses.txt"))
    if len(poses) != len(files):
        raise ValueError(f"{folder}: {len(files)} scans, {len(poses)} poses")
    keep = pick(len(files), step, frames)
    return ([np.asarray(sgd_icp.read_points(files[i]), np.float32) for i in keep], poses[keep],
            [files[i].name for i in keep])


def repeated_frames(files: list[Path]) -> list[bool]:
    """Per file: True when its bytes equal the previous file's (7-Scenes' stale depth frames)."""
    digests = [hashlib.md5(f.read_bytes()).hexdigest() for f in files]
    return [False] + [a == b for a, b in zip(digests, digests[1:])]


def load_sevenscenes(data: Path, step: int, frames: int):
    """(clouds, camera-to-world poses re-orthonormalised, names, repeated flags)."""
    folder = data / "sevenscenes_redkitchen"
    files = sorted(folder.glob("frame-*.depth.png"))
    repeated = repeated_frames(files)
    keep = pick(len(files), step, frames)
    files = [files[i] for i in keep]
    # A picked frame is stale when it repeats the frame before it in the picked sequence.
    repeated = [False] + [repeated[b] and a == b - 1 for a, b in zip(keep, keep[1:])]
    K = folder / "camera-intrinsics.txt"
    clouds = [sgd_icp.read_depth_image(f, K) for f in files]
    poses = np.array([orthonormal(np.loadtxt(str(f).replace(".depth.png", ".pose.txt")))
                      for f in files])
    return clouds, poses, [f.name for f in files], repeated


# ---- the run and its errors

def run_odometry(frames: list[np.ndarray], method: str, uncertainty: str, threads: int,
                 temper: bool = True):
    """(poses (K, 4, 4), covariances (K, 6, 6), failed (K,), wall s of register_frame calls)."""
    keywords = dict(temper=False) if not temper and uncertainty != "none" else {}
    odometry = sgd_icp.Odometry(method, uncertainty=uncertainty, threads=threads, **keywords)
    start = time.perf_counter()
    for f in frames:
        odometry.register_frame(f)
    wall = time.perf_counter() - start
    reports = odometry.reports
    return (np.array(odometry.poses), np.array([r.covariance for r in reports]),
            np.array([r.failed for r in reports]), wall)


def relative_error(est_prev: np.ndarray, est: np.ndarray, true_prev: np.ndarray,
                   true: np.ndarray) -> np.ndarray:
    """xi = Log(R_est^-1 R_true), R = T_prev^-1 T: R_true = R_est Exp(xi) (the covariance's
    convention, frame k's tangent space)."""
    R_est = inverse(est_prev) @ est
    R_true = inverse(true_prev) @ true
    return se3_log(inverse(R_est) @ R_true)


def carried(C_prev: np.ndarray, R_est: np.ndarray) -> np.ndarray:
    """The anchor's covariance in frame k's tangent space: Ad(R^-1) C_prev Ad(R^-1)^T."""
    A = adjoint(inverse(R_est))
    return A @ C_prev @ A.T


def pair_rows(est: np.ndarray, true: np.ndarray, covs: np.ndarray, failed: np.ndarray,
              excluded: list[bool] | None = None) -> list[dict]:
    """One row per usable pair (k-1, k): xi, C_k, C_k + the carried C_{k-1}, both NEES."""
    rows = []
    for k in range(1, len(est)):
        if failed[k] or failed[k - 1] or (excluded and (excluded[k] or excluded[k - 1])):
            continue
        if not (np.all(np.isfinite(covs[k])) and np.all(np.isfinite(covs[k - 1]))):
            continue
        xi = relative_error(est[k - 1], est[k], true[k - 1], true[k])
        R = inverse(est[k - 1]) @ est[k]
        C_sum = covs[k] + carried(covs[k - 1], R)
        rows.append(dict(k=k, xi=xi, R=R, C=covs[k], C_sum=C_sum, nees=cal.nees_of(xi, covs[k]),
                         nees_sum=cal.nees_of(xi, C_sum)))
    return rows


def lag1_correlation(rows: list[dict]) -> dict:
    """Per block, the correlation of consecutive relative errors, xi_k against xi_{k-1} carried
    into frame k's tangent space (Ad(R_k^-1) xi_{k-1}), over the consecutive pairs: -0.5 when the
    frames' errors against a common map are independent (xi_k = e_k - Ad e_{k-1} shares e_{k-1}
    with the pair before, of opposite sign; equal variances), 0 when each frame's error is against
    a map that moved with its anchor (a random walk: independent increments)."""
    a, b = [], []
    for prev, cur in zip(rows, rows[1:]):
        if cur["k"] == prev["k"] + 1:
            a.append(cur["xi"])
            b.append(adjoint(inverse(cur["R"])) @ prev["xi"])
    a, b = np.array(a).reshape(-1, 6), np.array(b).reshape(-1, 6)
    out = {}
    for name, s in BLOCKS:
        den = math.sqrt(np.sum(a[:, s] ** 2) * np.sum(b[:, s] ** 2))
        out[f"lag1_corr_{name}"] = float(np.sum(a[:, s] * b[:, s]) / den) if den > 0 else math.nan
    return out


BLOCKS = (("t", slice(0, 3)), ("r", slice(3, 6)))


def block_std(C: np.ndarray) -> tuple[float, float]:
    """sqrt of the trace of each block: the norm of the per-axis standard deviations (m, rad)."""
    return math.sqrt(np.trace(C[:3, :3])), math.sqrt(np.trace(C[3:, 3:]))


def sequence_summary(rows: list[dict]) -> dict:
    """The pairs' calibration against C_k and against C_k + the carried C_k-1, the median
    predicted standard deviations and actual errors, the lag-1 correlation."""
    e = np.array([r["xi"] for r in rows]).reshape(-1, 6)
    out = dict(pairs=len(rows), alone=cal.summarize(e, [r["C"] for r in rows]),
               with_prev=cal.summarize(e, [r["C_sum"] for r in rows]), **lag1_correlation(rows))
    if not rows:
        return out | dict.fromkeys(("median_std_mm", "median_std_deg", "median_error_mm",
                                    "median_error_deg"), math.nan)
    std = np.median([block_std(r["C"]) for r in rows], axis=0)
    return out | dict(median_std_mm=float(std[0] * 1e3), median_std_deg=math.degrees(std[1]),
                      median_error_mm=float(np.median(np.linalg.norm(e[:, :3], axis=1)) * 1e3),
                      median_error_deg=math.degrees(np.median(np.linalg.norm(e[:, 3:], axis=1))))


def evaluate(name: str, frames: list[np.ndarray], true: np.ndarray, args,
             excluded: list[bool] | None = None, reference_error=None) -> tuple[dict, list[dict]]:
    """Runs the odometry without and with the uncertainty over the frames, and scores the second."""
    _, _, _, wall_none = run_odometry(frames, args.method, "none", args.threads)
    est, covs, failed, wall = run_odometry(frames, args.method, args.uncertainty, args.threads,
                                           args.temper)
    rows = pair_rows(est, true, covs, failed, excluded)
    summary = dict(sequence=name, frames=len(frames), lost=int(failed.sum()),
                   excluded=int(sum(excluded)) if excluded else 0,
                   wall_none_s=wall_none, wall_s=wall, reference_error=reference_error,
                   **sequence_summary(rows))
    for r in rows:
        r["sequence"] = name
    return summary, rows


# ---- the report

def reference_text(ref) -> str:
    if ref is None:
        return "exact"
    t, r = ref
    return f"~{t * 1e3:g} mm / " + (f"{r:g} deg" if r is not None else "rotation not stated")


def table(summaries: list[dict], uncertainty: str) -> str:
    head = ("| sequence | frames (lost, left out) | pairs | NEES against | mean NEES | median NEES "
            "| 1-sigma cov. (68 %) | 2-sigma cov. (95 %) | var ratio t | var ratio r | bias t "
            "| bias r | median std (mm / deg) | median error (mm / deg) | wall s none → "
            f"{uncertainty} | lag-1 corr. t / r | reference |")
    lines = [head, "|" + " --- |" * 17]
    for s in summaries:
        for key, label in (("alone", "C_k"), ("with_prev", "C_k + C_k-1")):
            c = s[key]
            lines.append(
                f"| {s['sequence']} | {s['frames']} ({s['lost']}, {s['excluded']}) | {s['pairs']} "
                f"| {label} | {fmt(c['mean_nees'], '.3g')} | {fmt(c['median_nees'], '.3g')} | "
                f"{fmt(c['coverage_1sigma'], '.0%')} | {fmt(c['coverage_2sigma'], '.0%')} | "
                f"{fmt(c['var_ratio_t'], '.2f')} | {fmt(c['var_ratio_r'], '.2f')} | "
                f"{fmt(c['bias_share_t'], '.0%')} | {fmt(c['bias_share_r'], '.0%')} | "
                f"{fmt(s['median_std_mm'], '.2f')} / {fmt(s['median_std_deg'], '.4f')} | "
                f"{fmt(s['median_error_mm'], '.2f')} / {fmt(s['median_error_deg'], '.4f')} | "
                f"{s['wall_none_s']:.1f} → {s['wall_s']:.1f} "
                f"({s['wall_s'] / s['wall_none_s']:.2f}x) | "
                f"{fmt(s['lag1_corr_t'], '.2f')} / {fmt(s['lag1_corr_r'], '.2f')} | "
                f"{reference_text(s['reference_error'])} |")
    return "\n".join(lines) + "\n"


def verdict(summaries: list[dict]) -> list[str]:
    """The target's reading (mean NEES against C_k + the carried C_k-1) for the built rows."""
    lo, hi = TARGET_NEES
    out = []
    for s in summaries:
        if s["reference_error"] is not None:
            continue
        m = s["with_prev"]["mean_nees"]
        ok = lo <= m <= hi
        out.append(f"- {'PASS' if ok else 'FAIL'} {s['sequence']}: mean NEES (C_k + C_k-1) "
                   f"{fmt(m, '.3g')}, target [{lo:g}, {hi:g}]; against C_k alone "
                   f"{fmt(s['alone']['mean_nees'], '.3g')}")
    return out


def write_frames_csv(path: Path, rows: list[dict]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fields = ["sequence", "k", "rho_x", "rho_y", "rho_z", "phi_x", "phi_y", "phi_z",
              "std_rho_x", "std_rho_y", "std_rho_z", "std_phi_x", "std_phi_y", "std_phi_z",
              "nees", "nees_sum"]
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(fields)
        for r in rows:
            w.writerow([r["sequence"], r["k"], *r["xi"], *np.sqrt(np.diag(r["C"])), r["nees"],
                        r["nees_sum"]])


# ---- main

def tag(args) -> str:
    """The row name's note of a run other than the tempered default."""
    return "" if args.temper else " (untempered)"


def run_built(args) -> list[tuple[dict, list[dict]]]:
    scans, poses, _ = load_handheld(args.data, args.step, args.frames)
    out = []
    for noise in args.noise:
        t0 = time.perf_counter()
        frames = built_frames(scans, poses, voxel_m=args.world_voxel, sampling=args.sampling,
                              points=args.points, noise_m=noise, seed=args.seed)
        build_s = time.perf_counter() - t0
        name = f"built {args.sampling}, noise {noise * 1e3:g} mm, every {args.step}" + tag(args)
        summary, rows = evaluate(name, frames, poses, args)
        summary.update(build_s=build_s, noise_m=noise,
                       points_median=int(np.median([len(f) for f in frames])))
        out.append((summary, rows))
        print(f"{name}: {len(frames)} frames ({summary['points_median']} points median), built in "
              f"{build_s:.0f} s, odometry {summary['wall_none_s']:.0f} + {summary['wall_s']:.0f} s",
              flush=True)
    return out


def run_real(args) -> list[tuple[dict, list[dict]]]:
    out = []
    if "handheld" in args.sequences:
        scans, poses, _ = load_handheld(args.data, args.step, args.frames)
        name = f"hand-held LiDAR, real scans, every {args.step}" + tag(args)
        out.append(evaluate(name, scans, poses, args, reference_error=REFERENCE_ERROR["handheld"]))
        print(f"{name}: done", flush=True)
    if "7scenes" in args.sequences:
        clouds, poses, _, repeated = load_sevenscenes(args.data, 1, args.sevenscenes_frames)
        name = f"7-Scenes, first {len(clouds)} frames" + tag(args)
        out.append(evaluate(name, clouds, poses, args, excluded=repeated,
                            reference_error=REFERENCE_ERROR["7scenes"]))
        print(f"{name}: done", flush=True)
    return out


def parse_args(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sequences", default=",".join(SEQUENCES),
                    help=f"comma-separated, of {', '.join(SEQUENCES)} [default: all]")
    ap.add_argument("--uncertainty", default="laplace", choices=("laplace", "sgld", "svgd"),
                    help="the odometry's uncertainty method [default: laplace]")
    ap.add_argument("--no-temper", dest="temper", action="store_false",
                    help="the untempered covariance (temper=False: residuals taken as "
                    "independent, what the peers report), for comparison [default: tempered]")
    ap.add_argument("--method", default="sgd",
                    help="the odometry's registration method (an SGD one) [default: sgd]")
    ap.add_argument("--noise", default="0.01",
                    help="built sequence: sensor noise, metres per coordinate (one standard "
                    "deviation), comma-separated for several runs [default: 0.01]")
    ap.add_argument("--frames", type=int, default=0,
                    help="hand-held scans used (built and real), a count after --step; 0 = all "
                    "[default: 0]")
    ap.add_argument("--step", type=int, default=1,
                    help="use every step-th hand-held scan (built and real), a count [default: 1]")
    ap.add_argument("--points", type=int, default=0,
                    help="built sequence: points per frame, a count (a random subset when the "
                    "selection has more); 0 = nearest: all it selects, range: the real scan's "
                    "count [default: 0]")
    ap.add_argument("--sampling", default="nearest", choices=SAMPLINGS,
                    help="built sequence: which world points a frame sees (see above) "
                    "[default: nearest]")
    ap.add_argument("--world-voxel", type=float, default=0.02,
                    help="built sequence: the world's thinning voxel, metres [default: 0.02]")
    ap.add_argument("--seed", type=int, default=SEED,
                    help="built sequence: the seed of the world's thinning, the selection and "
                    f"the noise, an integer [default: {SEED}]")
    ap.add_argument("--sevenscenes-frames", type=int, default=300,
                    help="7-Scenes: the first this many depth frames, a count [default: 300]")
    ap.add_argument("--threads", type=int, default=1,
                    help="the odometry's threads, a count [default: 1]")
    ap.add_argument("--data", type=Path, default=DATA,
                    help="the shared data folder [default: ../shared/data beside the repository]")
    ap.add_argument("--json", type=Path, default=None,
                    help="also write the protocol and the rows as JSON here [default: none]")
    ap.add_argument("--frames-csv", type=Path, default=None,
                    help="also write one CSV row per pair (xi in m and rad, the predicted "
                    "per-axis std, both NEES) here [default: none]")
    args = ap.parse_args(argv)
    args.sequences = args.sequences.split(",")
    unknown = [s for s in args.sequences if s not in SEQUENCES]
    if unknown:
        ap.error(f"unknown sequences {unknown}: of {', '.join(SEQUENCES)}")
    try:
        args.noise = [float(v) for v in args.noise.split(",")]
    except ValueError:
        ap.error(f"--noise: not a comma-separated list of metres: {args.noise}")
    if any(not v >= 0 for v in args.noise) or args.step < 1 or args.frames < 0 or args.points < 0:
        ap.error("--noise must be >= 0, --step >= 1, --frames and --points >= 0")
    return args


def main(argv=None) -> None:
    args = parse_args(argv)
    t0 = time.perf_counter()
    results = run_built(args) if "built" in args.sequences else []
    results += run_real(args)
    summaries = [s for s, _ in results]
    text = table(summaries, args.uncertainty) + "\n" + "\n".join(verdict(summaries))
    print(text)
    print(f"sgd_icp {getattr(sgd_icp, '__version__', '?')}; {time.perf_counter() - t0:.0f} s")
    if args.json is not None:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        protocol = {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()}
        record = dict(protocol=protocol, target_nees=TARGET_NEES, rows=summaries)
        args.json.write_text(json.dumps(cal.jsonable(record), indent=1) + "\n")
    if args.frames_csv is not None:
        write_frames_csv(args.frames_csv, [r for _, rows in results for r in rows])


if __name__ == "__main__":
    main()
