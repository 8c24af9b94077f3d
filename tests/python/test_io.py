"""read_points, read_point_cloud and write_points, and the error metrics."""

from __future__ import annotations

import numpy as np
import pytest

import sgd_icp
from conftest import make_transform, shared_data_dir, synthetic_scene

POINTS = synthetic_scene(7, 1000)


@pytest.mark.parametrize("name", ["cloud.ply", "cloud.pcd", "cloud.xyz"])
@pytest.mark.parametrize("encoding", ["binary", "ascii"])
def test_written_files_read_back_bit_identical(tmp_path, name, encoding):
    path = tmp_path / name
    sgd_icp.write_points(path, POINTS.astype(np.float64), encoding=encoding)
    back = sgd_icp.read_points(path)
    assert back.dtype == np.float32 and back.shape == POINTS.shape
    assert back.flags.c_contiguous and back.flags.writeable
    assert np.array_equal(back, POINTS)


def test_explicit_format_and_str_paths(tmp_path):
    path = tmp_path / "cloud.dat"
    sgd_icp.write_points(str(path), POINTS, format="xyz")
    assert np.array_equal(sgd_icp.read_points(str(path), format="xyz"), POINTS)


def test_read_point_cloud_counts_dropped_points(tmp_path):
    path = tmp_path / "holes.xyz"
    path.write_text("# x y z\n1 2 3\nnan 0 0\n4 5 6\n0 inf 0\n")
    read = sgd_icp.read_point_cloud(path)
    assert read.format == "xyz"
    assert read.points_in_file == 4 and read.non_finite_dropped == 2
    np.testing.assert_array_equal(read.points, [[1, 2, 3], [4, 5, 6]])
    assert "2 of 4 dropped" in repr(read)


def test_empty_files_and_arrays(tmp_path):
    path = tmp_path / "empty.ply"
    sgd_icp.write_points(path, np.zeros((0, 3)))
    read = sgd_icp.read_points(path)
    assert read.shape == (0, 3) and read.dtype == np.float32


def test_read_array_owns_its_memory():
    path = shared_data_dir() / "pcl_bunny" / "bun0.pcd"
    if not path.is_file():
        pytest.skip(f"real data not found: {path}")
    points = sgd_icp.read_points(path)
    assert points.shape == (397, 3)
    points[0] = 0  # writeable, and freed with the array (the buffer is handed over, not copied)
    del points


def test_metrics():
    T_gt = make_transform(0.1, -0.2, 0.3, (1.0, 2.0, 3.0))
    T_est = T_gt @ make_transform(0, 0, 0.01, (0.3, 0.4, 0.0))
    assert sgd_icp.translation_error(T_est, T_gt) == pytest.approx(
        np.linalg.norm(T_est[:3, 3] - T_gt[:3, 3])
    )
    assert sgd_icp.rotation_error_geodesic(T_est, T_gt) == pytest.approx(0.01)
    assert sgd_icp.rotation_error_euler_sum(T_gt, T_gt) == 0.0
    assert sgd_icp.rotation_error_euler_sum(T_est, T_gt) > 0.0
    assert sgd_icp.translation_error(T_est.tolist(), T_gt) == sgd_icp.translation_error(T_est, T_gt)
    with pytest.raises(ValueError, match=r"T_est must be a \(4, 4\) transform, got shape \(3, 4\)"):
        sgd_icp.translation_error(T_est[:3], T_gt)


def test_a_time_field_is_read_as_times(tmp_path):
    path = tmp_path / "sweep.ply"
    path.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                    "property float z\nproperty uint t\nend_header\n"
                    "1 0 0 50000000\nnan 0 0 0\n0 1 0 100000000\n")
    read = sgd_icp.read_point_cloud(path)
    assert read.points.shape == (2, 3)
    np.testing.assert_allclose(read.times, [0.0, 0.05], atol=1e-9)  # ns -> s, from the earliest
    plain = tmp_path / "plain.xyz"
    plain.write_text("1 0 0\n0 1 0\n")
    assert sgd_icp.read_point_cloud(plain).times is None
