"""bench/compare_odometry.py: which frames a run reads (every step-th, at random steps with a seed,
backwards) and the metrics it reports, on synthetic trajectories with known errors."""

from __future__ import annotations

import importlib.util
import sys

import numpy as np
import pytest

from conftest import REPO_ROOT

SCRIPT = REPO_ROOT / "bench" / "compare_odometry.py"


@pytest.fixture(scope="module")
def co():
    spec = importlib.util.spec_from_file_location("compare_odometry_under_test", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def test_every_step_th_frame(co):
    assert co.frame_indices(10, 1, None) == list(range(10))
    assert co.frame_indices(10, 3, None) == [0, 3, 6, 9]


def test_irregular_steps_are_seeded_and_within_the_step(co):
    a = co.frame_indices(600, 6, 1)
    assert a == co.frame_indices(600, 6, 1)  # reproducible
    assert a != co.frame_indices(600, 6, 2)  # another seed, other frames
    gaps = np.diff(a)
    assert a[0] == 0 and a[-1] < 600 and a[-1] >= 600 - 6
    assert gaps.min() >= 1 and gaps.max() <= 6
    assert len(set(gaps.tolist())) == 6  # every gap 1-6 drawn over ~170 draws


def poses_along_x(count: int, step_m: float) -> np.ndarray:
    P = np.tile(np.eye(4), (count, 1, 1))
    P[:, 0, 3] = step_m * np.arange(count)
    return P


def test_open_sequence_picks_reverses_and_starts_at_the_identity(co, tmp_path):
    (tmp_path / "scans").mkdir()
    for i in range(8):
        (tmp_path / "scans" / f"{i:06d}.bin").write_bytes(b"")
    np.savetxt(tmp_path / "poses.txt", poses_along_x(8, 1.0)[:, :3, :].reshape(8, 12))
    seq = co.open_sequence(tmp_path, 3, 0, reverse=True)
    assert [f.name for f in seq.files] == ["000006.bin", "000003.bin", "000000.bin"]
    assert seq.name.endswith("every 3 reversed")
    np.testing.assert_allclose(seq.reference[0], np.eye(4), atol=1e-12)
    np.testing.assert_allclose(seq.reference[:, 0, 3], [0.0, -3.0, -6.0], atol=1e-12)
    irregular = co.open_sequence(tmp_path, 3, 0, irregular_seed=5)
    assert [int(f.stem) for f in irregular.files] == co.frame_indices(8, 3, 5)
    assert "every 1-3 (seed 5)" in irregular.name


def test_metrics_of_a_known_error(co):
    ref = poses_along_x(11, 0.1)  # 1 m along x
    assert co.metrics(ref, ref)["lost"] == 0
    assert co.metrics(ref, ref)["end_percent"] == pytest.approx(0.0, abs=1e-9)
    est = ref.copy()
    est[:, 1, 3] = 0.001 * np.arange(11)  # 1 mm a frame sideways: 1 cm at the end of 1 m
    m = co.metrics(est, ref)
    assert m["rpe_t_median_m"] == pytest.approx(0.001, rel=1e-9)
    assert m["end_percent"] == pytest.approx(1.0, rel=1e-9)
    est[5, 0, 3] += 0.5  # one frame half a metre off: the two motions around it are lost
    assert co.metrics(est, ref)["lost"] == 2
