#!/usr/bin/env python3
"""How far are sgld's samples and svgd's particles from their posterior? An MCMC reference.

usage: eval/mcmc_reference.py [--datasets LIST] [--trials N] [--points N] [--chains C]
                              [--steps N] [--pairings LIST] [--seed S] [--out DIR]
                              [--figure PATH]

The Stein ICP paper's protocol (Maken, Ramos, Ott, RA-L 2022): a long Metropolis-Hastings chain on
the same likelihood as the samplers is the reference, and each method is scored by its KL
divergence to it, and by its run time.

Problems are drawn like eval/calibrate_uncertainty.py's earlier protocol (random halves of a
scene, sensor noise per scene: NOISE_M, a random motion up to 5 cm / 2 deg per axis; kept here so
that the tables of docs/uncertainty.md reproduce), each half then subsampled at random to
--points points, so that an evaluation of the energy over every source point is cheap. Each
problem is registered by the library once per method (laplace, sgld, svgd; tempered, the
defaults) with reference normals estimated here (PCA of the 10 nearest points), no voxel grid and
the default point-to-plane cost.

The energy is written here independently of the library, in the reported theta = (x, y, z, roll,
pitch, yaw) of T_reference_source (R = Rz(yaw) Ry(pitch) Rx(roll), metres and radians):
  U(theta) = sum_i ((R s_i + t - r_i) . n_i)^2 / (2 sigma^2 kappa)
with sigma = residual_sigma_m, kappa = correlation_factor and d_max = final_max_distance_m as the
library reports them, and one of two pairings (--pairings):
  nearest  r_i is the nearest reference point of the moved s_i, pairs beyond d_max dropped, at
           every theta: the likelihood as written. It is rough at the posterior's scale: a
           point that changes its nearest neighbour jumps to another noisy point and normal
           (~0.5 nats per jump; a Laplace standard deviation moves dozens of points across),
           and a pair crossing d_max with a large residual drops 10-20 nats at once. Its
           chains need a proposal several times smaller than Laplace's, mix slowly and mostly
           stay in different local minima (split R-hat up to ~10; measured: converged on 3 of
           12 problems, none of Kinect's and KITTI's): no reference within minutes. Where they
           converge its mass sits several Laplace standard deviations from the estimate, where
           outlying pairs fall beyond d_max: the estimate is the fixed point of ICP's
           re-paired gradient, not U's minimum. The tables take medians over the problems
           whose chains converged only.
  fixed    the pairs of the estimate held (those within d_max there): the smooth energy whose
           curvature the Laplace approximation is and around which the samplers' control
           variate linearises their gradient; the reference for the samplers' accuracy.
The library's weak prior (std 1 scaled unit = the scene's size, 1 rad) is left out: its weight
is printed per problem (largest posterior variance over the prior's, 1e-7 to 1e-4).
Random-walk Metropolis-Hastings on U (see metropolis(): the optimal scaling 2.38^2 / 6 of the
Laplace covariance, adapted during the burn-in), --chains chains started at the estimate plus an
over-dispersed draw (3x the Laplace std), the first quarter of each chain discarded; split R-hat
and the effective sample size (Gelman et al., BDA3, 11.4-11.5) per axis are checked.

Scores per method, of Gaussian fits (mean, covariance) to the MCMC samples and to the method's
output (laplace: its covariance at the estimate; sgld: its samples; svgd: its heaviest mode,
i.e. its particles when there is one mode):
  KL(MCMC || method), KL(method || MCMC)   the closed-form KL of the two 6-D Gaussian fits (not
                                           of the sample distributions themselves)
  std ratio t / r                          sqrt(trace of the method's covariance block / trace
                                           of the MCMC one), translation and rotation blocks
  mean offset                              Mahalanobis distance of the method's mean from the
                                           MCMC mean, in MCMC standard deviations
  sample ESS                               sgld: the effective sample size of its 200 samples
                                           (one chain), the worst axis (its effective_samples)
  KL floor                                 KL(MCMC || fit) of a fit to K exact independent draws
                                           of the MCMC Gaussian (K = the method's sample count):
                                           what a perfect sampler with K samples would score
                                           (K independent samples: sgld's 200 are correlated,
                                           its own floor is higher)
and the wall times of the register() call and of the chain. The MCMC samples' per-axis excess
kurtosis (0 for a Gaussian) says whether a Gaussian comparison is enough.

Writes DIR/mcmc.csv (one row per problem and method), DIR/mcmc.md (the tables printed) and the
figure (one problem per dataset: the MCMC samples, the sgld samples, the svgd particles and the
2-sigma ellipses of the 2-D marginals). Needs the sgd_icp package, numpy, scipy and matplotlib.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree
from scipy.stats import kurtosis

import sgd_icp

sys.path.insert(0, str(Path(__file__).resolve().parent))
import calibrate_uncertainty as cal  # noqa: E402  (the problems of the calibration)
import calibration_figure as calfig  # noqa: E402  (its ellipses)

METHODS = ("laplace", "sgld", "svgd")
NORMAL_NEIGHBORS = 10  # the library's kSurfaceNeighbors
PROPOSAL_SCALE = 2.38**2 / 6  # optimal random-walk scaling in 6-D
START_SPREAD = 3.0  # over-dispersed starts, in Laplace standard deviations
RHAT_MAX = 1.05
TARGET_ACCEPTANCE = 0.234  # optimal for random-walk MH (Roberts, Gelman and Gilks 1997)
ADAPT_GAIN = 0.05
ANCHOR_REFRESH_STEPS = 100
KL_FLOOR_REPEATS = 200


# ---- problems

# Sensor noise per scene, metres per coordinate (calibrate_uncertainty's earlier protocol).
NOISE_M = {"synthetic": 0.01, "kitti": 0.02, "bunny": 0.001, "kinect": 0.005}
SCENES = {"kinect": "eth"}  # this script's dataset names that calibrate_uncertainty names otherwise


def draw_problem(scene: np.ndarray, noise_m: float, rng: np.random.Generator):
    """Random halves of the scene, the source moved by a motion drawn uniformly in a 5 cm / 2 deg
    box per axis, each half with its own Gaussian noise: (source, reference, T_reference_source)."""
    half = rng.permutation(len(scene))
    src, ref = scene[half[: len(scene) // 2]], scene[half[len(scene) // 2:]]
    theta = np.r_[rng.uniform(-0.05, 0.05, 3), np.deg2rad(rng.uniform(-2, 2, 3))]
    T_gt = cal.T_of(theta)
    src = (src - T_gt[:3, 3]) @ T_gt[:3, :3]  # T_gt^-1 p for row vectors: reference = T_gt src
    src = src + rng.normal(0, noise_m, src.shape)
    ref = ref + rng.normal(0, noise_m, ref.shape)
    return src.astype(np.float32), ref.astype(np.float32), T_gt


def small_problem(scene: np.ndarray, noise_m: float, points: int, rng: np.random.Generator):
    """A calibration problem whose halves are subsampled to `points` each (fewer if the half
    has fewer: the bunny's file holds ~400 points)."""
    src, ref, T_ref_src_gt = draw_problem(scene, noise_m, rng)
    src = src[np.sort(rng.choice(len(src), min(points, len(src)), replace=False))]
    ref = ref[np.sort(rng.choice(len(ref), min(points, len(ref)), replace=False))]
    return src, ref, T_ref_src_gt


def pca_normals(points_m: np.ndarray, k: int = NORMAL_NEIGHBORS) -> np.ndarray:
    """Unit normals: the eigenvector of the smallest eigenvalue of the covariance of each
    point's k nearest points (itself included). Their sign does not matter to (e . n)^2."""
    p = points_m.astype(np.float64)
    _, nb = cKDTree(p).query(p, k=min(k, len(p)))
    local = p[nb] - p[nb].mean(axis=1, keepdims=True)
    _, vectors = np.linalg.eigh(np.einsum("nki,nkj->nij", local, local))
    return vectors[:, :, 0]


def rotations(theta: np.ndarray) -> np.ndarray:
    """(C, 3, 3) R = Rz(yaw) Ry(pitch) Rx(roll) of (C, 6) poses (cal.rpy_matrix, batched)."""
    return np.stack([cal.rpy_matrix(*th[3:]) for th in theta])


def offsets_from(theta: np.ndarray, theta_hat: np.ndarray) -> np.ndarray:
    """theta - theta_hat with the angles wrapped: samples as offsets from the estimate."""
    d = np.atleast_2d(theta) - theta_hat
    d[:, 3:] = cal.wrap(d[:, 3:])
    return d


# ---- the energy, independent of the library

class Energy:
    """U(theta) of the point-to-plane likelihood over every source point (reported theta,
    metres and radians), evaluated for several poses (one per chain) at once.

    pairing 'nearest' (the library's likelihood as written): every source point is paired with
    its nearest reference point at theta, and dropped when that is farther than d_max.
    pairing 'fixed': the pairs of the estimate are held (those within d_max there, with their
    reference points): the smooth energy whose curvature the Laplace approximation is and
    around which the samplers' control variate linearises their gradient.

    'nearest' without a KD-tree query per point per step: at an anchor pose each moved source
    point has its nearest reference point at d1 and its second at d2; a point moved by delta
    from there keeps that nearest point while delta < (d2 - d1) / 2 (the nearest gains at most
    delta, any other loses at most delta). Only the points moved further are queried again;
    each chain's anchor is refreshed at its current pose every ANCHOR_REFRESH_STEPS steps."""

    def __init__(self, src_m, ref_m, ref_normals, d_max_m, sigma_m, kappa, theta_hat, pairing):
        # Coordinates first, (3, N): the moved points of C poses are one (C, 3, 3) @ (3, N).
        self.src_m = src_m.astype(np.float64).T.copy()
        self.ref_m = ref_m.astype(np.float64).T.copy()
        self.normals = np.asarray(ref_normals, dtype=np.float64).T.copy()
        self.d_max_sq_m2 = d_max_m**2
        self.inv_two_var = 1.0 / (2.0 * sigma_m**2 * kappa)
        self.pairing = pairing
        self.tree = cKDTree(self.ref_m.T)
        self.requeried = 0  # points queried again, for the record
        self.evaluated = 0
        self.set_anchors(theta_hat[None])
        nn, paired = self.anchor_nn[0], self.pairs_of(self.moved(theta_hat[None]),
                                                      self.anchor_nn)[0]
        self.nn_hat, self.paired_hat = nn, paired
        # 'fixed': e_i = n_i . (R s_i + t - r_i) is linear in z = (R row-major, t, 1), so U is
        # the quadratic form z^T M z with M = sum over the pairs of f_i f_i^T.
        n, r, s = self.normals[:, nn[paired]], self.ref_m[:, nn[paired]], self.src_m[:, paired]
        f = np.concatenate([(n[:, None, :] * s[None, :, :]).reshape(9, -1), n,
                            -(n * r).sum(axis=0)[None]])
        self.fixed_form = self.inv_two_var * f @ f.T

    def moved(self, theta: np.ndarray) -> np.ndarray:
        """(C, 3, N) source points moved by each of (C, 6) poses, reference frame."""
        return rotations(theta) @ self.src_m + theta[:, :3, None]

    def set_anchors(self, theta: np.ndarray) -> None:
        """Anchors of the cached neighbours, one per row of theta (the poses evaluated next)."""
        self.anchor_m = self.moved(theta)
        d, j = self.tree.query(self.anchor_m.transpose(0, 2, 1).reshape(-1, 3), k=2)
        self.anchor_nn = j[:, 0].reshape(len(theta), -1)
        self.margin_sq_m2 = (0.5 * (d[:, 1] - d[:, 0])).reshape(len(theta), -1) ** 2

    def nearest(self, q: np.ndarray, exact: bool) -> np.ndarray:
        """(C, N) index of the nearest reference point of each moved point."""
        if exact:
            return self.tree.query(q.transpose(0, 2, 1).reshape(-1, 3))[1].reshape(len(q), -1)
        nn = self.anchor_nn.copy()
        far = ((q - self.anchor_m) ** 2).sum(axis=1) >= self.margin_sq_m2
        if far.any():
            nn[far] = self.tree.query(q.transpose(0, 2, 1)[far])[1]
        self.requeried += int(far.sum())
        self.evaluated += far.size
        return nn

    def pairs_of(self, q: np.ndarray, nn: np.ndarray) -> np.ndarray:
        """(C, N) mask of the pairs within d_max."""
        return ((q - self.ref_m[:, nn].transpose(1, 0, 2)) ** 2).sum(axis=1) <= self.d_max_sq_m2

    def residuals(self, theta: np.ndarray, exact: bool = False):
        """(C, N) point-to-plane residuals (m) and (C, N) mask of the pairs counted, with the
        'nearest' pairing (exact: by a query of every point, the check of the cache)."""
        q = self.moved(theta)
        nn = self.nearest(q, exact)
        diff = q - self.ref_m[:, nn].transpose(1, 0, 2)
        paired = (diff * diff).sum(axis=1) <= self.d_max_sq_m2
        return (diff * self.normals[:, nn].transpose(1, 0, 2)).sum(axis=1), paired

    def __call__(self, theta: np.ndarray, exact: bool = False) -> np.ndarray:
        if self.pairing == "fixed" and not exact:
            z = np.concatenate([rotations(theta).reshape(-1, 9), theta[:, :3],
                                np.ones((len(theta), 1))], axis=1)
            return np.einsum("ci,ij,cj->c", z, self.fixed_form, z)
        e, paired = self.residuals(theta, exact)
        return self.inv_two_var * np.where(paired, e * e, 0.0).sum(axis=1)

    def fixed_direct(self, theta: np.ndarray) -> np.ndarray:
        """'fixed' U summed over the pairs directly (the check of the quadratic form)."""
        q = self.moved(theta)
        nn = np.broadcast_to(self.nn_hat, (len(theta), q.shape[2]))
        diff = q - self.ref_m[:, nn].transpose(1, 0, 2)
        e = (diff * self.normals[:, nn].transpose(1, 0, 2)).sum(axis=1)
        return self.inv_two_var * np.where(self.paired_hat, e * e, 0.0).sum(axis=1)


# ---- Metropolis-Hastings and its diagnostics

def metropolis(energy: Energy, theta_hat, cov_laplace, chains, steps, rng):
    """Random-walk Metropolis-Hastings, all chains in step, adapted during the burn-in only.
    Proposals N(0, s^2 2.38^2/6 Sigma) (the optimal scaling), Sigma first the Laplace
    covariance; halfway through the burn-in Sigma becomes the covariance of the chains' samples
    since the first eighth (the 'nearest' posterior is narrower than Laplace and shaped
    otherwise: Haario et al. 2001's adaptive Metropolis, frozen before the kept samples), and
    s is adapted throughout the burn-in (Robbins-Monro on log s, shared by the chains) towards
    an acceptance of 0.234: the 'nearest' energy is rough at the posterior's scale and rejects
    almost every full-size proposal. After the burn-in Sigma and s are fixed, so the kept
    samples are those of a plain MH chain. Returns the (C, steps, 6) offsets from theta_hat,
    the acceptance rate per chain after the burn-in and s (relative to Laplace's: the geometric
    mean of the final proposal's std over the first one's)."""
    chol = np.linalg.cholesky(cov_laplace)
    step_chol = np.sqrt(PROPOSAL_SCALE) * chol
    burn_in = steps // 4
    x = theta_hat + START_SPREAD * rng.standard_normal((chains, 6)) @ chol.T
    refresh = energy.pairing == "nearest"
    if refresh:
        energy.set_anchors(x)
    u = energy(x)
    log_scale = 0.0
    out = np.empty((chains, steps, 6))
    accepted = np.zeros(chains)
    for k in range(steps):
        if refresh and k % ANCHOR_REFRESH_STEPS == 0:
            energy.set_anchors(x)
        proposal = x + np.exp(log_scale) * rng.standard_normal((chains, 6)) @ step_chol.T
        u_new = energy(proposal)
        # Symmetric proposals: accept with probability min(1, exp(U(x) - U(x'))).
        take = np.log(rng.random(chains)) < u - u_new
        x[take], u[take] = proposal[take], u_new[take]
        if k < burn_in:
            log_scale += ADAPT_GAIN * (take.mean() - TARGET_ACCEPTANCE) / np.sqrt(1 + k / 100)
        else:
            accepted += take
        out[:, k] = x
        if k == burn_in // 2:
            shape = np.cov(out[:, burn_in // 4:k + 1].reshape(-1, 6), rowvar=False)
            step_chol = np.sqrt(PROPOSAL_SCALE) * np.linalg.cholesky(shape)
    out -= theta_hat
    out[:, :, 3:] = cal.wrap(out[:, :, 3:])
    scale = np.exp(log_scale) * (np.linalg.det(step_chol) / np.linalg.det(
        np.sqrt(PROPOSAL_SCALE) * chol)) ** (1 / 6)
    return out, accepted / (steps - burn_in), float(scale)


def split_chains(samples: np.ndarray) -> np.ndarray:
    """(C, N, 6) -> (2C, N // 2, 6): each chain's halves as separate chains (BDA3 11.4), so
    that a drift within a chain shows as a disagreement."""
    half = samples.shape[1] // 2
    return np.concatenate([samples[:, :half], samples[:, half:2 * half]])


def split_rhat(samples: np.ndarray) -> np.ndarray:
    x = split_chains(samples)
    n = x.shape[1]
    within = x.var(axis=1, ddof=1).mean(axis=0)
    between = n * x.mean(axis=1).var(axis=0, ddof=1)
    return np.sqrt(((n - 1) / n * within + between / n) / within)


def effective_sample_size(samples: np.ndarray) -> np.ndarray:
    """Per-axis ESS over all chains (BDA3 11.5): the autocorrelation from the variogram of the
    split chains, summed over Geyer's initial monotone sequence of positive pair sums."""
    x = split_chains(samples)
    m, n, d = x.shape
    centred = x - x.mean(axis=1, keepdims=True)
    spectrum = np.fft.rfft(centred, n=2 * n, axis=1)
    acov = np.fft.irfft(spectrum * np.conj(spectrum), axis=1)[:, :n] / n  # (m, n, d)
    within = x.var(axis=1, ddof=1).mean(axis=0)
    var_plus = (n - 1) / n * within + x.mean(axis=1).var(axis=0, ddof=1)
    rho = 1.0 - (within - acov.mean(axis=0)) / var_plus  # (n, d)
    ess = np.empty(d)
    for a in range(d):
        pairs = rho[0:n - 1:2, a] + rho[1:n:2, a]
        positive = np.argmax(pairs <= 0) if (pairs <= 0).any() else len(pairs)
        pairs = np.minimum.accumulate(pairs[:positive])
        tau = -1.0 + 2.0 * pairs.sum()
        ess[a] = m * n / max(tau, 1.0 / np.log10(m * n))
    return ess


# ---- Gaussian comparison

def gaussian_fit(offsets: np.ndarray):
    return offsets.mean(axis=0), np.cov(offsets, rowvar=False)


def gaussian_kl(mean0, cov0, mean1, cov1) -> float:
    """KL(N0 || N1) in closed form, in the space whitened by cov0 (KL is invariant under an
    affine map, and metres and radians differ by orders of magnitude)."""
    w = np.linalg.inv(np.linalg.cholesky(cov0))
    c1 = w @ cov1 @ w.T
    dm = w @ (mean1 - mean0)
    k = len(mean0)
    _, logdet1 = np.linalg.slogdet(c1)
    return 0.5 * (np.trace(np.linalg.solve(c1, np.eye(k))) + dm @ np.linalg.solve(c1, dm) - k
                  + logdet1)


def block_std_ratio(cov, cov_ref, block: slice) -> float:
    return float(np.sqrt(np.trace(cov[block, block]) / np.trace(cov_ref[block, block])))


def mahalanobis(mean, mean_ref, cov_ref) -> float:
    d = mean - mean_ref
    return float(np.sqrt(d @ np.linalg.solve(cov_ref, d)))


def kl_floor(count: int, rng: np.random.Generator) -> float:
    """Median KL(N || fit) of Gaussian fits to `count` exact independent draws of a 6-D N: the
    score of a perfect sampler with that many samples (whitened: it depends on count only)."""
    kls = [gaussian_kl(np.zeros(6), np.eye(6), *gaussian_fit(rng.standard_normal((count, 6))))
           for _ in range(KL_FLOOR_REPEATS)]
    return float(np.median(kls))


def method_fit(name: str, result, theta_hat: np.ndarray):
    """(mean offset, covariance, sample count) of a method's output around the estimate."""
    if name == "laplace":
        return np.zeros(6), np.array(result.covariance), 0
    samples = offsets_from(np.array(result.samples), theta_hat)
    if name == "svgd" and len(result.modes) > 1:
        # The reported covariance is the heaviest mode's; the other modes are not this optimum's.
        mode = result.modes[0]
        return (offsets_from(np.array(mode.mean), theta_hat)[0], np.array(mode.covariance),
                int(round(mode.weight * len(samples))))
    mean, cov = gaussian_fit(samples)
    return mean, cov, len(samples)


# ---- one problem

def register_all(src, index, seed):
    """The three methods on one problem (plus the point estimate, for the time ratio)."""
    common = dict(seed=seed, voxel_size=0.0, downsample_to=0)  # every point, as given
    results, times_ms = {}, {}
    for name in ("none",) + METHODS:
        t0 = time.perf_counter()
        results[name] = sgd_icp.register(src, index, uncertainty=name, **common)
        times_ms[name] = 1e3 * (time.perf_counter() - t0)
    return results, times_ms


def check_library(results, src, theta_hat) -> None:
    """The library used exactly our source points, and every method polished to one optimum."""
    for name in METHODS:
        r = results[name]
        if r.source_points != len(src) or r.voxel_size_m != 0.0:
            raise RuntimeError(f"{name}: the library registered {r.source_points} source points "
                               f"(voxel {r.voxel_size_m} m), not our {len(src)}")
        d = offsets_from(cal.pose_of(r.T_reference_source), theta_hat)[0]
        if np.abs(d).max() > 1e-9:
            print(f"  warning: {name} reports another optimum (offset {d})")


def mcmc_reference(energy: Energy, theta_hat, cov_lap, args, rng) -> dict:
    """One long MH run on `energy` and its diagnostics; the Gaussian fit of its kept samples."""
    t0 = time.perf_counter()
    chains, acceptance, scale = metropolis(energy, theta_hat, cov_lap, args.chains, args.steps,
                                           rng)
    mcmc_ms = 1e3 * (time.perf_counter() - t0)
    kept = chains[:, args.steps // 4:]
    pooled = kept.reshape(-1, 6)
    mean, cov = gaussian_fit(pooled)
    return dict(samples=pooled, mean=mean, cov=cov, mcmc_ms=mcmc_ms,
                acceptance=float(acceptance.mean()), scale=scale, rhat=split_rhat(kept),
                ess=effective_sample_size(kept), kurtosis=kurtosis(pooled, axis=0),
                requeried=energy.requeried / max(energy.evaluated, 1))


def run_problem(name, trial, scene, args, rng):
    src, ref, _ = small_problem(scene, NOISE_M[name], args.points, rng)
    ref_normals = pca_normals(ref)
    index = sgd_icp.ReferenceIndex(ref, normals=ref_normals, cost="point-to-plane")
    results, times_ms = register_all(src, index, seed=trial)
    lap = results["laplace"]
    theta_hat = cal.pose_of(lap.T_reference_source)
    check_library(results, src, theta_hat)
    cov_lap = np.array(lap.covariance)
    energies = {p: Energy(src, ref, ref_normals, lap.final_max_distance_m, lap.residual_sigma_m,
                          lap.correlation_factor, theta_hat, p) for p in ("fixed", "nearest")}

    # Sanity: our residuals at the optimum give the library's sigma (same pairs, normals, d_max).
    e, paired = energies["nearest"].residuals(theta_hat[None], exact=True)
    pairs = int(paired.sum())
    sigma_ratio = float((e[paired] ** 2).sum() / (pairs - 6) / lap.residual_sigma_m**2)
    # Sanity: the cached neighbours give the exact energy (a KD-tree query of every point), and
    # the quadratic form of 'fixed' its sum over the pairs (nats).
    probe = theta_hat + 3 * rng.standard_normal((64, 6)) @ np.linalg.cholesky(cov_lap).T
    energies["nearest"].set_anchors(np.repeat(theta_hat[None], len(probe), axis=0))
    cache_error = float(np.abs(energies["nearest"](probe)
                               - energies["nearest"](probe, exact=True)).max())
    form_error = float(np.abs(energies["fixed"](probe)
                              - energies["fixed"].fixed_direct(probe)).max())
    energies["nearest"].requeried = energies["nearest"].evaluated = 0
    # The library's prior (std 1 scaled unit, 1 rad) against the posterior: its weight.
    prior_var = np.r_[np.full(3, lap.scale_m**2), np.ones(3)]
    prior_weight = float((np.diag(cov_lap) / prior_var).max())
    print(f"{name} #{trial}: {len(src)} src / {len(ref)} ref points, {pairs} pairs (library "
          f"{lap.uncertainty_pairs}), sigma^2 check {sigma_ratio:.6f}, cache error "
          f"{cache_error:.1e}, quadratic form error {form_error:.1e}, kappa "
          f"{lap.correlation_factor:.2f}, prior weight {prior_weight:.1e}; register ms: "
          + ", ".join(f"{m} {t:.0f}" for m, t in times_ms.items()), flush=True)

    fits = {m: method_fit(m, results[m], theta_hat) for m in METHODS}
    # sgld's samples are one chain: its ESS says how many independent draws its fit rests on
    # (svgd's particles are not a chain, laplace has none); the library reports it.
    sample_ess = {m: float("nan") for m in METHODS}
    sample_ess["sgld"] = results["sgld"].effective_samples
    rows, references = [], {}
    for pairing in args.pairings:
        energy = energies[pairing]
        mc = mcmc_reference(energy, theta_hat, cov_lap, args, rng)
        references[pairing] = mc
        print(f"  MCMC {pairing}: {mc['mcmc_ms'] / 1e3:.1f} s, proposal scale {mc['scale']:.2f}, "
              f"acceptance {mc['acceptance']:.2f}, split R-hat max {mc['rhat'].max():.3f}, "
              f"ESS min {mc['ess'].min():.0f}, requeried {mc['requeried']:.1%}, |excess "
              f"kurtosis| max {np.abs(mc['kurtosis']).max():.2f}, mean offset from the estimate "
              f"{mahalanobis(np.zeros(6), mc['mean'], mc['cov']):.2f} sd", flush=True)
        if mc["rhat"].max() >= RHAT_MAX:
            print(f"  warning: split R-hat {mc['rhat'].round(3)} >= {RHAT_MAX}: the chains "
                  "disagree")
        for m in METHODS:
            mean, cov, count = fits[m]
            rows.append(dict(
                dataset=name, trial=trial, reference=pairing, method=m,
                kl_mcmc_method=gaussian_kl(mc["mean"], mc["cov"], mean, cov),
                kl_method_mcmc=gaussian_kl(mean, cov, mc["mean"], mc["cov"]),
                kl_floor=kl_floor(count, rng) if count > 6 else 0.0,
                std_ratio_t=block_std_ratio(cov, mc["cov"], slice(0, 3)),
                std_ratio_r=block_std_ratio(cov, mc["cov"], slice(3, 6)),
                mean_offset_sd=mahalanobis(mean, mc["mean"], mc["cov"]),
                time_ms=times_ms[m], point_estimate_ms=times_ms["none"],
                modes=len(results[m].modes), sample_ess_min=sample_ess[m],
                mcmc_ms=mc["mcmc_ms"], proposal_scale=mc["scale"],
                acceptance=mc["acceptance"], rhat_max=float(mc["rhat"].max()),
                ess_min=float(mc["ess"].min()),
                kurtosis_max=float(np.abs(mc["kurtosis"]).max()),
                mcmc_offset_sd=mahalanobis(np.zeros(6), mc["mean"], mc["cov"]),
                sigma_ratio=sigma_ratio, kappa=lap.correlation_factor, pairs=pairs,
                source_points=len(src), sd_mcmc=np.sqrt(np.diag(mc["cov"])).tolist()))
    figure_data = dict(references=references, fits=fits,
                       sgld=offsets_from(np.array(results["sgld"].samples), theta_hat),
                       svgd=offsets_from(np.array(results["svgd"].samples), theta_hat))
    return rows, figure_data


# ---- output

def tables(rows, datasets, args) -> str:
    med = lambda sel, key: float(np.median([r[key] for r in sel]))  # noqa: E731
    lines = [
        f"{args.trials} problems per dataset, halves of at most {args.points} points, "
        f"{args.chains} chains x {args.steps} steps (first quarter discarded); medians over the "
        "problems. reference: the MCMC's energy, 'nearest' (re-paired at every pose, pairs "
        "beyond d_max dropped: the likelihood as written) or 'fixed' (the estimate's pairs held); "
        f"converged: the problems whose chains reached split R-hat < {RHAT_MAX} on every axis, "
        "over which alone the row's medians are taken. "
        "KL: of the Gaussian fits, nats; KL floor: KL(MCMC || fit) of a fit to as many exact "
        "draws as the method has samples; std ratio: method / MCMC; mean offset: in MCMC "
        "standard deviations (Mahalanobis); sample ESS: of sgld's 200 samples, the worst axis; "
        "time: wall time of register() with the method.",
        "",
        "| dataset | reference (converged) | method | KL(MCMC ‖ method) | KL(method ‖ MCMC) "
        "| KL floor | std ratio translation | std ratio rotation | mean offset (sd) | sample ESS "
        "min | time (ms) | time / point estimate |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for d in datasets:
        for p in args.pairings:
            for m in METHODS:
                every = [r for r in rows
                         if (r["dataset"], r["reference"], r["method"]) == (d, p, m)]
                sel = [r for r in every if r["rhat_max"] < RHAT_MAX]
                head = f"| {d} | {p} ({len(sel)}/{len(every)}) | {m} |"
                if not sel:
                    lines.append(head + " not converged |" + " |" * 9)
                    continue
                lines.append(
                    f"{head} {med(sel, 'kl_mcmc_method'):.3g} | {med(sel, 'kl_method_mcmc'):.3g} | "
                    f"{med(sel, 'kl_floor'):.2g} | {med(sel, 'std_ratio_t'):.2f} | "
                    f"{med(sel, 'std_ratio_r'):.2f} | {med(sel, 'mean_offset_sd'):.2f} | "
                    f"{med(sel, 'sample_ess_min'):.0f} | {med(sel, 'time_ms'):.1f} | "
                    f"{np.median([r['time_ms'] / r['point_estimate_ms'] for r in sel]):.1f}x |")
    lines += [
        "",
        "The MCMC references (medians over the problems; R-hat and ESS: the worst axis of the "
        "worst problem; kurtosis: the largest |excess kurtosis| over the axes, 0 for a Gaussian; "
        "offset: the MCMC mean from the estimate in MCMC sd; sigma check: our sum of squared "
        "residuals / (pairs - 6) over the library's sigma^2; scale: the proposal's, after the "
        "burn-in's adaptation, 1 = 2.38^2/6 Sigma_laplace):",
        "",
        "| dataset | reference | source points | pairs | kappa | sigma check | proposal scale | "
        "acceptance | split R-hat max | ESS min | excess kurtosis max | MCMC offset (sd) | MCMC "
        "time (s) |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for d in datasets:
        for p in args.pairings:
            sel = [r for r in rows
                   if (r["dataset"], r["reference"], r["method"]) == (d, p, "laplace")]
            lines.append(
                f"| {d} | {p} | {med(sel, 'source_points'):.0f} | {med(sel, 'pairs'):.0f} | "
                f"{med(sel, 'kappa'):.2f} | {med(sel, 'sigma_ratio'):.4f} | "
                f"{med(sel, 'proposal_scale'):.2f} | {med(sel, 'acceptance'):.2f} | "
                f"{max(r['rhat_max'] for r in sel):.3f} | {min(r['ess_min'] for r in sel):.0f} | "
                f"{med(sel, 'kurtosis_max'):.2f} | {med(sel, 'mcmc_offset_sd'):.2f} | "
                f"{med(sel, 'mcmc_ms') / 1e3:.1f} |")
    return "\n".join(lines) + "\n"


def write_csv(rows, path: Path) -> None:
    keys = [k for k in rows[0] if k != "sd_mcmc"]
    with open(path, "w") as f:
        f.write(",".join(keys) + ",sd_x_m,sd_y_m,sd_z_m,sd_roll_rad,sd_pitch_rad,sd_yaw_rad\n")
        for r in rows:
            f.write(",".join(str(r[k]) for k in keys) + "," + ",".join(map(str, r["sd_mcmc"]))
                    + "\n")


def plot(figure_data: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = [((0, 1), 1e3, "x (mm)", "y (mm)", "translation x-y"),
              ((3, 5), np.rad2deg(1.0), "roll (deg)", "yaw (deg)", "rotation roll-yaw")]
    colours = dict(laplace="tab:blue", sgld="tab:orange", svgd="tab:green")
    reference_style = dict(fixed=("black", "-"), nearest=("tab:red", ":"))
    fig, axes = plt.subplots(len(figure_data), 2, figsize=(12, 4.6 * len(figure_data)),
                             squeeze=False)
    for row, (name, data) in enumerate(figure_data.items()):
        for col, (axis_pair, unit, xlabel, ylabel, title) in enumerate(panels):
            ax = axes[row, col]
            ix = list(axis_pair)
            # The first reference's samples as a 2-D histogram (the likelihood as written).
            first = next(iter(data["references"]))
            ax.hist2d(*(data["references"][first]["samples"][:, ix] * unit).T, bins=70,
                      cmap="Greys", cmin=1, alpha=0.7)
            ax.scatter(*(data["sgld"][:, ix] * unit).T, s=6, color=colours["sgld"], alpha=0.5,
                       label="sgld samples")
            ax.scatter(*(data["svgd"][:, ix] * unit).T, s=30, marker="^", color=colours["svgd"],
                       edgecolor="k", linewidth=0.4, label="svgd particles")
            for pairing, mc in data["references"].items():
                colour, style = reference_style[pairing]
                xy = calfig.ellipse_xy(mc["mean"][ix] * unit, mc["cov"][np.ix_(ix, ix)] * unit**2,
                                       2.0)
                note = "" if mc["rhat"].max() < RHAT_MAX else ", not converged"
                ax.plot(*xy.T, color=colour, ls=style, lw=2.2,
                        label=f"MCMC ({pairing} pairs{note}) 2-sigma")
            for m in METHODS:
                mean, cov, _ = data["fits"][m]
                xy = calfig.ellipse_xy(mean[ix] * unit, cov[np.ix_(ix, ix)] * unit**2, 2.0)
                ax.plot(*xy.T, color=colours[m], ls="--", lw=1.6, label=f"{m} 2-sigma")
            ax.plot(0, 0, "+", color="red", ms=12, mew=2, label="estimate")
            ax.set(xlabel=xlabel, ylabel=ylabel, title=f"{name}: {title}")
            ax.grid(alpha=0.3)
            if col == 0:
                ax.legend(fontsize=7, loc="best", framealpha=0.85)
    fig.suptitle(f"MCMC references against laplace, sgld, svgd, centred on the estimate (grey: "
                 f"MCMC samples, {first} pairs); ellipses: Mahalanobis radius 2 of the 2-D "
                 "marginals", fontsize=11)
    fig.tight_layout(rect=(0, 0, 1, 0.985))
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=75)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--datasets", default="synthetic,bunny,kinect,kitti")
    ap.add_argument("--trials", type=int, default=3)
    ap.add_argument("--points", type=int, default=3000, help="points per half (source, reference)")
    ap.add_argument("--chains", type=int, default=4)
    ap.add_argument("--steps", type=int, default=20000, help="Metropolis-Hastings steps per chain")
    ap.add_argument("--pairings", default="fixed,nearest",
                    help="the MCMC references' energies: 'fixed' (the estimate's pairs held), "
                    "'nearest' (re-paired at every pose: the likelihood as written; rough, its "
                    "chains do not converge on every scene)")
    ap.add_argument("--seed", type=int, default=2026)
    ap.add_argument("--out", type=Path, default=Path("results/uncertainty"))
    ap.add_argument("--figure", type=Path, default=Path(__file__).resolve().parents[1]
                    / "docs" / "figures" / "uncertainty_mcmc.png")
    args = ap.parse_args()
    args.pairings = args.pairings.split(",")
    datasets = args.datasets.split(",")
    rows, figure_data = [], {}
    t0 = time.perf_counter()
    for k, name in enumerate(datasets):
        rng = np.random.default_rng([args.seed, k])
        scene = cal.load_scene(SCENES.get(name, name), rng)
        for trial in range(args.trials):
            problem_rows, data = run_problem(name, trial, scene, args, rng)
            rows += problem_rows
            figure_data.setdefault(name, data)  # the first problem of each dataset
    text = tables(rows, datasets, args)
    print(text)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "mcmc.md").write_text(text)
    write_csv(rows, args.out / "mcmc.csv")
    plot(figure_data, args.figure)
    print(f"wrote {args.out / 'mcmc.md'}, {args.out / 'mcmc.csv'}, {args.figure}; "
          f"{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
