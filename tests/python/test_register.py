"""sgd_icp.register: known transforms (synthetic and real data), the CLI's bits, array layouts,
reference indexes, results and traces."""

from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest

import sgd_icp
from conftest import (find_cli, make_transform, read_pairs, shared_data_dir, synthetic_scene,
                      transformed)

DEG = np.pi / 180


# ---- known transforms


@pytest.mark.parametrize(
    "roll, pitch, yaw, t",
    [
        (0, 0, 0, (0, 0, 0)),
        (0, 0, 20 * DEG, (0.1, 0.2, 0)),
        (5 * DEG, -8 * DEG, 15 * DEG, (-0.25, 0.1, 0.05)),
    ],
    ids=["identity", "yaw20", "mixed"],
)
def test_synthetic_transform_is_recovered(roll, pitch, yaw, t):
    # Independent samplings ~4 cm apart: the point-to-point optimum is biased by a few mm, so
    # 1 cm / 0.3 deg (the C++ tests' bounds) leave room for that and fail any wrong basin.
    T_gt = make_transform(roll, pitch, yaw, t)
    source = synthetic_scene(1)
    reference = transformed(synthetic_scene(2), T_gt)
    r = sgd_icp.register(source, reference)
    assert r.converged, r.message
    assert sgd_icp.translation_error(r.T_reference_source, T_gt) < 0.01
    assert sgd_icp.rotation_error_geodesic(r.T_reference_source, T_gt) < 0.3 * DEG
    assert r.inlier_ratio > 0.9
    assert r.inlier_rmse_m < 0.03


def test_initial_guess_is_used(scene):
    source, reference, T_gt = scene
    from_truth = sgd_icp.register(source, reference, init=T_gt, record_trace=True)
    from_identity = sgd_icp.register(source, reference, record_trace=True)
    # One Adam step turns each angle by at most ~lr (0.01 rad) from where the run starts.
    assert sgd_icp.rotation_error_geodesic(from_truth.trace.T_reference_source[0], T_gt) < 2 * DEG
    assert (
        sgd_icp.rotation_error_geodesic(from_identity.trace.T_reference_source[0], T_gt) > 10 * DEG
    )
    assert from_truth.converged, from_truth.message
    assert sgd_icp.translation_error(from_truth.T_reference_source, T_gt) < 0.01


def test_real_pair_is_registered_within_its_ground_truth(car_pair):
    *_, source, reference, T_gt = car_pair
    r = sgd_icp.register(source, reference)
    assert r.converged, r.message
    # README table: 1.9 cm / 0.19 deg median; libpointmatcher's own ground truth is no better.
    assert sgd_icp.translation_error(r.T_reference_source, T_gt) < 0.05
    assert sgd_icp.rotation_error_geodesic(r.T_reference_source, T_gt) < 1 * DEG


def test_real_moved_copy_is_registered_exactly():
    # The paper's protocol on the ETH Kinect map: the reference is an exact moved copy, so with
    # every point each has its twin and the answer is exact. The default voxel grid (2.8 cm) falls
    # on the copy at another phase (other centroids): about a millimetre there.
    source_path, reference_path, T_gt = read_pairs("eth_kinect_map_moved_copies")[0]
    source, reference = sgd_icp.read_points(source_path), sgd_icp.read_points(reference_path)
    r = sgd_icp.register(source, reference, downsample_to=0)
    assert r.converged, r.message
    assert r.voxel_size_m == 0 and r.source_points == len(source)
    assert sgd_icp.translation_error(r.T_reference_source, T_gt) < 1e-4
    assert sgd_icp.rotation_error_geodesic(r.T_reference_source, T_gt) < 0.01 * DEG
    default = sgd_icp.register(source, reference)
    assert default.voxel_size_m > 0 and default.source_points < len(source)
    assert sgd_icp.translation_error(default.T_reference_source, T_gt) < 3e-3
    assert sgd_icp.rotation_error_geodesic(default.T_reference_source, T_gt) < 0.05 * DEG


# ---- the same bits as the C++ command-line tool


@pytest.mark.parametrize(
    "cli_options, python_options",
    [
        (["--seed", "7"], {"seed": 7}),
        (
            ["--optimizer", "gauss-newton", "-m", "100", "-d", "1.0", "--max-distance-unit", "m"],
            {
                "optimizer": "gauss-newton",
                "batch_size": 100,
                "max_distance": 1.0,
                "max_distance_unit": "m",
            },
        ),
        (
            ["--preset", "paper", "--optimizer", "adam"],
            {"settings": sgd_icp.Settings.paper("adam")},
        ),
        (
            [
                "--method",
                "sgd-plane",
                "--kernel",
                "huber",
                "--kernel-scale",
                "0.05",
                "--max-distance-unit",
                "m",
                "--trim",
                "0.9",
            ],
            {
                "cost": "point-to-plane",
                "kernel": "huber",
                "kernel_scale": 0.05,
                "max_distance_unit": "m",
                "trim": 0.9,
            },
        ),
        (["--method", "sgd-plane", "--seed", "3"], {"method": "sgd-plane", "seed": 3}),
        (
            ["--method", "sgd-gicp", "--neighbors", "15", "--trim", "0.95"],
            {"method": "sgd-gicp", "neighbors": 15, "trim": 0.95},
        ),
        (["--method", "icp"], {"method": "icp"}),
        (
            ["--method", "icp-plane", "-d", "1.0", "--max-distance-unit", "m", "--damping", "0"],
            {"method": "icp-plane", "max_distance": 1.0, "max_distance_unit": "m", "damping": 0.0},
        ),
        (
            ["--method", "gicp", "--kernel", "cauchy", "--max-iterations", "30"],
            {"method": "gicp", "kernel": "cauchy", "max_iterations": 30},
        ),
    ],
    ids=[
        "seed",
        "overrides",
        "paper-adam",
        "plane-huber-trim",
        "method-sgd-plane",
        "method-sgd-gicp",
        "method-icp",
        "method-icp-plane",
        "method-gicp",
    ],
)
def test_same_result_as_the_cli(car_pair, cli_options, python_options):
    cli = find_cli()
    if cli is None:
        pytest.skip("sgdicp CLI not found (set SGDICP_BIN or build it with scripts/build.sh)")
    source_path, reference_path, source, reference, _ = car_pair
    out = subprocess.run(
        [str(cli), "register", str(source_path), str(reference_path), "--json", *cli_options],
        check=True,
        capture_output=True,
        text=True,
        timeout=120,
    )
    expected = json.loads(out.stdout)
    r = sgd_icp.register(source, reference, **python_options)
    # Same library, inputs and seed: the same iterations and the same transform (to the bit, up
    # to the 17 digits of the JSON).
    assert r.iterations == expected["iterations"], f"is {cli} built from the same sources?"
    assert r.stop_reason == expected["stop_reason"]
    assert r.degenerate == expected["degenerate"]
    np.testing.assert_allclose(
        r.T_reference_source, np.array(expected["transform"]), rtol=0, atol=1e-12
    )


@pytest.mark.parametrize("cost", ["point-to-plane", "plane-to-plane"])
def test_plane_costs_recover_the_transform(scene, cost):
    source, reference, T_gt = scene
    source, reference = source[::2], reference[::2]
    # Every point (downsample_to=0): the index holds the clouds as given, as the array does.
    with_array = sgd_icp.register(source, reference, cost=cost, kernel="huber", downsample_to=0)
    # Prepared with the SGD methods' neighbourhoods (flat ones of 10), as they would estimate.
    index = sgd_icp.ReferenceIndex(reference, cost=cost, neighborhood=sgd_icp.Settings().neighborhood)
    assert index.has_normals and (index.has_covariances or cost == "point-to-plane")
    with_index = sgd_icp.register(source, index, cost=cost, kernel="huber", downsample_to=0)
    assert np.array_equal(with_array.T_reference_source, with_index.T_reference_source)
    assert with_index.converged, with_index.message
    assert sgd_icp.translation_error(with_index.T_reference_source, T_gt) < 0.01
    assert sgd_icp.rotation_error_geodesic(with_index.T_reference_source, T_gt) < 0.3 * DEG


def test_same_seed_same_bits_other_seed_other_path(scene):
    source, reference, _ = scene
    a = sgd_icp.register(source, reference, seed=11)
    b = sgd_icp.register(source, reference, seed=11)
    c = sgd_icp.register(source, reference, seed=12)
    assert np.array_equal(a.T_reference_source, b.T_reference_source)
    assert not np.array_equal(a.T_reference_source, c.T_reference_source)


# ---- array layouts: one float32 copy, whatever the input looks like


def layouts(points: np.ndarray) -> dict[str, np.ndarray]:
    """The same float32 points in every layout register() must accept."""
    n = len(points)
    wide = np.zeros((n, 7))
    wide[:, 2:5] = points
    columns = np.zeros((n, 6), dtype=np.float32)
    columns[:, ::2] = points
    rows = np.zeros((2 * n, 3), dtype=np.float32)
    rows[::2] = points
    reversed_storage = np.ascontiguousarray(points[::-1, ::-1])
    unaligned = np.frombuffer(bytearray(points.nbytes + 1), dtype=np.float32, offset=1).reshape(
        n, 3
    )
    unaligned[...] = points
    return {
        "float32 C": np.ascontiguousarray(points, dtype=np.float32),
        "float64 C": points.astype(np.float64),
        "float32 F": np.asfortranarray(points),
        "float64 F": np.asfortranarray(points, dtype=np.float64),
        "float64 column slice": wide[:, 2:5],
        "float32 strided columns": columns[:, ::2],
        "float32 strided rows": rows[::2],
        "negative strides": reversed_storage[::-1, ::-1],
        "unaligned": unaligned,
        "big-endian": points.astype(">f4"),
    }


def test_every_layout_gives_the_same_result(scene):
    source, reference, _ = scene
    source, reference = source[::4], reference[::4]  # 15k points: fast, still well posed
    expected = sgd_icp.register(source, reference).T_reference_source
    variants = layouts(source)
    assert sum(not v.flags.c_contiguous for v in variants.values()) >= 6
    assert not variants["unaligned"].flags.aligned
    for name, s in variants.items():
        r = sgd_icp.register(s, reference)
        assert np.array_equal(r.T_reference_source, expected), f"source as {name}"
    for name, ref in layouts(reference).items():
        r = sgd_icp.register(source, ref)
        assert np.array_equal(r.T_reference_source, expected), f"reference as {name}"


def test_list_input_is_accepted():
    points = synthetic_scene(3, 500)
    r = sgd_icp.register(points.tolist(), points, batch_size=50, max_iterations=50)
    assert r.iterations > 0


def test_inputs_are_not_modified(scene):
    source, reference, _ = scene
    s, ref = source.copy(), reference.copy()
    sgd_icp.register(s, ref)
    assert np.array_equal(s, source) and np.array_equal(ref, reference)


# ---- reference indexes


def test_reference_index_gives_the_same_result_as_an_array(scene):
    source, reference, _ = scene
    index = sgd_icp.ReferenceIndex(reference)
    assert len(index) == len(reference)
    assert index.non_finite_dropped == 0
    assert np.array_equal(index.points, reference)
    assert not index.points.flags.writeable
    lower, upper = index.bounding_box
    np.testing.assert_allclose(lower, reference.min(axis=0))
    np.testing.assert_allclose(upper, reference.max(axis=0))
    # An index of the points as given registers every point, as an array with downsample_to=0.
    with_index = sgd_icp.register(source, index)
    assert with_index.voxel_size_m == 0 and with_index.reference_points == len(reference)
    with_array = sgd_icp.register(source, reference, downsample_to=0)
    assert np.array_equal(with_index.T_reference_source, with_array.T_reference_source)
    assert with_index.build_ms == 0.0 and with_array.build_ms > 0.0
    assert index.build_ms > 0.0
    # The index register() builds by default (the reference on its voxel grid) is for_registration.
    default_index = sgd_icp.ReferenceIndex.for_registration(reference)
    assert len(default_index) < len(reference)
    with_default_index = sgd_icp.register(source, default_index)
    by_default = sgd_icp.register(source, reference)
    assert by_default.voxel_size_m > 0 and with_default_index.voxel_size_m == by_default.voxel_size_m
    assert np.array_equal(with_default_index.T_reference_source, by_default.T_reference_source)
    assert by_default.reference_points == len(default_index)


def test_points_view_keeps_the_index_alive(scene):
    view = sgd_icp.ReferenceIndex(scene[1]).points  # the index object is gone after this line
    assert np.array_equal(view, scene[1])


# ---- results


def test_result_has_every_field(scene):
    source, reference, _ = scene
    r = sgd_icp.register(source, reference)
    assert r.T_reference_source.shape == (4, 4) and r.T_reference_source.dtype == np.float64
    np.testing.assert_array_equal(r.T_reference_source[3], [0, 0, 0, 1])
    assert r.converged is True and r.stop_reason == "converged" and r.message
    assert r.iterations > 0 and r.points_processed == r.iterations * 160
    # The coarse phase and 3 refinement stages, or fewer once the pairs settle (settle_tolerance);
    # all four when settling is off.
    assert 2 <= r.stages <= 4
    every_stage = sgd_icp.Settings()
    every_stage.refinement.settle_tolerance = 0  # a fixed rule: an attribute, not a keyword
    assert sgd_icp.register(source, reference, settings=every_stage).stages == 4
    assert r.evaluated_points == 2000 and 0 < r.inliers <= r.evaluated_points
    assert r.inlier_ratio == pytest.approx(r.inliers / r.evaluated_points)
    assert 0 < r.inlier_rmse_m < 0.03
    assert 0 < r.final_max_distance_m < 0.5 * r.scale_m
    # Both clouds on the default voxel grid (more than downsample_to=20000 points each).
    assert r.voxel_size_m > 0
    source = sgd_icp.voxel_downsample(source, r.voxel_size_m)
    reference = sgd_icp.voxel_downsample(reference, r.voxel_size_m)
    joint = np.vstack([source, reference]).astype(np.float64)
    assert r.scale_m == pytest.approx(np.ptp(joint, axis=0).max())  # longest side of the joint box
    assert r.time_ms > 0 and r.build_ms > 0
    assert 0 < r.constraint_ratio <= 1 and r.degenerate is False
    assert r.source_points == len(source) and r.reference_points == len(reference)
    assert r.source_non_finite_dropped == 0 and r.reference_non_finite_dropped == 0
    assert len(r.trace) == 0 and r.trace.T_reference_source.shape == (0, 4, 4)
    assert "converged" in repr(r)


def test_trace_describes_every_iteration(scene):
    source, reference, _ = scene
    r = sgd_icp.register(source, reference, record_trace=True)
    k = r.iterations
    t = r.trace
    assert len(t) == k
    np.testing.assert_array_equal(t.iteration, np.arange(1, k + 1))
    np.testing.assert_array_equal(t.points_processed, 160 * np.arange(1, k + 1))
    assert t.T_reference_source.shape == (k, 4, 4)
    assert t.iteration.dtype == np.int64 and t.inliers.dtype == np.int64
    for name in ("step_size", "max_distance_m", "cost"):
        assert getattr(t, name).shape == (k,) and getattr(t, name).dtype == np.float64
    assert np.all(t.inliers <= 160) and np.all(t.step_size > 0) and np.all(t.cost >= 0)
    assert np.all(np.diff(t.max_distance_m) <= 1e-12)  # d_max never grows
    assert t.max_distance_m[-1] == pytest.approx(r.final_max_distance_m)


def test_non_converged_run_is_reported(scene):
    source, reference, _ = scene
    r = sgd_icp.register(source, reference, max_iterations=5)
    assert not r.converged and r.stop_reason == "max_iterations" and r.iterations == 5


NEWER = shared_data_dir() / "newer_college_ouster_skewed"


@pytest.mark.skipif(not (NEWER / "raw_01.bin").is_file(), reason="no Newer College sweeps")
def test_a_skewed_sweep_is_registered_with_its_times():
    raw = np.fromfile(NEWER / "raw_01.bin", dtype="<f4").reshape(-1, 3)
    times = np.fromfile(NEWER / "times_01.bin", dtype="<f4").astype(np.float64) + 1.7e9  # a clock
    copy = np.fromfile(NEWER / "deskewed_01.bin", dtype="<f4").reshape(-1, 3)
    turn = np.diag([-1.0, -1.0, 1.0, 1.0])  # the half turn between their frames (PROVENANCE)
    r = sgd_icp.register_sweep(raw, copy, times, init=turn)
    assert r["converged"], r["message"]
    assert r["aligned"].shape == raw.shape
    assert np.median(np.linalg.norm(r["aligned"] - copy, axis=1)) < 0.02  # rigid fit: 23 cm
    assert abs(r["mid_time"] - 1.7e9 - 0.05) < 0.01 and r["velocity"].shape == (6,)
    with pytest.raises(sgd_icp.InvalidInputError, match="one per point"):
        sgd_icp.register_sweep(raw, copy, times[:10])
