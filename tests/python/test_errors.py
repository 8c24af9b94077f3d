"""Bad input gives a Python exception with a message, never a crash: ValueError for data and
settings, OSError for files, TypeError for unknown keywords and wrong types."""

from __future__ import annotations

import numpy as np
import pytest

import sgd_icp
from conftest import synthetic_scene

GOOD = synthetic_scene(5, 2000)


@pytest.mark.parametrize(
    "points, message",
    [
        (np.zeros((100, 2)), r"\(N, 3\) array.*got shape \(100, 2\)"),
        (np.zeros((100, 4)), r"got shape \(100, 4\)"),
        (np.zeros((100, 3, 1)), r"got shape \(100, 3, 1\)"),
        (np.zeros(300), r"got shape \(300,\)"),
        (np.zeros(()), r"got shape \(\)"),
        (np.zeros((0, 3)), r"has no points \(shape \(0, 3\)\)"),
        (np.zeros((100, 3), dtype=np.int64), r"float32 or float64.*got dtype int64"),
        (np.zeros((100, 3), dtype=np.float16), r"got dtype float16"),
        (np.zeros((100, 3), dtype=np.complex128), r"got dtype complex128"),
        (np.zeros((100, 3), dtype=object), r"got dtype object"),
        (np.full((100, 3), np.nan), r"no finite points: all 100 rows hold a NaN or infinite"),
        (np.full((7, 3), np.inf, dtype=np.float32), r"no finite points: all 7 rows"),
        (np.full((5, 3), 1e300), r"no finite points: all 5 rows"),  # beyond float32
        ("scan.pcd", r"got a path scan.pcd \(read files with sgd_icp.read_points"),
    ],
)
@pytest.mark.parametrize("role", ["source", "reference"])
def test_bad_arrays_raise_value_error(points, message, role):
    args = (points, GOOD) if role == "source" else (GOOD, points)
    with pytest.raises(ValueError, match=f"^{role} .*{message}") as info:
        sgd_icp.register(*args, batch_size=10)
    assert isinstance(info.value, sgd_icp.InvalidInputError)


@pytest.mark.parametrize("points", [np.zeros((0, 3)), np.full((4, 3), np.nan), np.zeros((3, 2))])
def test_bad_reference_index_input_raises_value_error(points):
    with pytest.raises(ValueError, match="^reference "):
        sgd_icp.ReferenceIndex(points)


def test_non_finite_rows_are_dropped_and_counted():
    source = GOOD.astype(np.float64)
    source[3, 0] = np.nan
    source[60, 2] = np.inf
    reference = synthetic_scene(6, 2000)
    reference[10] = -np.inf
    r = sgd_icp.register(source, reference, batch_size=50)
    assert r.source_non_finite_dropped == 2 and r.source_points == len(GOOD) - 2
    assert r.reference_non_finite_dropped == 1 and r.reference_points == len(reference) - 1
    finite = sgd_icp.register(
        source[np.isfinite(source).all(axis=1)], np.delete(reference, 10, axis=0), batch_size=50
    )
    assert np.array_equal(r.T_reference_source, finite.T_reference_source)
    index = sgd_icp.ReferenceIndex(reference)
    assert index.non_finite_dropped == 1 and len(index) == len(reference) - 1


def test_fewer_source_points_than_a_batch_raise_value_error():
    with pytest.raises(ValueError, match="fewer than the smallest mini-batch 32"):
        sgd_icp.register(GOOD[:20], GOOD)
    with pytest.raises(ValueError, match="fewer than the mini-batch size 160"):
        sgd_icp.register(GOOD[:100], GOOD, settings=sgd_icp.Settings.paper("adam"))


@pytest.mark.parametrize(
    "init, message",
    [
        (np.eye(3), r"init must be a \(4, 4\) transform, got shape \(3, 3\)"),
        (np.diag([2.0, 1, 1, 1]), "not a finite rigid transform"),
        (np.full((4, 4), np.nan), "not a finite rigid transform"),
        ("identity", r"init must be a \(4, 4\) array of numbers"),
    ],
)
def test_bad_initial_transforms_raise_value_error(init, message):
    with pytest.raises(ValueError, match=message):
        sgd_icp.register(GOOD, GOOD, init=init, batch_size=10)


@pytest.mark.parametrize(
    "overrides, message",
    [
        ({"batch_size": 0}, r"batch_size=0: must be in \[1, 10000000\]"),
        ({"learning_rate": -1.0}, r"learning_rate=-1: must be in \[1e-06, 10000\]"),
        ({"max_distance": 0.0}, r"max_distance=0 scaled: must be in \[1e-06, 10\] scaled"),
        ({"window": 3}, r"window=3: must be in \[8, 100000\]"),
        ({"window": 10**9}, r"window=1000000000: must be in \[8, 100000\]"),
        ({"learning_rate": 1e-308}, r"learning_rate=1e-308: must be in"),
        ({"distance_factor": 1e-308}, r"distance_factor=1e-308: must be in \[1, 1000\]"),
        ({"kernel": "huber", "kernel_scale": 1e-308}, "kernel_scale=1e-308 scaled: must be in"),
        ({"batch_size": 100000, "window": 10000}, r"batch_size= x window= = 1000000000"),
        ({"batch_size": -5}, "batch_size must be >= 0"),
        ({"optimizer": "newton"}, "unknown optimizer 'newton'"),
        ({"scaling_origin": "middle"}, "unknown scaling origin 'middle'"),
        ({"max_distance_unit": "km", "max_distance": 1.0}, "unknown unit 'km'"),
        ({"max_distance_unit": "m"}, "max_distance_unit applies to max_distance, min_distance"),
        ({"cost": "plane"}, "unknown cost 'plane'"),
        ({"kernel": "tukey"}, "unknown kernel 'tukey'"),
        ({"trim": 0.0}, r"trim=0: must be in \[0.01, 1\]"),
        ({"kernel_scale": 0.0}, "kernel_scale=0 scaled: must be in"),
    ],
)
def test_bad_settings_raise_value_error(overrides, message):
    with pytest.raises(ValueError, match=message) as info:
        sgd_icp.register(GOOD, GOOD, **overrides)
    assert isinstance(info.value, sgd_icp.InvalidSettingsError)
    with pytest.raises(ValueError, match=message):
        sgd_icp.Settings(**overrides)


@pytest.mark.parametrize(
    "overrides, message",
    [
        ({"bach_size": 10}, r"unknown setting 'bach_size'; the keyword settings are: .*batch_size"),
        ({"average_iterates": False}, r"did you mean 'average'\?"),
        ({"max_correspondence_distance": 1.0}, r"did you mean 'max_distance'\?"),
        ({"batch_size": 1.5}, "batch_size must be an integer, got float"),
        ({"batch_size": True}, "batch_size must be an integer, got bool"),
        ({"learning_rate": "0.1"}, "learning_rate must be a number, got str"),
        ({"average": 1}, "average must be True or False, got int"),
        ({"optimizer": 3}, "optimizer must be one of 'sgd', 'momentum'"),
        ({"trim_ratio": 0.5}, r"did you mean 'trim'\?"),
    ],
)
def test_unknown_keywords_and_wrong_types_raise_type_error(overrides, message):
    with pytest.raises(TypeError, match=message):
        sgd_icp.register(GOOD, GOOD, **overrides)


def test_unsigned_settings_reject_negative_and_huge_values():
    # Neither -1 nor 2**64 may wrap around to 2**64 - 1.
    for keyword in ("max_iterations", "seed", "refine_stages", "evaluation_points"):
        with pytest.raises(sgd_icp.InvalidSettingsError, match=f"{keyword} must be >= 0"):
            sgd_icp.Settings(**{keyword: -1})
        with pytest.raises(sgd_icp.InvalidSettingsError, match=f"{keyword} must be at most 2\\^64-1"):
            sgd_icp.Settings(**{keyword: 2**64})
    with pytest.raises(sgd_icp.InvalidSettingsError, match=r"max_iterations=1000000000000: must be in"):
        sgd_icp.Settings(max_iterations=10**12)


def test_method_is_not_a_setting():
    # register() takes method=; Settings (one solver) has a cost instead.
    with pytest.raises(TypeError, match=r"did you mean 'cost'\?"):
        sgd_icp.Settings(method="sgd-plane")


def test_batch_plane_costs_need_a_prepared_index():
    index = sgd_icp.ReferenceIndex(GOOD)
    assert not index.has_normals and not index.has_covariances
    with pytest.raises(
        ValueError,
        match=r"point-to-plane cost needs reference normals: build the "
        r"index with ReferenceIndex\(points, cost='point-to-plane'\)",
    ):
        sgd_icp.register(GOOD, index, method="icp-plane")
    with pytest.raises(ValueError, match="plane-to-plane cost needs reference covariances"):
        sgd_icp.register(GOOD, index, method="gicp")
    with pytest.raises(ValueError, match="unknown cost"):
        sgd_icp.ReferenceIndex(GOOD, cost="plane")


def test_sgd_plane_costs_estimate_what_they_use():
    # The SGD solver estimates the normals / covariances of the points its mini-batches reach,
    # with the estimator of a prepared index: the same result either way.
    for cost in ("point-to-plane", "plane-to-plane"):
        bare = sgd_icp.register(GOOD, sgd_icp.ReferenceIndex(GOOD), cost=cost)
        prepared = sgd_icp.register(GOOD, sgd_icp.ReferenceIndex(GOOD, cost=cost), cost=cost)
        np.testing.assert_array_equal(bare.T_reference_source, prepared.T_reference_source)
        assert bare.converged


def test_settings_argument_must_be_settings():
    with pytest.raises(TypeError, match="settings must be a sgd_icp.Settings or None, got dict"):
        sgd_icp.register(GOOD, GOOD, settings={"batch_size": 10})


def test_attribute_assignment_is_checked():
    s = sgd_icp.Settings()
    with pytest.raises(ValueError, match="batch_size must be >= 0"):
        s.batch_size = -1
    with pytest.raises(TypeError, match="must be a Distance"):
        s.max_correspondence_distance = 1.0
    with pytest.raises(ValueError, match="unknown optimizer"):
        s.optimizer.type = "newton"
    s.refinement.min_distance = sgd_icp.Distance.metres(0.001)
    s.convergence.window = 4
    with pytest.raises(ValueError, match=r"convergence.window = 4: must be in \[8, 100000\]"):
        s.validate()


def test_missing_file_raises_os_error(tmp_path):
    missing = tmp_path / "missing.pcd"
    with pytest.raises(
        OSError, match="missing.pcd: cannot open: No such file or directory"
    ) as info:
        sgd_icp.read_points(missing)
    assert isinstance(info.value, sgd_icp.IoError)
    directory = tmp_path / "folder.xyz"
    directory.mkdir()
    with pytest.raises(OSError, match="folder.xyz: cannot read: Is a directory"):
        sgd_icp.read_points(directory)


def test_bad_files_raise_format_error(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("1 2 3\n4 5\n")
    with pytest.raises(ValueError, match=r"bad.csv: line 2: expected 3 numbers, got 2") as info:
        sgd_icp.read_points(bad)
    assert isinstance(info.value, sgd_icp.FormatError)
    with pytest.raises(sgd_icp.FormatError, match="unknown"):
        sgd_icp.read_points(tmp_path / "cloud.unknown")
    with pytest.raises(sgd_icp.FormatError, match="unknown format 'las'"):
        sgd_icp.read_points(bad, format="las")
    with pytest.raises(sgd_icp.FormatError):
        sgd_icp.write_points(tmp_path / "out.bin", GOOD)  # KITTI .bin is read-only


def test_errors_are_one_family():
    for error in (sgd_icp.InvalidInputError, sgd_icp.InvalidSettingsError, sgd_icp.FormatError):
        assert issubclass(error, sgd_icp.Error) and issubclass(error, ValueError)
    assert issubclass(sgd_icp.IoError, sgd_icp.Error) and issubclass(sgd_icp.IoError, OSError)
    assert sgd_icp.FormatError.__module__ == "sgd_icp"
