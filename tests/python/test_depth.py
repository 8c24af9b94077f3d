"""read_depth_image and depth_to_points: hand-computed points, the intrinsics forms, bad input,
and a real 7-Scenes frame against bench/make_sevenscenes_pairs.py's numpy back-projection."""

from __future__ import annotations

import importlib.util
import struct
import zlib

import numpy as np
import pytest

import sgd_icp
from conftest import REPO_ROOT, shared_data_dir

K = (500.0, 480.0, 3.5, 2.0)


def png16(depth: np.ndarray, bit_depth: int = 16) -> bytes:
    """A greyscale PNG of a 2-D array (the test's own encoder, independent of the reader)."""
    height, width = depth.shape
    dtype = ">u2" if bit_depth == 16 else "u1"
    raw = b"".join(b"\0" + depth[v].astype(dtype).tobytes() for v in range(height))

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    ihdr = struct.pack(">IIBBBBB", width, height, bit_depth, 0, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")


def expected_points(depth_m: np.ndarray, intrinsics, stride: int = 1) -> np.ndarray:
    fx, fy, cx, cy = intrinsics
    v, u = np.mgrid[0 : depth_m.shape[0] : stride, 0 : depth_m.shape[1] : stride]
    z = depth_m[::stride, ::stride]
    keep = z > 0
    return np.stack([(u - cx) * z / fx, (v - cy) * z / fy, z], axis=-1)[keep].astype(np.float32)


def test_plane_in_millimetres_gives_the_hand_computed_points():
    depth = np.full((5, 8), 2000, dtype=np.uint16)
    points = sgd_icp.depth_to_points(depth, K)
    assert points.dtype == np.float32 and points.shape == (40, 3)
    np.testing.assert_array_equal(points, expected_points(depth / 1000.0, K))
    np.testing.assert_allclose(points[0], [-0.014, -2.0 * 2.0 / 480.0, 2.0], rtol=1e-6)


def test_float_metres_stride_and_dropped_pixels():
    depth = np.linspace(0.5, 3.0, 7 * 9, dtype=np.float32).reshape(7, 9)
    depth[0, 0] = np.nan
    depth[2, 2] = 0.0
    depth[4, 4] = 12.0  # beyond the default max_depth of 10 m
    points = sgd_icp.depth_to_points(depth, K, pixel_stride=2)
    reference = depth.astype(np.float64)
    reference[0, 0] = 0.0
    reference[4, 4] = 0.0
    np.testing.assert_allclose(points, expected_points(reference, K, 2), rtol=1e-6)
    assert len(points) == 4 * 5 - 3
    # A Fortran-ordered or strided array gives the same points.
    np.testing.assert_array_equal(sgd_icp.depth_to_points(np.asfortranarray(depth), K, pixel_stride=2), points)
    np.testing.assert_array_equal(sgd_icp.depth_to_points(depth.astype(np.float64), K, pixel_stride=2), points)


def test_border_drops_a_band_along_each_edge():
    depth = np.linspace(0.5, 3.0, 7 * 9, dtype=np.float32).reshape(7, 9)
    points = sgd_icp.depth_to_points(depth, K, border=2)
    inner = np.zeros_like(depth)
    inner[2:-2, 2:-2] = depth[2:-2, 2:-2]
    np.testing.assert_allclose(points, expected_points(inner.astype(np.float64), K), rtol=1e-6)
    assert len(points) == 5 * 3
    with pytest.raises(sgd_icp.InvalidSettingsError, match="leaves no pixel of a 9 x 7"):
        sgd_icp.depth_to_points(depth, K, border=4)


def test_depth_scale_and_range_keywords():
    depth = np.array([[5000, 100, 60000]], dtype=np.uint16)
    points = sgd_icp.depth_to_points(depth, K, depth_scale=5000)
    assert points[:, 2].tolist() == pytest.approx([1.0, 0.02])
    assert len(sgd_icp.depth_to_points(depth, K, depth_scale=5000, min_depth=0.5)) == 1
    assert len(sgd_icp.depth_to_points(depth, K, depth_scale=5000, max_depth=20)) == 3


def test_intrinsics_forms(tmp_path):
    depth = np.full((3, 4), 1500, dtype=np.uint16)
    reference = sgd_icp.depth_to_points(depth, K)
    matrix = np.array([[K[0], 0, K[2]], [0, K[1], K[3]], [0, 0, 1]])
    k_file = tmp_path / "camera-intrinsics.txt"
    np.savetxt(k_file, matrix)
    for intrinsics in (list(K), np.array(K), matrix, k_file, str(k_file), "500,480,3.5,2"):
        np.testing.assert_array_equal(sgd_icp.depth_to_points(depth, intrinsics), reference)


def test_read_depth_image_reads_a_16_bit_png(tmp_path):
    depth = (np.arange(12, dtype=np.uint16).reshape(3, 4) * 311 + 700).astype(np.uint16)
    depth[1, 1] = 0
    path = tmp_path / "d.png"
    path.write_bytes(png16(depth))
    points = sgd_icp.read_depth_image(path, K)
    np.testing.assert_array_equal(points, sgd_icp.depth_to_points(depth, K))
    assert len(points) == 11


def test_bad_input_is_a_typed_error(tmp_path):
    depth = np.full((3, 4), 1000, dtype=np.uint16)
    with pytest.raises(sgd_icp.InvalidInputError, match="uint16"):
        sgd_icp.depth_to_points(depth.astype(np.int32), K)
    with pytest.raises(sgd_icp.InvalidInputError, match="2-D"):
        sgd_icp.depth_to_points(depth[None], K)
    with pytest.raises(sgd_icp.InvalidSettingsError, match="fx"):
        sgd_icp.depth_to_points(depth, (0.0, 480, 3, 2))
    with pytest.raises(sgd_icp.InvalidSettingsError, match="cx"):
        sgd_icp.depth_to_points(depth, (500, 480, float("nan"), 2))
    with pytest.raises(sgd_icp.InvalidSettingsError, match="pixel_stride"):
        sgd_icp.depth_to_points(depth, K, pixel_stride=0)
    with pytest.raises(sgd_icp.InvalidSettingsError, match="border"):
        sgd_icp.depth_to_points(depth, K, border=-1)
    with pytest.raises(sgd_icp.InvalidSettingsError, match="max_depth"):
        sgd_icp.depth_to_points(depth, K, max_depth=-1)
    with pytest.raises(sgd_icp.InvalidInputError, match="3x3"):
        sgd_icp.depth_to_points(depth, np.eye(3) * 2)
    with pytest.raises(TypeError):
        sgd_icp.depth_to_points(depth, K, depth_scale="1000")
    eight = tmp_path / "eight.png"
    eight.write_bytes(png16(depth.astype(np.uint8), bit_depth=8))
    with pytest.raises(sgd_icp.FormatError, match="eight.png: an 8-bit PNG"):
        sgd_icp.read_depth_image(eight, K)
    with pytest.raises(sgd_icp.IoError):
        sgd_icp.read_depth_image(tmp_path / "missing.png", K)


def _sevenscenes_script():
    spec = importlib.util.spec_from_file_location("make_sevenscenes_pairs", REPO_ROOT / "bench" / "make_sevenscenes_pairs.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_sevenscenes_frame_matches_the_numpy_back_projection():
    data = shared_data_dir() / "sevenscenes_redkitchen"
    if not (data / "frame-000000.depth.png").exists():
        pytest.skip(f"missing {data}")
    pytest.importorskip("PIL")
    script = _sevenscenes_script()
    for index in (0, 300):
        reference = script.back_project_numpy(data, index, script.read_intrinsics(data))
        points = sgd_icp.read_depth_image(data / script.frame_name(index, "depth.png"), data / "camera-intrinsics.txt")
        assert points.shape == reference.shape
        assert np.max(np.linalg.norm(points.astype(np.float64) - reference, axis=1)) < 1e-6
