#!/usr/bin/env python3
"""Is the reported pose covariance the spread of the actual errors? A Monte-Carlo check.

usage: eval/calibrate_uncertainty.py [--trials N] [--noise-scale F] [--out DIR] [--datasets LIST]
                                     [--methods LIST] [--particles LIST] [--svgd-iterations N]
                                     [--svgd-spread S] [--figure PNG]

For each dataset, `--trials` independent problems are drawn from one scene: the scene's points are
split at random into two halves (source, reference), each half gets its own Gaussian sensor noise
(NOISE_M, metres per coordinate, times --noise-scale), and the source is moved by a known random rigid motion (up to
5 cm / 2 deg). Each problem is registered once per uncertainty method; the error
e = theta_est - theta_gt (x, y, z, roll, pitch, yaw of T_reference_source, angles wrapped) is
compared with the reported covariance P:
  NEES = e^T P^-1 e        (chi-square with 6 dof when P is right: mean 6)
  coverage of the 1-sigma / 2-sigma ellipsoids: NEES below the 68.3 % / 95.4 % chi2(6) quantiles
  std ratio per block: sqrt(trace of mean P) / sqrt(trace of E[e e^T]) for the translation and
  the rotation blocks (1 when calibrated; < 1 over-confident)
Datasets: 'synthetic' (a floor, two walls, a box and a ball, 20k points, the unit tests' scene),
'kitti' (KITTI 00 scan 0, 120k points), 'bunny' (PCL bunny bun0, 397 points), 'kinect' (ETH Kinect
map, 38k points): real geometry, so the test is independent of the estimator's own model.

svgd reports the covariance of its heaviest mode; the CSV has its number of modes per trial.
--particles 16,32,64 runs svgd once per particle count (rows 'svgd K=16 (tempered)', ...).

Writes DIR/calibration.csv (one row per trial and method) and DIR/calibration.md (the table of
docs/uncertainty.md). Needs the sgd_icp package (`pip install .`) and numpy.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import sgd_icp

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data"
# chi2(6) quantiles of the 1-sigma and 2-sigma probabilities (68.27 %, 95.45 %)
CHI2_1SIGMA, CHI2_2SIGMA = 7.0406, 12.8491

NOISE_M = {"synthetic": 0.01, "kitti": 0.02, "bunny": 0.001, "kinect": 0.005}


def methods(names: list[str], particles: list[int]) -> dict:
    """The uncertainty settings of each row: every method naive and tempered; svgd once per
    particle count when more than one is given."""
    out = {}
    for name in names:
        for temper in (False, True):
            label = "tempered" if temper else "naive"
            if name != "svgd" or len(particles) == 1:
                extra = dict(particles=particles[0]) if name == "svgd" else {}
                out[f"{name} ({label})"] = dict(uncertainty=name, temper=temper, **extra)
                continue
            for k in particles:
                out[f"svgd K={k} ({label})"] = dict(uncertainty=name, temper=temper, particles=k)
    return out


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


def load_scene(name: str, rng: np.random.Generator) -> np.ndarray:
    if name == "synthetic":
        return synthetic_scene(rng)
    path = {
        "kitti": DATA / "kitti_odometry_seq00/velodyne/000000.bin",
        "bunny": DATA / "pcl_bunny/bunny.pcd",
        "kinect": DATA / "eth_kinect_highcomplexity_map/high-complexity-environment_map_ascii.ply",
    }[name]
    return sgd_icp.read_points(path).astype(np.float64)


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


def draw_problem(scene: np.ndarray, noise_m: float, rng: np.random.Generator):
    half = rng.permutation(len(scene))
    src, ref = scene[half[: len(scene) // 2]], scene[half[len(scene) // 2:]]
    theta = np.r_[rng.uniform(-0.05, 0.05, 3), np.deg2rad(rng.uniform(-2, 2, 3))]
    T_gt = T_of(theta)
    src = (src - T_gt[:3, 3]) @ T_gt[:3, :3]  # T_gt^-1 p for row vectors: reference = T_gt src
    src = src + rng.normal(0, noise_m, src.shape)
    ref = ref + rng.normal(0, noise_m, ref.shape)
    return src.astype(np.float32), ref.astype(np.float32), T_gt


def wrap(angle_rad: np.ndarray) -> np.ndarray:
    """Angles in [-pi, pi)."""
    return (angle_rad + np.pi) % (2 * np.pi) - np.pi


def error_of(T_est: np.ndarray, T_gt: np.ndarray) -> np.ndarray:
    e = pose_of(T_est) - pose_of(T_gt)
    e[3:] = wrap(e[3:])
    return e


# The 2-D marginals drawn per dataset: translation x-y in mm, rotation pitch-yaw in deg.
PANELS = (((0, 1), 1e3, "x error (mm)", "y error (mm)"),
          ((4, 5), np.degrees(1.0), "pitch error (deg)", "yaw error (deg)"))
CHI2_95_2DOF = 5.991  # the 95 % ellipse of a 2-D Gaussian


def ellipse_xy(mean2, cov2, radius: float, n: int = 100) -> np.ndarray:
    """(n, 2) points of the Mahalanobis-radius contour of a 2-D Gaussian (a semi-definite
    covariance gives a flat ellipse)."""
    vals, vecs = np.linalg.eigh(cov2)
    t = np.linspace(0, 2 * np.pi, n)
    circle = np.c_[np.cos(t), np.sin(t)] * (radius * np.sqrt(np.maximum(vals, 0)))
    return np.asarray(mean2) + circle @ vecs.T


def draw_figure(figure_data: dict, path: Path) -> None:
    """Per dataset: the actual errors of every trial (dots), the 95 % ellipse of each method's mean
    reported covariance around zero, and the first trial's samples / particles (as errors)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(figure_data)
    fig, axes = plt.subplots(len(names), 2, figsize=(11, 4.2 * len(names)), squeeze=False)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for row, name in enumerate(names):
        errors, mean_covs, first_samples = figure_data[name]
        for col, (axes_idx, unit, xlabel, ylabel) in enumerate(PANELS):
            ax = axes[row, col]
            idx = list(axes_idx)
            ax.scatter(errors[:, idx[0]] * unit, errors[:, idx[1]] * unit, s=10, c="0.35",
                       label=f"actual errors ({len(errors)} trials)", zorder=3)
            actual = errors[:, idx].T @ errors[:, idx] / len(errors)
            e = ellipse_xy(np.zeros(2), actual * unit**2, np.sqrt(CHI2_95_2DOF)).T
            ax.plot(*e, c="k", lw=2.2, ls="--", label="95 % of the actual errors")
            # The peers' report (naive laplace) and the tempered methods; the rest would clutter.
            drawn = [m for m in mean_covs if m.endswith("(tempered)") or m == "laplace (naive)"]
            for k, m in enumerate(drawn):
                c = colours[k % len(colours)]
                e = ellipse_xy(np.zeros(2), mean_covs[m][np.ix_(idx, idx)] * unit**2,
                               np.sqrt(CHI2_95_2DOF)).T
                ax.plot(*e, c=c, lw=1.6, ls=":" if "naive" in m else "-",
                        label=f"{m}: mean reported 95 %")
                if m in first_samples and m.endswith("(tempered)"):
                    smp = first_samples[m]
                    ax.scatter(smp[:, idx[0]] * unit, smp[:, idx[1]] * unit, s=9, color=c,
                               alpha=0.5, marker="x" if m.startswith("svgd") else ".",
                               label=f"{m}: trial 0 samples")
            ax.set_xlabel(xlabel)
            ax.set_ylabel(ylabel)
            ax.set_title(name)
            ax.set_aspect("equal", adjustable="datalim")
            ax.grid(alpha=0.3)
        axes[row, 1].legend(fontsize=7, loc="center left", bbox_to_anchor=(1.02, 0.5))
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=80)
    print(f"wrote {path}")


def run(datasets, trials, noise: dict, out: Path, settings: dict, figure: Path | None) -> str:
    rows, table = [], []
    figure_data = {}
    for name in datasets:
        rng = np.random.default_rng(2026)
        scene = load_scene(name, rng)
        noise_m = noise[name]
        errors = {m: [] for m in settings}
        covs = {m: [] for m in settings}
        times = {m: [] for m in settings}
        kappas = []
        base_ms = []
        first_samples = {}
        for trial in range(trials):
            src, ref, T_gt = draw_problem(scene, noise_m, rng)
            # The reference as register(src, ref) prepares it (its voxel grid of ~20k points):
            # what a user gets, not a hand-built index over every point.
            index = sgd_icp.ReferenceIndex.for_registration(ref)
            t0 = time.perf_counter()
            base = sgd_icp.register(src, index, seed=trial)
            base_ms.append(1e3 * (time.perf_counter() - t0))
            for m, kw in settings.items():
                t0 = time.perf_counter()
                r = sgd_icp.register(src, index, seed=trial, **kw)
                times[m].append(1e3 * (time.perf_counter() - t0))
                e = error_of(r.T_reference_source, T_gt)
                errors[m].append(e)
                covs[m].append(np.array(r.covariance))
                if trial == 0 and len(r.samples):
                    # The first trial's samples as errors (theta - theta_gt): a cloud around
                    # that trial's estimate, to set against the spread of every trial's estimate.
                    first_samples[m] = np.array([error_of(T_of(x), T_gt) for x in r.samples])
                nees = float(e @ np.linalg.solve(r.covariance, e))
                rows.append((name, trial, m, nees, *e, *np.sqrt(np.diag(r.covariance)),
                             r.correlation_factor, times[m][-1], len(r.modes)))
                if m.endswith("(tempered)") and len(kappas) <= trial:
                    kappas.append(r.correlation_factor)
        for m in settings:
            e, P = np.array(errors[m]), np.array(covs[m])
            nees = np.array([ei @ np.linalg.solve(Pi, ei) for ei, Pi in zip(e, P)])
            second = e.T @ e / len(e)
            mean_p = P.mean(axis=0)
            ratio_t = np.sqrt(np.trace(mean_p[:3, :3]) / np.trace(second[:3, :3]))
            ratio_r = np.sqrt(np.trace(mean_p[3:, 3:]) / np.trace(second[3:, 3:]))
            table.append((name, m, np.mean(nees), np.median(nees), np.mean(nees < CHI2_1SIGMA),
                          np.mean(nees < CHI2_2SIGMA), ratio_t, ratio_r,
                          np.median(times[m]) / np.median(base_ms), np.median(kappas)))
        figure_data[name] = (np.array(errors[next(iter(settings))]),
                             {m: np.mean(covs[m], axis=0) for m in settings}, first_samples)
        print(f"{name}: done ({trials} trials)", flush=True)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "calibration.csv", "w") as f:
        f.write("dataset,trial,method,nees,ex,ey,ez,eroll,epitch,eyaw,"
                "sx,sy,sz,sroll,spitch,syaw,kappa,time_ms,modes\n")
        for row in rows:
            f.write(",".join(str(v) for v in row) + "\n")
    lines = [
        f"{trials} trials per dataset, random halves, sensor noise per coordinate "
        + ", ".join(f"{d} {noise[d]} m" for d in datasets) + "; "
        "time = median wall time over the point estimate's (uncertainty='none').",
        "",
        "| dataset | method | mean NEES (6 = calibrated) | median NEES | 1-sigma coverage "
        "(68 %) | 2-sigma coverage (95 %) | std ratio translation | std ratio rotation | time "
        "/ point estimate | kappa |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for t in table:
        lines.append(f"| {t[0]} | {t[1]} | {t[2]:.3g} | {t[3]:.3g} | {t[4]:.0%} | {t[5]:.0%} | "
                     f"{t[6]:.2f} | {t[7]:.2f} | {t[8]:.1f}x | {t[9]:.3g} |")
    text = "\n".join(lines) + "\n"
    (out / "calibration.md").write_text(text)
    if figure is not None:
        draw_figure(figure_data, figure)
    return text


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trials", type=int, default=50)
    ap.add_argument("--noise-scale", type=float, default=1.0,
                    help="multiplies the sensor noise of every dataset (synthetic 1 cm, KITTI "
                    "2 cm, bunny 1 mm, Kinect 5 mm)")
    ap.add_argument("--datasets", default="synthetic,kitti,bunny,kinect")
    ap.add_argument("--methods", default="laplace,sgld,svgd")
    ap.add_argument("--particles", default="32",
                    help="svgd particle counts, comma-separated (one row pair per count)")
    ap.add_argument("--svgd-iterations", type=int, default=None,
                    help="svgd iterations (default: the library's)")
    ap.add_argument("--svgd-spread", type=float, default=None,
                    help="svgd initial spread in Laplace standard deviations (default: the "
                    "library's)")
    ap.add_argument("--out", type=Path, default=Path("results/uncertainty"))
    ap.add_argument("--figure", type=Path, default=None,
                    help="also draw the errors, the mean reported 95 %% ellipses and the first "
                    "trial's samples per dataset (PNG; e.g. docs/figures/uncertainty_calibration.png)")
    args = ap.parse_args()
    noise = {d: v * args.noise_scale for d, v in NOISE_M.items()}
    settings = methods(args.methods.split(","), [int(k) for k in args.particles.split(",")])
    svgd_options = dict(svgd_iterations=args.svgd_iterations, svgd_spread=args.svgd_spread)
    for kw in settings.values():
        if kw["uncertainty"] == "svgd":
            kw.update({k: v for k, v in svgd_options.items() if v is not None})
    print(run(args.datasets.split(","), args.trials, noise, args.out, settings, args.figure))


if __name__ == "__main__":
    main()
