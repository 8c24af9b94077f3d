"""Georeferenced float64 input (UTM-like coordinates, millions of metres): registered as exactly
as the same clouds near the origin, and float64 back out, where float32 would snap every point
to a 0.25-0.5 m grid."""

from __future__ import annotations

import numpy as np

import sgd_icp

# On the kilometre grid the library stores points from, so the stored floats are the same as for
# the un-offset clouds and the run is the very same one.
GRID_OFFSET = np.array([512000.0, 4235000.0, 0.0])
UTM_OFFSET = np.array([512345.0, 4234567.0, 120.0])


def at(T: np.ndarray, point: np.ndarray) -> np.ndarray:
    """The transform re-expressed about `point`, where its translation error means something."""
    out = T.copy()
    out[:3, 3] += T[:3, :3] @ point - point
    return out


def test_grid_offset_gives_the_same_run(scene):
    source, reference, _ = scene
    clean = sgd_icp.register(source, reference)
    offset = sgd_icp.register(
        source.astype(np.float64) + GRID_OFFSET, reference.astype(np.float64) + GRID_OFFSET
    )
    assert offset.iterations == clean.iterations
    np.testing.assert_allclose(
        at(offset.T_reference_source, GRID_OFFSET), clean.T_reference_source, atol=1e-6
    )


def test_utm_offset_is_registered_as_accurately(scene):
    source, reference, T_gt = scene
    r = sgd_icp.register(
        source.astype(np.float64) + UTM_OFFSET,
        reference.astype(np.float64) + UTM_OFFSET,
        method="icp-plane",
    )
    clean = sgd_icp.register(source, reference, method="icp-plane")
    T_at_scene = at(r.T_reference_source, UTM_OFFSET)
    assert sgd_icp.translation_error(T_at_scene, clean.T_reference_source) < 1e-3
    sgd = sgd_icp.register(
        source.astype(np.float64) + UTM_OFFSET, reference.astype(np.float64) + UTM_OFFSET
    )
    assert sgd.converged, sgd.message
    assert not sgd.degenerate
    assert sgd_icp.translation_error(at(sgd.T_reference_source, UTM_OFFSET), T_gt) < 0.01
    assert sgd_icp.rotation_error_geodesic(at(sgd.T_reference_source, UTM_OFFSET), T_gt) < np.radians(0.3)


def test_preprocessing_returns_float64_for_georeferenced_points(scene):
    source = scene[0].astype(np.float64) + UTM_OFFSET
    down = sgd_icp.voxel_downsample(source, 0.05)
    assert down.dtype == np.float64
    # Every centroid lies within the cloud's own box, not quantised to the 0.5 m float grid.
    assert np.all(down.min(axis=0) >= source.min(axis=0) - 1e-6)
    assert np.all(down.max(axis=0) <= source.max(axis=0) + 1e-6)
    frac = np.modf(down[:, 0])[0]
    assert len(np.unique(np.round(frac, 3))) > 10
    near = sgd_icp.voxel_downsample(scene[0], 0.05)
    assert near.dtype == np.float32


def test_files_round_trip_georeferenced_points(tmp_path, scene):
    source = scene[0].astype(np.float64) + UTM_OFFSET
    for name in ("g.ply", "g.pcd", "g.xyz"):
        path = tmp_path / name
        sgd_icp.write_points(path, source)
        back = sgd_icp.read_points(path)
        assert back.dtype == np.float64, name
        np.testing.assert_allclose(back, source, rtol=0, atol=1e-4)
    index = sgd_icp.ReferenceIndex(source)
    np.testing.assert_allclose(index.points, source, rtol=0, atol=1e-4)
