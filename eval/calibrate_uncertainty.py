#!/usr/bin/env python3
"""Is the reported pose covariance the spread of the actual errors? A Monte-Carlo check.

    python3 eval/calibrate_uncertainty.py          # the full protocol (~7 min on 2 busy cores)
    python3 eval/calibrate_uncertainty.py --datasets kitti,eth --noise 0.01 --trials 10
    python3 eval/calibrate_uncertainty.py --out /tmp/calib --json /tmp/calib/calibration.json

For each scene (one real cloud), each noise level and each trial, one problem is drawn: the
scene's points are split at random into two halves (source, reference), each half gets its own
i.i.d. Gaussian noise of sigma NOISE metres per coordinate (--noise, the same for every scene),
and the source is moved by a known random rigid motion: a translation of uniform length in
[0, --max-translation] in a uniformly random direction and a rotation of uniform angle in
[0, --max-rotation] about a uniformly random axis. The problem of trial k depends only on
(--seed, scene, noise, k): the same problems on every run and every code version, whichever
subsets are asked for. The reference is built as a user gets it
(`ReferenceIndex.for_registration`: a voxel grid of ~20k points over a larger cloud), the point
estimate (uncertainty='none') is timed, then each method on the same problem and index:
  laplace          the Laplace covariance, tempered by the measured correlation factor kappa
  laplace-naive    the same with temper=False: residuals taken as independent (what peers report)
  sgld, svgd       the samplers, tempered (the defaults); any method-naive runs it untempered
The error e = theta_est - theta_gt (theta = x, y, z, roll, pitch, yaw of T_reference_source,
metres and radians, angles wrapped) is compared with the reported covariance P, per (scene, noise,
method), over the trials that did not fail:
  variance ratio per block   tr(mean P) / tr(E[e e^T]) over the translation and the rotation
                             blocks (1 = calibrated, < 1 over-confident); the std ratio is its root
  NEES = e^T P^-1 e          chi-square with 6 dof when P is right: mean 6; its mean and median
  coverage                   the share of NEES below the chi2(6) quantiles of 68.3 % and 95.4 %
  bias share per block       |mean e|^2 / mean |e|^2: the part of the second moment that an offset
                             common to all problems makes (no per-problem covariance can hold it)
  cost                       median wall time / median wall time of the point estimate
  kappa                      the median correlation_factor the method reports
  ess                        sgld: the median effective_samples of its chain (slowest coordinate)
A trial fails (it is listed, counted and left out of the statistics) when register() raises,
when its estimate or covariance is not finite or the covariance not positive definite, or when
its translation or rotation error is above OUTLIER_FACTOR (10) times the median of the method's
trials at that (scene, noise). A (scene, noise, method) passes when both variance ratios are in
TARGET_VARIANCE_RATIO ([0.67, 1.5]: the predicted variance within 1.5x of the actual) and the mean
NEES in TARGET_NEES ([4, 9]), over at least MIN_TRIALS (2) trials.

Scenes (--data, default ../shared/data beside the repository):
  kitti      KITTI 00 Velodyne scan 000000 (125k points, outdoor, ~150 m)
  handheld   a hand-held spinning LiDAR scan, the 11th of balm_handheld_lidar/scans (72k, ~60 m)
  car        libpointmatcher's car scan cloud.00000.vtk (25k, outdoor, ~130 m)
  eth        the ETH Kinect "high complexity" map (38k, a fused map, ~4 m)
  7scenes    7-Scenes RedKitchen depth frame 0, back-projected (274k, ~3 m)
  pclkinect  PCL's office1 Kinect frame (254k, ~4 m)
  bunny      PCL's bunny bun0 (397 points, 15 cm: 3 cm noise and 0.3 m motions are large to it)
  synthetic  a floor, two walls, a box and a ball (40k points, 6 m; the unit tests' kind of scene)
svgd reports the covariance of its heaviest mode (the CSV has its number of modes per trial);
--particles 16,32,64 runs svgd once per particle count (rows 'svgd K=16', ...).

Writes DIR/calibration.csv (one row per trial and method, the point estimate as method 'none'
with setup_ms, the problem's drawing and index; errors, reported standard deviations, NEES,
kappa, time, status), DIR/calibration.md (the table grouped by scene then noise, a PASS/FAIL line
per row, the count and the failed trials; also printed), with --json the summary as JSON, with
--figure the errors and mean reported 95 % ellipses per (scene, noise). Each group's progress line
says where its time went. Needs sgd_icp and numpy (matplotlib for --figure).
"""
from __future__ import annotations

import argparse
import csv
import hashlib
import json
import math
import subprocess
import sys
import time
import zlib
from pathlib import Path

import numpy as np

import sgd_icp

sys.path.insert(0, str(Path(__file__).resolve().parent))
from calibration_figure import draw_figure  # noqa: E402  (the figure of --figure)

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
# chi2(6) quantiles of the 1-sigma and 2-sigma probabilities (68.27 %, 95.45 %)
CHI2_1SIGMA, CHI2_2SIGMA = 7.0406, 12.8491

DATASETS = ("kitti", "handheld", "car", "eth", "7scenes", "pclkinect", "bunny", "synthetic")
SCENE_FILES = {
    "kitti": "kitti_odometry_seq00/velodyne/000000.bin",
    "car": "libpointmatcher_car/cloud.00000.vtk",
    "eth": "eth_kinect_highcomplexity_map/high-complexity-environment_map_ascii.ply",
    "pclkinect": "pcl_kinect_frames/office1.xyz.f32",
    "bunny": "pcl_bunny/bunny.pcd",
}
HANDHELD_SCAN = 10  # the 11th scan of balm_handheld_lidar/scans in sorted order
NOISE_LEVELS_M = (0.003, 0.01, 0.03)
MAX_TRANSLATION_M, MAX_ROTATION_DEG = 0.3, 5.0
METHODS = ("laplace", "laplace-naive", "sgld", "svgd")
SEED = 2026

TARGET_VARIANCE_RATIO = (0.67, 1.5)
TARGET_NEES = (4.0, 9.0)
OUTLIER_FACTOR = 10.0
MIN_TRIALS = 2
POINT_ESTIMATE = "none"  # the method name of the point estimate's rows


def methods(names: list[str], particles: list[int]) -> dict:
    """The register() keywords of each row's label: 'laplace' tempered, 'laplace-naive' labelled
    'laplace (naive)' with temper=False (likewise sgld, svgd); svgd once per particle count
    when more than one is given ('svgd K=16', ...)."""
    out = {}
    for name in names:
        naive = name.endswith("-naive")
        base = name.removesuffix("-naive")
        if base not in ("laplace", "sgld", "svgd"):
            raise ValueError(f"unknown method {name!r}: laplace, sgld or svgd, each optionally "
                             "with -naive")
        suffix = " (naive)" if naive else ""
        counts = particles if base == "svgd" and len(particles) > 1 else [None]
        for k in counts:
            kw = dict(uncertainty=base, temper=not naive)
            if base == "svgd":
                kw["particles"] = k if k is not None else particles[0]
            out[f"svgd K={k}{suffix}" if k is not None else f"{base}{suffix}"] = kw
    return out


# ---- scenes and problems

def synthetic_scene(rng: np.random.Generator, n: int = 40000) -> np.ndarray:
    a, b = rng.random(n), rng.random(n)
    part = np.arange(n) % 5
    p = np.zeros((n, 3))
    p[part == 0] = np.c_[6 * a, 4 * b, 0 * a][part == 0]
    p[part == 1] = np.c_[6 * a, 0 * a, 2.5 * b][part == 1]
    p[part == 2] = np.c_[0 * a, 4 * a, 2.5 * b][part == 2]
    p[part == 3] = np.c_[2 + 0.8 * a, 1.5 + 0.5 * b, 0.9 + 0 * a][part == 3]
    th, ph = 2 * np.pi * a, np.arccos(2 * b - 1)
    ball = np.c_[4.2 + 0.5 * np.sin(ph) * np.cos(th), 2.8 + 0.5 * np.sin(ph) * np.sin(th),
                 0.6 + 0.5 * np.cos(ph)]
    p[part == 4] = ball[part == 4]
    return p


def load_scene(name: str, rng: np.random.Generator | None = None, data: Path = DATA) -> np.ndarray:
    """The scene's points, (N, 3) float64 metres. 'synthetic' is drawn from rng (default: a
    generator seeded with SEED, the same scene every time)."""
    if name == "synthetic":
        return synthetic_scene(rng if rng is not None else np.random.default_rng(SEED))
    if name == "7scenes":
        folder = data / "sevenscenes_redkitchen"
        points = sgd_icp.read_depth_image(folder / "frame-000000.depth.png",
                                          folder / "camera-intrinsics.txt")
    elif name == "handheld":
        scans = sorted((data / "balm_handheld_lidar" / "scans").glob("*.bin"))
        if len(scans) <= HANDHELD_SCAN:
            raise FileNotFoundError(f"{data / 'balm_handheld_lidar/scans'}: fewer than "
                                    f"{HANDHELD_SCAN + 1} scans")
        points = sgd_icp.read_points(scans[HANDHELD_SCAN])
    elif name in SCENE_FILES:
        points = sgd_icp.read_points(data / SCENE_FILES[name])
    else:
        raise ValueError(f"unknown dataset {name!r}: one of {', '.join(DATASETS)}")
    return points.astype(np.float64)


def problem_seed(dataset: str, noise_m: float, trial: int, seed: int = SEED) -> list[int]:
    """The seed of one problem: a function of (seed, dataset, noise in micrometres, trial) only."""
    return [seed, zlib.crc32(dataset.encode()), round(noise_m * 1e6), trial]


def rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = (np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch),
                              np.cos(yaw), np.sin(yaw))
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def pose_of(T: np.ndarray) -> np.ndarray:
    r = T[:3, :3]
    pitch = np.arctan2(-r[2, 0], np.hypot(r[0, 0], r[1, 0]))
    return np.r_[T[:3, 3], np.arctan2(r[2, 1], r[2, 2]), pitch, np.arctan2(r[1, 0], r[0, 0])]


def T_of(theta: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = rpy_matrix(*theta[3:])
    T[:3, 3] = theta[:3]
    return T


def axis_angle_matrix(axis: np.ndarray, angle_rad: float) -> np.ndarray:
    """The rotation by angle_rad about the unit vector axis (Rodrigues)."""
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle_rad) * k + (1 - np.cos(angle_rad)) * (k @ k)


def random_unit_vector(rng: np.random.Generator) -> np.ndarray:
    """A direction uniform on the sphere (a normalised isotropic Gaussian)."""
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def random_motion(rng: np.random.Generator, max_translation_m: float = MAX_TRANSLATION_M,
                  max_rotation_deg: float = MAX_ROTATION_DEG) -> np.ndarray:
    """A 4x4 rigid motion: translation of uniform length in [0, max] in a uniform direction,
    rotation of uniform angle in [0, max] about a uniform axis."""
    T = np.eye(4)
    T[:3, 3] = rng.uniform(0, max_translation_m) * random_unit_vector(rng)
    T[:3, :3] = axis_angle_matrix(random_unit_vector(rng),
                                  np.deg2rad(rng.uniform(0, max_rotation_deg)))
    return T


def split_problem(scene: np.ndarray, order: np.ndarray, T_gt: np.ndarray, noise_m: float,
                  rng: np.random.Generator):
    """Source = the first half of scene[order] moved by T_gt^-1 (so reference = T_gt source),
    reference = the second half; each gets its own N(0, noise_m^2) per coordinate."""
    half = len(scene) // 2
    src, ref = scene[order[:half]], scene[order[half:]]
    # T_gt^-1 p for row vectors; einsum: OpenBLAS's matmul of an (n, 3) by a 3x3 is ~8x slower
    src = np.einsum("ni,ij->nj", src - T_gt[:3, 3], T_gt[:3, :3])
    src += rng.normal(0, noise_m, src.shape)
    ref = ref + rng.normal(0, noise_m, ref.shape)
    return src.astype(np.float32), ref.astype(np.float32)


def draw_problem(scene: np.ndarray, noise_m: float, rng: np.random.Generator,
                 max_translation_m: float = MAX_TRANSLATION_M,
                 max_rotation_deg: float = MAX_ROTATION_DEG):
    """(source float32, reference float32, T_reference_source ground truth 4x4) of one trial."""
    order = rng.permutation(len(scene))
    T_gt = random_motion(rng, max_translation_m, max_rotation_deg)
    src, ref = split_problem(scene, order, T_gt, noise_m, rng)
    return src, ref, T_gt


def wrap(angle_rad: np.ndarray) -> np.ndarray:
    """Angles in [-pi, pi)."""
    return (angle_rad + np.pi) % (2 * np.pi) - np.pi


def error_of(T_est: np.ndarray, T_gt: np.ndarray) -> np.ndarray:
    e = pose_of(T_est) - pose_of(T_gt)
    e[3:] = wrap(e[3:])
    return e


# ---- statistics

def nees_of(e: np.ndarray, P: np.ndarray) -> float:
    """e^T P^-1 e; NaN when P is not positive definite."""
    try:
        y = np.linalg.solve(np.linalg.cholesky(P), e)
    except np.linalg.LinAlgError:
        return math.nan
    return float(y @ y)


def trial_status(T_est: np.ndarray, P: np.ndarray) -> str:
    """'ok', or why the trial failed before the outlier check."""
    if not np.all(np.isfinite(T_est)):
        return "non-finite estimate"
    if not np.all(np.isfinite(P)):
        return "non-finite covariance"
    if math.isnan(nees_of(np.zeros(6), P)):
        return "covariance not positive definite"
    return "ok"


def outlier_reasons(errors: np.ndarray, factor: float = OUTLIER_FACTOR) -> list[str]:
    """Per trial (rows of (n, 6) errors): '' or why its error is an outlier: a translation or
    rotation error norm above factor x the median over the trials."""
    if len(errors) == 0:
        return []
    out = []
    norms = {"translation": np.linalg.norm(errors[:, :3], axis=1),
             "rotation": np.linalg.norm(errors[:, 3:], axis=1)}
    medians = {b: float(np.median(v)) for b, v in norms.items()}
    for i in range(len(errors)):
        why = [f"{b} error {norms[b][i] / medians[b]:.0f}x the median" for b in norms
               if norms[b][i] > factor * medians[b]]
        out.append("; ".join(why))
    return out


STATISTICS = ("var_ratio_t", "std_ratio_t", "bias_share_t", "var_ratio_r", "std_ratio_r",
              "bias_share_r", "mean_nees", "median_nees", "coverage_1sigma", "coverage_2sigma")


def summarize(errors: np.ndarray, covs: np.ndarray) -> dict:
    """The calibration statistics of (n, 6) errors against their (n, 6, 6) covariances (a NaN NEES,
    not positive definite, is left out of the mean and median, outside both coverages)."""
    e, P = np.asarray(errors, float).reshape(-1, 6), np.asarray(covs, float).reshape(-1, 6, 6)
    n = len(e)
    if n == 0:
        return dict(n=0, **dict.fromkeys(STATISTICS, math.nan))
    nees = np.array([nees_of(ei, Pi) for ei, Pi in zip(e, P)])
    second = e.T @ e / n
    mean_p = P.mean(axis=0)
    mean_e = e.mean(axis=0)
    out = dict(n=n)
    for b, s in (("t", slice(0, 3)), ("r", slice(3, 6))):
        out[f"var_ratio_{b}"] = float(np.trace(mean_p[s, s]) / np.trace(second[s, s]))
        out[f"std_ratio_{b}"] = math.sqrt(out[f"var_ratio_{b}"])
        out[f"bias_share_{b}"] = float(mean_e[s] @ mean_e[s] / np.trace(second[s, s]))
    out.update(mean_nees=float(np.nanmean(nees)), median_nees=float(np.nanmedian(nees)),
               coverage_1sigma=float(np.mean(nees < CHI2_1SIGMA)),
               coverage_2sigma=float(np.mean(nees < CHI2_2SIGMA)))
    return out


def verdict(stats: dict) -> list[str]:
    """Why a (scene, noise, method) misses the targets; empty when it passes."""
    if stats["n"] < MIN_TRIALS:
        return [f"{stats['n']} valid trials (< {MIN_TRIALS})"]
    why = []
    lo, hi = TARGET_VARIANCE_RATIO
    for b, block in (("t", "translation"), ("r", "rotation")):
        r = stats[f"var_ratio_{b}"]
        if not lo <= r <= hi:
            side = (f"< {lo:g}: {1 / r if r > 0 else math.inf:.1f}x over-confident" if r < lo
                    else f"> {hi:g}: {r:.1f}x under-confident" if r > hi else "undefined")
            why.append(f"{block} variance ratio {r:.3g} {side}")
    lo, hi = TARGET_NEES
    m = stats["mean_nees"]
    if not lo <= m <= hi:
        why.append(f"mean NEES {m:.3g} " + (f"< {lo:g}" if m < lo else f"> {hi:g}" if m > hi
                                            else "undefined"))
    return why


# ---- the run

def package_identity() -> dict:
    """What was measured: the package's version, its compiled core's hash and time, the tree's
    commit (the installed package may have been built from another)."""
    core = next(Path(sgd_icp.__file__).parent.glob("_core*.so"), None)
    ident = dict(version=getattr(sgd_icp, "__version__", "?"),
                 package=str(Path(sgd_icp.__file__).parent))
    if core is not None:
        ident["core_sha256"] = hashlib.sha256(core.read_bytes()).hexdigest()[:16]
        ident["core_mtime"] = time.strftime("%Y-%m-%d %H:%M:%S",
                                            time.localtime(core.stat().st_mtime))
    try:
        ident["tree_commit"] = subprocess.run(
            ["git", "-C", str(REPO), "describe", "--always", "--dirty"], capture_output=True,
            text=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        pass
    return ident


def run_trial(dataset, noise_m, trial, scene, settings, args, figure_samples) -> list[dict]:
    """The rows of one problem: the point estimate's, then one per method."""
    t0 = time.perf_counter()
    rng = np.random.default_rng(problem_seed(dataset, noise_m, trial, args.seed))
    src, ref, T_gt = draw_problem(scene, noise_m, rng, args.max_translation, args.max_rotation)
    # The reference as register(src, ref) prepares it (its voxel grid of ~20k points): what a
    # user gets, not a hand-built index over every point.
    try:
        index, index_error = sgd_icp.ReferenceIndex.for_registration(ref), None
    except Exception as ex:  # noqa: BLE001  (the trial's failure, reported per method)
        index, index_error = None, f"exception (reference index): {type(ex).__name__}: {ex}"
    setup_ms = 1e3 * (time.perf_counter() - t0)
    rows = []
    for m, kw in [(POINT_ESTIMATE, {})] + list(settings.items()):
        row = dict(dataset=dataset, noise_m=noise_m, trial=trial, method=m)
        if m == POINT_ESTIMATE:
            row["setup_ms"] = setup_ms
        t0 = time.perf_counter()
        try:
            if index_error:
                raise RuntimeError(index_error)
            r = sgd_icp.register(src, index, seed=trial, **kw)
        except Exception as ex:  # noqa: BLE001  (any failure is the trial's, reported)
            row.update(status=index_error or f"exception: {type(ex).__name__}: {ex}",
                       time_ms=math.nan)
            rows.append(row)
            continue
        row["time_ms"] = 1e3 * (time.perf_counter() - t0)
        T = np.array(r.T_reference_source)
        e = error_of(T, T_gt) if np.all(np.isfinite(T)) else np.full(6, math.nan)
        row.update(e=e, converged=r.converged)
        if m == POINT_ESTIMATE:
            row["status"] = "ok" if np.all(np.isfinite(T)) else "non-finite estimate"
            rows.append(row)
            continue
        P = np.array(r.covariance)
        row.update(P=P, status=trial_status(T, P), kappa=r.correlation_factor,
                   residual_sigma_m=r.residual_sigma_m, pairs=r.uncertainty_pairs,
                   modes=len(r.modes), ess=r.effective_samples)
        row["nees"] = nees_of(e, P) if row["status"] == "ok" else math.nan
        if trial == 0 and len(r.samples) and figure_samples is not None:
            # The first trial's samples as errors (theta - theta_gt): a cloud around that trial's
            # estimate, to set against the spread of every trial's estimate.
            figure_samples[m] = np.array([error_of(T_of(x), T_gt) for x in r.samples])
        rows.append(row)
    return rows


def group_summary(rows: list[dict], base_rows: list[dict]) -> dict:
    """Marks the group's outlier trials (status) and returns its statistics, cost and kappa."""
    valid = [r for r in rows if r["status"] == "ok"]
    for r, why in zip(valid, outlier_reasons(np.array([r["e"] for r in valid]).reshape(-1, 6))):
        if why:
            r["status"] = f"outlier: {why}"
    valid = [r for r in valid if r["status"] == "ok"]
    stats = summarize(np.array([r["e"] for r in valid]), np.array([r["P"] for r in valid]))
    base_ms = [r["time_ms"] for r in base_rows if r["status"] == "ok"]
    times = [r["time_ms"] for r in rows if not math.isnan(r["time_ms"])]
    stats["cost"] = (float(np.median(times) / np.median(base_ms)) if times and base_ms
                     else math.nan)
    stats["median_ms"] = float(np.median(times)) if times else math.nan
    stats["kappa"] = float(np.median([r["kappa"] for r in valid])) if valid else math.nan
    stats["ess"] = float(np.median([r["ess"] for r in valid if r.get("ess", 0) > 0] or [math.nan]))
    stats["trials"] = len(rows)
    stats["failed"] = len(rows) - len(valid)
    stats["why_fail"] = verdict(stats)
    stats["passed"] = not stats["why_fail"]
    return stats


CSV_FIELDS = ["dataset", "noise_m", "trial", "method", "status", "nees",
              "ex", "ey", "ez", "eroll", "epitch", "eyaw", "sx", "sy", "sz", "sroll", "spitch",
              "syaw", "kappa", "ess", "residual_sigma_m", "pairs", "modes", "converged",
              "time_ms", "setup_ms"]


def csv_row(r: dict) -> dict:
    out = {k: r.get(k, "") for k in CSV_FIELDS}
    if "e" in r:
        out.update(zip(CSV_FIELDS[6:12], r["e"]))
    if "P" in r:
        out.update(zip(CSV_FIELDS[12:18], np.sqrt(np.abs(np.diag(r["P"])))))
    return out


def fmt(v: float, spec: str) -> str:
    return "n/a" if v is None or (isinstance(v, float) and math.isnan(v)) else format(v, spec)


def report(groups: list[dict], failed_rows: list[dict], args, wall_s: float, ident: dict) -> str:
    """The markdown table, the PASS/FAIL lines, the count and the failed trials."""
    lo, hi = TARGET_VARIANCE_RATIO
    lines = [
        f"{args.trials} trials per (dataset, noise); random halves of one scene, i.i.d. Gaussian "
        f"noise per coordinate on each half; motion up to {args.max_translation:g} m / "
        f"{args.max_rotation:g} deg (uniform length and angle, uniform direction and axis); seed "
        f"{args.seed}. var ratio = tr(mean P) / tr(E[e e^T]) per block (1 = calibrated, < 1 "
        f"over-confident); target: both var ratios in [{lo:g}, {hi:g}] and the mean NEES in "
        f"[{TARGET_NEES[0]:g}, {TARGET_NEES[1]:g}]; bias = |mean e|^2 / E|e|^2 per block; cost "
        "= median time / median point-estimate time; failed trials are left out of the "
        "statistics.",
        f"sgd_icp {ident.get('version')} (core {ident.get('core_sha256', '?')}, built "
        f"{ident.get('core_mtime', '?')}; tree {ident.get('tree_commit', '?')}); wall time "
        f"{wall_s / 60:.1f} min.",
        "",
        "| dataset | noise (m) | method | trials (failed) | var ratio t | var ratio r | mean NEES "
        "| median NEES | 1-sigma cov. (68 %) | 2-sigma cov. (95 %) | bias t | bias r | cost | "
        "kappa | ess | target |",
        "|" + " --- |" * 16,
    ]
    for g in groups:
        lines.append(
            f"| {g['dataset']} | {g['noise_m']:g} | {g['method']} | {g['trials']} "
            f"({g['failed']}) | {fmt(g['var_ratio_t'], '.2f')} | {fmt(g['var_ratio_r'], '.2f')} "
            f"| {fmt(g['mean_nees'], '.3g')} | {fmt(g['median_nees'], '.3g')} | "
            f"{fmt(g['coverage_1sigma'], '.0%')} | {fmt(g['coverage_2sigma'], '.0%')} | "
            f"{fmt(g['bias_share_t'], '.0%')} | {fmt(g['bias_share_r'], '.0%')} | "
            f"{fmt(g['cost'], '.1f')}x | {fmt(g['kappa'], '.3g')} | {fmt(g['ess'], '.0f')} | "
            f"{'PASS' if g['passed'] else 'FAIL'} |")
    lines.append("")
    for g in groups:
        head = (f"{'PASS' if g['passed'] else 'FAIL'} {g['dataset']} {g['noise_m']:g} m "
                f"{g['method']}")
        detail = (f"var ratio t {fmt(g['var_ratio_t'], '.2f')}, r {fmt(g['var_ratio_r'], '.2f')}, "
                  f"mean NEES {fmt(g['mean_nees'], '.3g')}")
        if g["why_fail"]:
            detail = "; ".join(g["why_fail"])
        failed = f" ({g['failed']} failed trials left out)" if g["failed"] else ""
        lines.append(f"- {head}: {detail}{failed}")
    passed = sum(g["passed"] for g in groups)
    trials = sum(g["trials"] for g in groups)
    lines += ["", f"**{passed} of {len(groups)} (dataset, noise, method) pass**; "
              f"{len(failed_rows)} failed trials of {trials} method runs."]
    if failed_rows:
        lines += ["", "Failed trials:", ""]
        lines += [f"- {r['dataset']} {r['noise_m']:g} m {r['method']} trial {r['trial']}: "
                  f"{r['status']}" for r in failed_rows]
    return "\n".join(lines) + "\n"


def time_split(rows: list[dict]) -> str:
    """Where a group's time went: problems (drawing, index) and each method's register() calls."""
    parts = {"problems": sum(r.get("setup_ms", 0.0) for r in rows)}
    for r in rows:
        if not math.isnan(r["time_ms"]):
            parts[r["method"]] = parts.get(r["method"], 0.0) + r["time_ms"]
    return ", ".join(f"{k} {v / 1e3:.1f} s" for k, v in parts.items())


def jsonable(v):
    """v with NaN and infinities as None (JSON has neither), numpy values as Python's."""
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, dict):
        return {k: jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [jsonable(x) for x in v]
    return None if isinstance(v, float) and not math.isfinite(v) else v


def run(args, settings: dict) -> str:
    t_start = time.perf_counter()
    ident = package_identity()
    rows, groups, figure_data = [], [], {}
    for dataset in args.datasets:
        scene = load_scene(dataset, data=args.data)
        for noise_m in args.noise:
            t0 = time.perf_counter()
            samples = {} if args.figure is not None else None
            trial_rows = []
            for trial in range(args.trials):
                trial_rows += run_trial(dataset, noise_m, trial, scene, settings, args, samples)
            base_rows = [r for r in trial_rows if r["method"] == POINT_ESTIMATE]
            for m in settings:
                g = group_summary([r for r in trial_rows if r["method"] == m], base_rows)
                groups.append(dict(dataset=dataset, noise_m=noise_m, method=m, **g))
            rows += trial_rows
            if args.figure is not None:
                first = next(iter(settings))
                ok = {m: [r for r in trial_rows if r["method"] == m and r["status"] == "ok"]
                      for m in settings}
                figure_data[f"{dataset}, noise {noise_m:g} m"] = (
                    np.array([r["e"] for r in ok[first]]).reshape(-1, 6),
                    {m: np.mean([r["P"] for r in v], axis=0) for m, v in ok.items() if v},
                    samples)
            print(f"{dataset} {noise_m:g} m: {args.trials} trials, "
                  f"{time.perf_counter() - t0:.0f} s ({time_split(trial_rows)})", flush=True)
    wall_s = time.perf_counter() - t_start
    failed_rows = sorted((r for r in rows if r["status"] != "ok"),  # the point estimates' last
                         key=lambda r: r["method"] == POINT_ESTIMATE)
    text = report(groups, failed_rows, args, wall_s, ident)
    args.out.mkdir(parents=True, exist_ok=True)
    with open(args.out / "calibration.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=CSV_FIELDS)
        w.writeheader()
        w.writerows(csv_row(r) for r in rows)
    (args.out / "calibration.md").write_text(text)
    if args.json is not None:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(jsonable(dict(
            protocol=dict(datasets=args.datasets, noise_m=args.noise, trials=args.trials,
                          methods=settings, max_translation_m=args.max_translation,
                          max_rotation_deg=args.max_rotation, seed=args.seed,
                          target_variance_ratio=TARGET_VARIANCE_RATIO, target_nees=TARGET_NEES,
                          outlier_factor=OUTLIER_FACTOR, min_trials=MIN_TRIALS),
            package=ident, wall_s=wall_s, groups=groups,
            passed=sum(g["passed"] for g in groups), total=len(groups),
            failed_trials=[dict(dataset=r["dataset"], noise_m=r["noise_m"], method=r["method"],
                                trial=r["trial"], status=r["status"]) for r in failed_rows],
        )), indent=1) + "\n")
    if args.figure is not None:
        draw_figure(figure_data, args.figure)
    return text


def parse_args(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--datasets", default=",".join(DATASETS),
                    help=f"scenes, comma-separated, of {', '.join(DATASETS)} [default: all]")
    ap.add_argument("--noise", default=",".join(f"{v:g}" for v in NOISE_LEVELS_M),
                    help="sensor noise levels, metres per coordinate (one standard deviation), "
                    "comma-separated, the same for every scene [default: "
                    f"{','.join(f'{v:g}' for v in NOISE_LEVELS_M)}]")
    ap.add_argument("--trials", type=int, default=30,
                    help="problems per (dataset, noise), a count; trial k is the same problem "
                    "whatever the count [default: 30]")
    ap.add_argument("--methods", default=",".join(METHODS),
                    help="uncertainty methods, comma-separated: laplace, sgld, svgd (tempered), "
                    f"each also as NAME-naive (temper=False) [default: {','.join(METHODS)}]")
    ap.add_argument("--max-translation", type=float, default=MAX_TRANSLATION_M,
                    help="largest ground-truth translation, metres (its length is uniform in "
                    f"[0, this]) [default: {MAX_TRANSLATION_M:g}]")
    ap.add_argument("--max-rotation", type=float, default=MAX_ROTATION_DEG,
                    help="largest ground-truth rotation angle, degrees (uniform in [0, this]) "
                    f"[default: {MAX_ROTATION_DEG:g}]")
    ap.add_argument("--seed", type=int, default=SEED,
                    help="the problems' seed, an integer; change it only to draw another set of "
                    f"problems [default: {SEED}]")
    ap.add_argument("--particles", default="32",
                    help="svgd particle counts, comma-separated (one svgd row per count when "
                    "more than one) [default: 32]")
    ap.add_argument("--svgd-iterations", type=int, default=None,
                    help="svgd iterations, a count [default: the library's]")
    ap.add_argument("--svgd-spread", type=float, default=None,
                    help="svgd initial spread, in Laplace standard deviations [default: the "
                    "library's]")
    ap.add_argument("--data", type=Path, default=DATA,
                    help="the shared data folder [default: ../shared/data beside the repository]")
    ap.add_argument("--out", type=Path, default=Path("results/uncertainty"),
                    help="folder of calibration.csv and calibration.md [default: "
                    "results/uncertainty]")
    ap.add_argument("--json", type=Path, default=None,
                    help="also write the summary (protocol, package, per-row statistics and "
                    "verdicts, failed trials) as JSON here [default: none]")
    ap.add_argument("--figure", type=Path, default=None,
                    help="also draw the errors, the mean reported 95 %% ellipses and the first "
                    "trial's samples, one row per (dataset, noise) (PNG) [default: none]")
    args = ap.parse_args(argv)
    args.datasets = args.datasets.split(",")
    unknown = [d for d in args.datasets if d not in DATASETS]
    if unknown:
        ap.error(f"unknown datasets {unknown}: of {', '.join(DATASETS)}")
    try:
        args.noise = [float(v) for v in args.noise.split(",")]
    except ValueError:
        ap.error(f"--noise: not a comma-separated list of metres: {args.noise}")
    if any(not v >= 0 for v in args.noise) or args.trials < 1:
        ap.error("--noise levels must be >= 0 and --trials at least 1")
    try:
        args.settings = methods(args.methods.split(","),
                                [int(k) for k in args.particles.split(",")])
    except ValueError as ex:
        ap.error(f"--methods / --particles: {ex}")
    return args


def main(argv=None) -> None:
    args = parse_args(argv)
    settings = args.settings
    svgd_options = dict(svgd_iterations=args.svgd_iterations, svgd_spread=args.svgd_spread)
    for kw in settings.values():
        if kw["uncertainty"] == "svgd":
            kw.update({k: v for k, v in svgd_options.items() if v is not None})
    print(run(args, settings))


if __name__ == "__main__":
    main()
