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
        (dict(sgld_step=float("nan")), "sgld_step="),
        (dict(sgld_step=-1.0), "sgld_step="),
    ],
)
def test_bad_values_are_rejected(problem, kwargs, message):
    src, ref, _ = problem
    with pytest.raises(sgd_icp.InvalidSettingsError, match=message):
        sgd_icp.register(src, ref, **kwargs)
