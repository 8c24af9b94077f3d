"""Pose uncertainty from Python (docs/uncertainty.md): the fields, their shapes, reproducibility,
agreement with the analytic covariance of a problem with known noise, and the errors."""

import numpy as np
import pytest

import sgd_icp

NOISE_M = 0.001


def rpy(roll, pitch, yaw):
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


@pytest.fixture(scope="module")
def problem():
    """Points 7 cm apart with 1 mm noise on the source: nearest neighbours are true partners."""
    rng = np.random.default_rng(5)
    ref = rng.random((3000, 3)) * np.array([1.0, 1.5, 0.7])
    theta = np.array([0.05, -0.04, 0.02, 0.05, -0.03, 0.1])
    R = rpy(*theta[3:])
    src = (ref - theta[:3]) @ R + rng.normal(0, NOISE_M, ref.shape)
    return src.astype(np.float32), ref.astype(np.float32), theta


@pytest.fixture(scope="module")
def surface():
    """Points on the faces of a 1 x 1.5 x 0.7 m box, 2 cm apart, with their exact normals."""
    rng = np.random.default_rng(6)
    size = np.array([1.0, 1.5, 0.7])
    areas = np.array([size[1] * size[2], size[0] * size[2], size[0] * size[1]])
    axis = rng.choice(3, 20000, p=areas / areas.sum())
    p = rng.random((20000, 3))
    p[np.arange(20000), axis] = rng.random(20000) < 0.5
    normals = np.eye(3)[axis]
    ref = p * size
    theta = np.array([0.05, -0.04, 0.02, 0.05, -0.03, 0.1])
    src = (ref - theta[:3]) @ rpy(*theta[3:]) + rng.normal(0, NOISE_M, ref.shape)
    return src.astype(np.float32), ref.astype(np.float32), theta, normals


def jacobians(src, theta):
    def moved(th):
        return src.astype(np.float64) @ rpy(*th[3:]).T + th[:3]

    jac = np.zeros((len(src), 3, 6))
    for k in range(6):
        d = np.zeros(6)
        d[k] = 1e-6
        jac[:, :, k] = (moved(theta + d) - moved(theta - d)) / 2e-6
    return jac


def surface_covariance(src, theta, normals):
    """NOISE_M^2 (sum J^T n n^T J)^-1: the distance to the surface (docs/uncertainty.md)."""
    nj = np.einsum("ni,nik->nk", normals, jacobians(src, theta))
    return NOISE_M**2 * np.linalg.inv(nj.T @ nj)


def analytic_covariance(src, theta):
    """NOISE_M^2 (sum J^T J)^-1 with J = d(R s + t)/d theta by central differences."""
    def moved(th):
        return src.astype(np.float64) @ rpy(*th[3:]).T + th[:3]

    jac = np.zeros((len(src), 3, 6))
    for k in range(6):
        d = np.zeros(6)
        d[k] = 1e-6
        jac[:, :, k] = (moved(theta + d) - moved(theta - d)) / 2e-6
    jtj = np.einsum("nik,nil->kl", jac, jac)
    return NOISE_M**2 * np.linalg.inv(jtj)


def test_laplace_matches_the_analytic_covariance(surface):
    src, ref, theta, normals = surface
    # Every point, so that the estimate describes the residuals the analytic formula sums.
    r = sgd_icp.register(src, ref, method="sgd-point", uncertainty="laplace", temper=False,
                         downsample_to=0)
    assert r.converged
    assert r.covariance.shape == (6, 6) and r.covariance_se3.shape == (6, 6)
    expected = surface_covariance(src, theta, normals)
    np.testing.assert_allclose(np.diag(r.covariance) / np.diag(expected), 1.0, atol=0.15)
    assert np.allclose(r.covariance, r.covariance.T)
    assert np.all(np.linalg.eigvalsh(r.covariance_se3) > 0)
    assert r.samples.shape == (0, 6)
    assert r.residual_sigma_m == pytest.approx(NOISE_M, rel=0.05)


def test_sgld_samples_are_reproducible_and_near_laplace(problem):
    src, ref, theta = problem
    # The point-to-point model of analytic_covariance, on every point.
    kw = dict(method="sgd-point", downsample_to=0, uncertainty_samples=400, temper=False)
    a = sgd_icp.register(src, ref, uncertainty="sgld", **kw)
    b = sgd_icp.register(src, ref, uncertainty="sgld", **kw)
    assert a.samples.shape == (400, 6) and a.sample_mean.shape == (6,)
    assert np.array_equal(a.samples, b.samples)
    np.testing.assert_allclose(a.sample_mean, a.samples.mean(axis=0), atol=1e-9)
    ratio = np.sqrt(np.diag(a.covariance) / np.diag(analytic_covariance(src, theta)))
    assert np.all((ratio > 0.7) & (ratio < 1.4)), ratio
    c = sgd_icp.register(src, ref, uncertainty="sgld", seed=7, **kw)
    assert not np.array_equal(a.samples, c.samples)
    # What the 400 samples are worth: the library's effective sample size against one computed
    # here (numpy, Geyer's initial monotone sequence, the slowest coordinate).
    assert a.effective_samples == pytest.approx(effective_sample_size(a.samples), rel=1e-6)
    assert 0 < a.effective_samples < 400


def effective_sample_size(chain):
    n = len(chain)
    ess = []
    for x in chain.T:
        d = x - x.mean()
        acov = np.correlate(d, d, mode="full")[n - 1:] / n
        tau, previous = -1.0, np.inf
        for m in range(n // 2):
            pair = (acov[2 * m] + acov[2 * m + 1]) / acov[0]
            if pair <= 0:
                break
            previous = min(previous, pair)
            tau += 2 * previous
        ess.append(n / tau)
    return min(ess)


def test_settings_object_carries_the_uncertainty(problem):
    src, ref, _ = problem
    s = sgd_icp.Settings(uncertainty="laplace")
    assert s.uncertainty.method == sgd_icp.UncertaintyType.laplace
    s.uncertainty.temper = False
    r = sgd_icp.register(src, ref, settings=s)
    assert np.all(np.diag(r.covariance) > 0)
    assert "uncertainty=UncertaintySettings(method=UncertaintyType.laplace" in repr(s)


def test_no_uncertainty_by_default(problem):
    src, ref, _ = problem
    r = sgd_icp.register(src, ref)
    assert not r.covariance.any() and r.samples.shape == (0, 6)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(uncertainty="svgd2"), "unknown uncertainty method 'svgd2'"),
        (dict(uncertainty_samples=0), "uncertainty_samples="),
        (dict(thinning=0), "thinning="),
    ],
)
def test_bad_values_are_rejected(problem, kwargs, message):
    src, ref, _ = problem
    with pytest.raises(sgd_icp.InvalidSettingsError, match=message):
        sgd_icp.register(src, ref, **kwargs)


# ---- svgd (Stein ICP)


def spd(m):
    return np.allclose(m, m.T) and np.all(np.linalg.eigvalsh(m) > 0)


def test_svgd_reports_particles_modes_and_a_positive_definite_covariance(surface):
    src, ref, _, normals = surface
    index = sgd_icp.ReferenceIndex(ref, normals=normals)
    r = sgd_icp.register(src, index, method="sgd-plane", uncertainty="svgd", particles=16)
    assert r.converged
    assert r.samples.shape == (16, 6) and r.sample_mean.shape == (6,)
    assert len(r.modes) >= 1
    for mode in r.modes:
        assert isinstance(mode, sgd_icp.PoseMode)
        assert mode.mean.shape == (6,) and mode.mean.dtype == np.float64
        assert mode.covariance.shape == (6, 6) and mode.covariance.dtype == np.float64
    assert sum(m.weight for m in r.modes) == pytest.approx(1.0)
    assert np.array_equal(r.covariance, r.modes[0].covariance)
    assert spd(r.covariance) and spd(r.covariance_se3)


def test_svgd_particles_are_reproducible(problem):
    src, ref, _ = problem
    kw = dict(method="sgd-point", uncertainty="svgd", particles=8, svgd_iterations=50)
    a = sgd_icp.register(src, ref, **kw)
    b = sgd_icp.register(src, ref, **kw)
    assert np.array_equal(a.samples, b.samples)
    c = sgd_icp.register(src, ref, seed=7, **kw)
    assert not np.array_equal(a.samples, c.samples)


def test_svgd_with_one_particle_descends_to_the_estimate(surface):
    """One particle: no kernel term, Adam descent on the energy; it ends at the optimum (within
    a fraction of the posterior's standard deviation)."""
    src, ref, _, normals = surface
    index = sgd_icp.ReferenceIndex(ref, normals=normals)
    kw = dict(method="sgd-plane", temper=False)
    laplace = sgd_icp.register(src, index, uncertainty="laplace", **kw)
    r = sgd_icp.register(src, index, uncertainty="svgd", particles=1, **kw)
    assert r.samples.shape == (1, 6) and len(r.modes) == 1 and r.modes[0].weight == 1.0
    np.testing.assert_allclose(r.modes[0].mean, r.samples[0], atol=1e-12)
    # Started 3 standard deviations out, it ends within half of one of the estimate.
    offset = r.samples[0] - pose_of(r.T_reference_source)
    std = np.sqrt(np.diag(laplace.covariance))
    assert np.all(np.abs(offset) < 0.5 * std), offset / std


def pose_of(T):
    r = T[:3, :3]
    return np.r_[T[:3, 3], np.arctan2(r[2, 1], r[2, 2]),
                 np.arctan2(-r[2, 0], np.hypot(r[0, 0], r[1, 0])), np.arctan2(r[1, 0], r[0, 0])]


def box_surface(n, rng):
    size = np.array([1.0, 1.5, 0.7])
    areas = np.array([size[1] * size[2], size[0] * size[2], size[0] * size[1]])
    axis = rng.choice(3, n, p=areas / areas.sum())
    p = rng.random((n, 3))
    p[np.arange(n), axis] = rng.random(n) < 0.5
    return p * size - size / 2, np.eye(3)[axis]


def test_svgd_finds_the_modes_of_a_symmetric_box_where_laplace_has_one_gaussian():
    """A box centred on its axes is symmetric under half-turns about each: particles spread over
    about 1.5 rad reach them (docs/uncertainty.md)."""
    rng = np.random.default_rng(8)
    ref, normals = box_surface(500, rng)
    theta = np.array([0.0, 0.0, 0.05, 0.02, -0.01, 0.01])
    src = (ref - theta[:3]) @ rpy(*theta[3:]) + rng.normal(0, 5 * NOISE_M, ref.shape)
    index = sgd_icp.ReferenceIndex(ref.astype(np.float32), normals=normals)
    kw = dict(method="sgd-plane", refine_stages=0, max_distance=1.0, svgd_iterations=1000,
              particles=64)
    laplace = sgd_icp.register(src.astype(np.float32), index, uncertainty="laplace", **kw)
    assert laplace.modes == []
    # svgd_spread counts the tempered fixed-pair Laplace's standard deviations (kappa times the
    # untempered covariance), not the sandwich's: 1.5 rad of yaw in that unit.
    naive = sgd_icp.register(src.astype(np.float32), index, uncertainty="laplace", temper=False,
                             **kw)
    yaw_std = np.sqrt(naive.covariance[5, 5] * laplace.correlation_factor)
    r = sgd_icp.register(src.astype(np.float32), index, uncertainty="svgd",
                         svgd_spread=1.5 / yaw_std, **kw)
    assert len(r.modes) >= 2

    def weight_near(pose):
        w = 0.0
        for m in r.modes:
            d = m.mean - pose
            d[3:] = (d[3:] + np.pi) % (2 * np.pi) - np.pi
            if np.linalg.norm(d[:3]) < 0.01 and np.linalg.norm(d[3:]) < 0.03:
                w += m.weight
        return w

    T = np.eye(4)
    T[:3, :3], T[:3, 3] = rpy(*theta[3:]), theta[:3]
    half_turns = []
    for axis in range(3):
        H = np.eye(4)
        H[:3, :3] = rpy(*np.pi * np.eye(3)[axis])
        half_turns.append(pose_of(H @ T))
    modes = [(m.weight, np.round(m.mean, 3)) for m in r.modes]
    assert weight_near(theta) > 0.05, modes
    assert sum(weight_near(p) for p in half_turns) > 0.1, modes


def test_svgd_plane_has_large_variance_along_its_free_directions():
    rng = np.random.default_rng(9)
    ref = np.c_[rng.uniform(-1, 1, 5000), rng.uniform(-3, 3, 5000), np.zeros(5000)]
    src = ref - np.array([0.01, 0.01, 0.0]) + rng.normal(0, NOISE_M, ref.shape)
    r = sgd_icp.register(src.astype(np.float32), ref.astype(np.float32), method="sgd-plane",
                         uncertainty="svgd")
    assert len(r.modes) == 1
    c = r.covariance
    assert min(c[0, 0], c[1, 1]) / c[2, 2] > 1e4  # x and y free, z held
    assert c[5, 5] / max(c[3, 3], c[4, 4]) > 1e4  # yaw free, roll and pitch held


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(particles=0), "particles="),
        (dict(svgd_iterations=0), "svgd_iterations="),
    ],
)
def test_bad_svgd_values_are_rejected(problem, kwargs, message):
    src, ref, _ = problem
    with pytest.raises(sgd_icp.InvalidSettingsError, match=message):
        sgd_icp.register(src, ref, uncertainty="svgd", **kwargs)
