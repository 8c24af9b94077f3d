"""Open3D clouds in place of NumPy arrays: open3d.geometry.PointCloud (legacy) and
open3d.t.geometry.PointCloud (tensor), with and without normals, give the transforms of the
equivalent arrays bit for bit; open3d is never imported by sgd_icp itself."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import sgd_icp
from conftest import REPO_ROOT, import_open3d, make_transform, synthetic_scene, transformed

o3d = import_open3d()  # skips when open3d is missing or cannot load its system libraries

DEG = np.pi / 180


def seeded(method):
    """seed= for the SGD methods (the batch methods have no randomness and no seed)."""
    return {"seed": 3} if method.startswith("sgd") else {}
T_GT = make_transform(4 * DEG, -3 * DEG, 12 * DEG, (0.2, -0.1, 0.05))


@pytest.fixture(scope="module")
def clouds():
    """(source, reference, reference normals): float64 arrays, the normals from Open3D's own
    estimate (5 neighbours, so they differ from sgd-icp's estimate)."""
    source = synthetic_scene(11, n=12000).astype(np.float64)
    reference = transformed(synthetic_scene(12, n=12000), T_GT).astype(np.float64)
    legacy = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(reference))
    legacy.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(knn=5))
    return source, reference, np.asarray(legacy.normals).copy()


def legacy_cloud(points, normals=None):
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    if normals is not None:
        cloud.normals = o3d.utility.Vector3dVector(normals)
    return cloud


def tensor_cloud(points, normals=None, dtype=np.float64):
    cloud = o3d.t.geometry.PointCloud(o3d.core.Tensor(points.astype(dtype)))
    if normals is not None:
        cloud.point.normals = o3d.core.Tensor(normals.astype(dtype))
    return cloud


@pytest.mark.parametrize("make", [legacy_cloud, tensor_cloud], ids=["legacy", "tensor"])
@pytest.mark.parametrize("method", ["sgd", "sgd-plane", "icp", "icp-plane", "gicp"])
def test_open3d_without_normals_matches_numpy(clouds, make, method):
    source, reference, _ = clouds
    expected = sgd_icp.register(source, reference, method=method, **seeded(method))
    got = sgd_icp.register(make(source), make(reference), method=method, **seeded(method))
    np.testing.assert_array_equal(got.T_reference_source, expected.T_reference_source)
    assert got.converged, got.message
    assert sgd_icp.translation_error(got.T_reference_source, T_GT) < 0.02


@pytest.mark.parametrize("make", [legacy_cloud, tensor_cloud], ids=["legacy", "tensor"])
@pytest.mark.parametrize("method", ["sgd-plane", "icp-plane"])
def test_open3d_normals_are_used_by_the_plane_costs(clouds, make, method):
    source, reference, normals = clouds
    index = sgd_icp.ReferenceIndex(reference, normals=normals, cost="point-to-plane")
    assert index.has_normals
    expected = sgd_icp.register(source, index, method=method, **seeded(method))
    got = sgd_icp.register(make(source), make(reference, normals), method=method, **seeded(method))
    np.testing.assert_array_equal(got.T_reference_source, expected.T_reference_source)
    o3d_index = sgd_icp.ReferenceIndex(make(reference, normals), cost="point-to-plane")
    via_index = sgd_icp.register(make(source), o3d_index, method=method, **seeded(method))
    np.testing.assert_array_equal(via_index.T_reference_source, expected.T_reference_source)
    # The given normals, not sgd-icp's own estimate, were used.
    estimated = sgd_icp.register(source, reference, method=method, **seeded(method))
    assert not np.array_equal(got.T_reference_source, estimated.T_reference_source)
    assert sgd_icp.translation_error(got.T_reference_source, T_GT) < 0.02


def test_float32_tensor_cloud_matches_float32_array(clouds):
    source, reference, _ = clouds
    s32, r32 = source.astype(np.float32), reference.astype(np.float32)
    expected = sgd_icp.register(s32, r32, seed=5)
    got = sgd_icp.register(tensor_cloud(s32, dtype=np.float32), tensor_cloud(r32, dtype=np.float32),
                           seed=5)
    np.testing.assert_array_equal(got.T_reference_source, expected.T_reference_source)


def test_result_is_open3d_transformation(clouds):
    # T_reference_source is what Open3D calls `transformation` (source -> target).
    source, reference, _ = clouds
    r = sgd_icp.register(legacy_cloud(source), legacy_cloud(reference))
    moved = legacy_cloud(source).transform(r.T_reference_source)
    expected = source @ r.T_reference_source[:3, :3].T + r.T_reference_source[:3, 3]
    np.testing.assert_allclose(np.asarray(moved.points), expected, atol=1e-12)
    def fitness(T):
        return o3d.pipelines.registration.evaluate_registration(
            legacy_cloud(source), legacy_cloud(reference), 0.05, T).fitness

    # Open3D scores our transform as it scores the ground truth, and far above the identity.
    assert fitness(r.T_reference_source) > fitness(T_GT) - 0.02
    assert fitness(np.eye(4)) < fitness(T_GT) - 0.3


def test_other_functions_take_open3d_clouds(clouds, tmp_path):
    source, _, _ = clouds
    cloud = legacy_cloud(source)
    np.testing.assert_array_equal(sgd_icp.voxel_downsample(cloud, 0.1),
                                  sgd_icp.voxel_downsample(source, 0.1))
    np.testing.assert_array_equal(sgd_icp.estimate_normals(tensor_cloud(source)),
                                  sgd_icp.estimate_normals(source))
    sgd_icp.write_points(tmp_path / "cloud.ply", cloud)
    np.testing.assert_array_equal(sgd_icp.read_points(tmp_path / "cloud.ply"),
                                  source.astype(np.float32))


def test_non_finite_points_drop_their_normals(clouds):
    _, reference, normals = clouds
    points = reference.copy()
    points[7] = np.nan
    index = sgd_icp.ReferenceIndex(legacy_cloud(points, normals), cost="point-to-plane")
    assert index.non_finite_dropped == 1 and len(index) == len(points) - 1
    expected = sgd_icp.ReferenceIndex(np.delete(points, 7, axis=0),
                                      normals=np.delete(normals, 7, axis=0),
                                      cost="point-to-plane")
    s = sgd_icp.register(reference[:5000], index, method="sgd-plane", seed=1)
    e = sgd_icp.register(reference[:5000], expected, method="sgd-plane", seed=1)
    np.testing.assert_array_equal(s.T_reference_source, e.T_reference_source)


def test_bad_normals_are_clear_errors(clouds):
    _, reference, normals = clouds
    with pytest.raises(sgd_icp.InvalidInputError, match="points but"):
        sgd_icp.ReferenceIndex(reference, normals=normals[:10])
    bad = normals.copy()
    bad[3] = np.inf
    with pytest.raises(sgd_icp.InvalidInputError, match="non-finite normal at row 3"):
        sgd_icp.ReferenceIndex(reference, normals=bad)
    with pytest.raises(sgd_icp.InvalidInputError, match="drop normals="):
        sgd_icp.ReferenceIndex(legacy_cloud(reference, normals), normals=normals)


def test_open3d_and_dask_are_not_imported_by_the_package():
    code = ("import sys, sgd_icp, sgd_icp.distributed; "
            "print('open3d' in sys.modules, 'dask' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=REPO_ROOT / "tests")
    assert out.stdout.strip() == "False False"
