"""register(method=...): the CLI's methods (SGD-ICP on the three costs, batch ICP, point-to-plane
ICP and GICP), BatchSettings, and the preprocessing functions."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import sgd_icp
from conftest import make_transform, synthetic_scene, transformed

DEG = np.pi / 180
METHODS = ["sgd", "sgd-plane", "sgd-gicp", "icp", "icp-plane", "gicp"]


@pytest.fixture(scope="module")
def small_scene():
    """(source, reference, T_gt): two samplings of the synthetic scene (~7 cm apart), the reference
    moved by a transform within the batch methods' basin (3, -2, 6 degrees; 0.12 m)."""
    T_gt = make_transform(3 * DEG, -2 * DEG, 6 * DEG, (0.1, -0.06, 0.03))
    return synthetic_scene(1, 20000), transformed(synthetic_scene(2, 20000), T_gt), T_gt


# ---- every method recovers a known transform


@pytest.mark.parametrize("method", METHODS)
def test_every_method_recovers_the_transform(small_scene, method):
    source, reference, T_gt = small_scene
    options = {} if method.startswith("sgd") else {"max_distance": 0.1}
    r = sgd_icp.register(source, reference, method=method, **options)
    assert r.converged, r.message
    assert sgd_icp.translation_error(r.T_reference_source, T_gt) < 0.01
    assert sgd_icp.rotation_error_geodesic(r.T_reference_source, T_gt) < 0.3 * DEG
    assert r.inlier_ratio > 0.9


@pytest.mark.parametrize("method", ["icp", "icp-plane", "gicp"])
def test_batch_methods_with_an_index_and_settings(small_scene, method):
    source, reference, T_gt = small_scene
    cost = {"icp": "point-to-point", "icp-plane": "point-to-plane", "gicp": "plane-to-plane"}
    index = sgd_icp.ReferenceIndex(reference, cost=cost[method])
    settings = sgd_icp.BatchSettings(max_distance=0.1)
    with_index = sgd_icp.register(source, index, settings=settings, method=method)
    with_array = sgd_icp.register(source, reference, method=method, max_distance=0.1)
    assert np.array_equal(with_index.T_reference_source, with_array.T_reference_source)
    assert with_index.iterations == with_array.iterations
    assert with_index.build_ms == 0.0 and with_array.build_ms > 0.0
    assert with_index.iterations <= 100


def test_method_sets_the_cost_of_the_settings(small_scene):
    source, reference, _ = small_scene
    # The method's cost replaces the one of the settings: gicp with point-to-point settings is gicp.
    a = sgd_icp.register(source, reference, method="gicp", settings=sgd_icp.BatchSettings())
    b = sgd_icp.register(source, reference, method="gicp", settings=sgd_icp.BatchSettings.gicp())
    assert np.array_equal(a.T_reference_source, b.T_reference_source)
    c = sgd_icp.register(source, reference, method="sgd-plane")
    d = sgd_icp.register(source, reference, cost="point-to-plane")
    assert np.array_equal(c.T_reference_source, d.T_reference_source)


def test_batch_overrides_apply(small_scene):
    source, reference, _ = small_scene
    r = sgd_icp.register(source, reference, method="icp", max_iterations=3)
    assert r.iterations == 3 and r.stop_reason == "max_iterations" and not r.converged
    r = sgd_icp.register(
        source, reference, method="icp-plane", max_distance=0.5, max_distance_unit="m",
        evaluation_points=500,
    )
    assert r.final_max_distance_m == pytest.approx(0.5)
    assert r.evaluated_points <= 500


# ---- method errors


@pytest.mark.parametrize("name", ["", "ICP", "gicp2", "sgd_gauss"])
def test_unknown_method_raises_value_error(small_scene, name):
    source, reference, _ = small_scene
    with pytest.raises(ValueError, match="unknown method") as info:
        sgd_icp.register(source[:500], reference[:500], method=name)
    assert isinstance(info.value, sgd_icp.InvalidSettingsError)


def test_method_errors(small_scene):
    source, reference, _ = small_scene
    source, reference = source[:2000], reference[:2000]
    with pytest.raises(TypeError, match="method must be a str"):
        sgd_icp.register(source, reference, method=1)
    with pytest.raises(ValueError, match="method='gicp' sets the cost"):
        sgd_icp.register(source, reference, method="gicp", cost="point-to-point")
    with pytest.raises(ValueError, match="method='sgd-plane' sets the cost"):
        sgd_icp.register(source, reference, method="sgd-plane", cost="point-to-plane")
    with pytest.raises(TypeError, match="'batch_size' applies to the SGD methods only.*'icp'"):
        sgd_icp.register(source, reference, method="icp", batch_size=100)
    with pytest.raises(TypeError, match="'optimizer' applies to the SGD methods only"):
        sgd_icp.register(source, reference, method="gicp", optimizer="adam")
    with pytest.raises(TypeError, match="unknown setting 'bogus'"):
        sgd_icp.register(source, reference, method="icp", bogus=1)
    with pytest.raises(TypeError, match="settings must be a sgd_icp.BatchSettings or None"):
        sgd_icp.register(source, reference, method="icp", settings=sgd_icp.Settings())
    with pytest.raises(TypeError, match="a BatchSettings is for method="):
        sgd_icp.register(source, reference, settings=sgd_icp.BatchSettings())
    with pytest.raises(ValueError, match=r"trim=2: must be in \[0.01, 1\]"):
        sgd_icp.register(source, reference, method="icp", trim=2.0)
    with pytest.raises(ValueError, match="max_distance_unit applies to max_distance and"):
        sgd_icp.register(source, reference, method="icp", max_distance_unit="m")


@pytest.mark.parametrize(
    "method, message",
    [
        ("icp-plane", "point-to-plane cost needs reference normals"),
        ("gicp", "plane-to-plane cost needs reference covariances"),
    ],
)
def test_batch_plane_methods_need_a_prepared_index(small_scene, method, message):
    source, reference, _ = small_scene
    index = sgd_icp.ReferenceIndex(reference[:2000])
    with pytest.raises(sgd_icp.InvalidInputError, match=message):
        sgd_icp.register(source[:2000], index, method=method)
    assert not index.has_normals  # a registration never changes a shared index


@pytest.mark.parametrize("method", ["sgd-plane", "sgd-gicp"])
def test_sgd_plane_methods_estimate_what_they_use(small_scene, method):
    # The SGD methods estimate the normals / covariances their mini-batches reach, during the
    # run: a bare index gives the result of the arrays, and stays as it was.
    source, reference, _ = small_scene
    index = sgd_icp.ReferenceIndex(reference[:2000])
    with_index = sgd_icp.register(source[:2000], index, method=method)
    with_array = sgd_icp.register(source[:2000], reference[:2000], method=method)
    np.testing.assert_array_equal(with_index.T_reference_source, with_array.T_reference_source)
    assert not index.has_normals and not index.has_covariances


# ---- BatchSettings

BATCH_DEFAULTS = {
    "cost": sgd_icp.CostType.point_to_point,
    "max_correspondence_distance": sgd_icp.Distance.scaled(0.05),
    "kernel": sgd_icp.KernelType.none,
    "kernel_scale": sgd_icp.Distance.scaled(0.01),
    "trim_ratio": 1.0,
    "max_iterations": 100,
    "translation_tolerance": 1e-5,
    "rotation_tolerance": 1e-5,
    "initial_damping": 1e-6,
    "evaluation_points": 2000,
    "record_trace": False,
}


@pytest.mark.parametrize("method", ["icp", "gicp"])
def test_batch_methods_record_a_trace(small_scene, method):
    source, reference, _ = small_scene
    r = sgd_icp.register(source, reference, method=method, record_trace=True)
    assert len(r.trace) == r.iterations > 0
    np.testing.assert_array_equal(r.trace.points_processed, len(source) * np.arange(1, r.iterations + 1))
    np.testing.assert_allclose(r.trace.T_reference_source[-1], r.T_reference_source, atol=1e-12)
    assert np.all(r.trace.step_size == 1.0) and r.trace.cost[-1] < r.trace.cost[0]
    assert len(sgd_icp.register(source, reference, method=method).trace) == 0
    assert sgd_icp.BatchSettings(record_trace=True).record_trace is True


def test_batch_settings_defaults_are_the_cpp_ones():
    s = sgd_icp.BatchSettings()
    for name, expected in BATCH_DEFAULTS.items():
        assert getattr(s, name) == expected, name
    assert s.neighborhood == sgd_icp.NeighborhoodSettings()
    assert sgd_icp.BatchSettings.icp() == s
    assert sgd_icp.BatchSettings.icp_plane().cost == sgd_icp.CostType.point_to_plane
    assert sgd_icp.BatchSettings.gicp().cost == sgd_icp.CostType.plane_to_plane
    assert sgd_icp.BatchSettings.gicp(trim=0.5).trim_ratio == 0.5


def test_batch_keyword_overrides_set_the_documented_fields():
    s = sgd_icp.BatchSettings(
        max_distance=2.0, max_distance_unit="m", max_iterations=7, kernel="huber",
        kernel_scale=0.1, trim=0.8, neighbors=12, damping=0.0, translation_tolerance=1e-4,
        rotation_tolerance=2e-4, evaluation_points=0, cost="plane-to-plane",
    )
    assert s.max_correspondence_distance == sgd_icp.Distance.metres(2.0)
    assert s.kernel_scale == sgd_icp.Distance.metres(0.1)
    assert s.max_iterations == 7 and s.kernel == sgd_icp.KernelType.huber
    assert s.trim_ratio == 0.8 and s.neighborhood.k == 12 and s.initial_damping == 0.0
    assert s.translation_tolerance == 1e-4 and s.rotation_tolerance == 2e-4
    assert s.evaluation_points == 0
    assert s.cost == sgd_icp.CostType.plane_to_plane
    assert s.replace(max_iterations=3).max_iterations == 3 and s.max_iterations == 7


def test_batch_settings_are_values():
    s = sgd_icp.BatchSettings.gicp(max_iterations=30)
    assert copy.copy(s) == s and copy.deepcopy(s) == s and copy.copy(s) is not s
    assert s != sgd_icp.BatchSettings.gicp()
    assert repr(s).startswith("BatchSettings(cost=CostType.plane_to_plane, ")
    assert "max_iterations=30" in repr(s)
    s.max_iterations = 0
    with pytest.raises(ValueError, match=r"max_iterations = 0: must be in \[1, 1000000000\]"):
        s.validate()
    with pytest.raises(TypeError):
        s.max_correspondence_distance = 1.0  # a distance needs its unit
    with pytest.raises(ValueError):
        s.max_iterations = -1
    s.cost = "point-to-plane"
    assert s.cost == sgd_icp.CostType.point_to_plane


# ---- preprocessing


def test_voxel_downsample_keeps_one_centroid_per_voxel():
    rng = np.random.default_rng(3)
    points = rng.uniform(-2.0, 3.0, size=(5000, 3))
    size = 0.5
    out = sgd_icp.voxel_downsample(points, size)
    keys = np.floor(points.astype(np.float32).astype(np.float64) / size).astype(np.int64)
    unique, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    assert out.dtype == np.float32 and out.shape == (len(unique), 3)
    # Each output point lies in its own occupied voxel, in the order of the voxels' first points.
    out_keys = np.floor(out.astype(np.float64) / size).astype(np.int64)
    np.testing.assert_array_equal(out_keys, unique[np.argsort(first)])
    # ... and is the centroid of the points in that voxel.
    order = np.argsort(first)
    for row, voxel in enumerate(order[:50]):
        np.testing.assert_allclose(
            out[row], points[inverse == voxel].astype(np.float32).mean(axis=0), atol=1e-5
        )


def test_voxel_downsample_edge_cases():
    assert sgd_icp.voxel_downsample(np.zeros((0, 3)), 0.1).shape == (0, 3)
    same = np.ones((10, 3), dtype=np.float32)
    np.testing.assert_array_equal(sgd_icp.voxel_downsample(same, 0.1), same[:1])
    with_nan = np.vstack([same, [[np.nan, 0, 0]]])
    assert sgd_icp.voxel_downsample(with_nan, 0.1).shape == (1, 3)  # non-finite rows dropped
    for bad in (0.0, -1.0, np.inf, np.nan):
        with pytest.raises(ValueError):
            sgd_icp.voxel_downsample(same, bad)
    with pytest.raises(ValueError, match=r"got shape \(10, 2\)"):
        sgd_icp.voxel_downsample(np.zeros((10, 2)), 0.1)
    with pytest.raises(TypeError):
        sgd_icp.voxel_downsample(same, "0.1")


def test_random_downsample_picks_distinct_input_rows():
    points = synthetic_scene(4, 3000)
    out = sgd_icp.random_downsample(points, 500, seed=1)
    assert out.shape == (500, 3) and out.dtype == np.float32
    rows = {tuple(p) for p in points}
    assert all(tuple(p) in rows for p in out)
    assert len({tuple(p) for p in out}) == 500
    # In input order, reproducible, seed-dependent.
    index = {tuple(p): i for i, p in enumerate(points)}
    assert np.all(np.diff([index[tuple(p)] for p in out]) > 0)
    np.testing.assert_array_equal(out, sgd_icp.random_downsample(points, 500, seed=1))
    assert not np.array_equal(out, sgd_icp.random_downsample(points, 500, seed=2))
    np.testing.assert_array_equal(sgd_icp.random_downsample(points, 500),
                                  sgd_icp.random_downsample(points, 500, seed=2019))
    np.testing.assert_array_equal(sgd_icp.random_downsample(points, 10**6), points)
    assert sgd_icp.random_downsample(points, 0).shape == (0, 3)
    with pytest.raises(ValueError, match="count must be >= 0"):
        sgd_icp.random_downsample(points, -1)
    with pytest.raises(TypeError, match="count must be an integer"):
        sgd_icp.random_downsample(points, 0.5)


def test_normals_of_a_plane():
    rng = np.random.default_rng(7)
    uv = rng.uniform(-1.0, 1.0, size=(2000, 2))
    normal = np.array([1.0, -2.0, 2.0]) / 3.0
    e1 = np.array([2.0, 1.0, 0.0]) / np.sqrt(5.0)
    e2 = np.cross(normal, e1)
    points = np.array([0.2, 0.1, -3.0]) + uv[:, :1] * e1 + uv[:, 1:] * e2
    normals = sgd_icp.estimate_normals(points)
    assert normals.shape == (2000, 3) and normals.dtype == np.float32
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-5)
    # Facing the viewpoint (the origin by default: on the +normal side of this plane).
    np.testing.assert_allclose(normals @ normal, 1.0, atol=1e-4)
    far = 10.0 * -normal + np.array([0.2, 0.1, -3.0])
    flipped = sgd_icp.estimate_normals(points, k=10, num_threads=1, viewpoint=far)
    np.testing.assert_allclose(flipped @ normal, -1.0, atol=1e-4)
    # Collinear points have no normal.
    line = np.c_[np.linspace(0, 1, 50), np.zeros(50), np.zeros(50)]
    np.testing.assert_array_equal(sgd_icp.estimate_normals(line), np.zeros((50, 3)))


def test_covariances_of_a_plane():
    rng = np.random.default_rng(8)
    points = np.c_[rng.uniform(0, 1, size=(1000, 2)), np.zeros(1000)]
    c = sgd_icp.estimate_covariances(points, k=15)
    assert c.shape == (1000, 3, 3) and c.dtype == np.float32
    np.testing.assert_allclose(c, np.swapaxes(c, 1, 2), atol=1e-6)
    # The plane model: epsilon along the normal (z), 1 in the plane.
    np.testing.assert_allclose(c[:, 2, 2], 1e-3, atol=1e-5)
    np.testing.assert_allclose(c[:, 0, 0] + c[:, 1, 1], 2.0, atol=1e-4)
    raw = sgd_icp.estimate_covariances(points, regularize=False)
    assert np.all(raw[:, 2, 2] == 0) and np.all(raw[:, 0, 0] > 0)
    assert np.all(raw[:, 0, 0] < 0.05)  # m^2: neighbourhoods of ~5 cm


@pytest.mark.parametrize("function", [sgd_icp.estimate_normals, sgd_icp.estimate_covariances])
def test_estimator_errors(function):
    good = synthetic_scene(5, 200)
    with pytest.raises(ValueError, match="row 3 holds a NaN or infinite coordinate"):
        bad = good.copy()
        bad[3, 1] = np.nan
        function(bad)
    with pytest.raises(ValueError, match="has no points"):
        function(np.zeros((0, 3)))
    with pytest.raises(ValueError):
        function(good, k=2)
    with pytest.raises(ValueError):
        function(good, num_threads=5000)
    with pytest.raises(ValueError, match=r"got shape \(200,\)"):
        function(good[:, 0])


def test_preprocessing_then_registration(small_scene):
    source, reference, T_gt = small_scene
    small = sgd_icp.random_downsample(sgd_icp.voxel_downsample(source, 0.05), 5000, seed=3)
    r = sgd_icp.register(small, reference, method="gicp", max_distance=0.1)
    assert r.converged, r.message
    assert sgd_icp.translation_error(r.T_reference_source, T_gt) < 0.02
