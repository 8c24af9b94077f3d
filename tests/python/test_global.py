"""register(init="global"): no initial guess (docs/global.md). The car scans turned by 150 deg
are solved, Python and the CLI give the same result, a plane gives no reliable solution, and
wrong uses are refused. The global_* keywords (the global settings table, the CLI's --global-*
options) reach the estimate, and a wrong one is refused naming it."""

from __future__ import annotations

import json
import re
import subprocess

import numpy as np
import pytest

import sgd_icp
from conftest import find_cli, make_transform, synthetic_scene, transformed


def rotation_error_deg(T: np.ndarray, T_gt: np.ndarray) -> float:
    c = (np.trace(T[:3, :3].T @ T_gt[:3, :3]) - 1) / 2
    return float(np.degrees(np.arccos(np.clip(c, -1, 1))))


# 150 deg about a tilted axis, the protocol (60-180 deg): beyond any local basin.
T_TURN = make_transform(np.radians(40), np.radians(-30), np.radians(150), (1.0, -0.5, 0.2))


def test_turned_car_scans_are_solved(car_pair):
    _, _, source, reference, T_gt = car_pair
    r = sgd_icp.register(transformed(source, T_TURN), reference, init="global")
    T_true = T_gt @ np.linalg.inv(T_TURN)
    assert r.global_init and r.global_reliable and not r.global_ambiguous, r.message
    assert r.global_score > r.global_runner_up_score
    assert np.linalg.norm(r.T_reference_source[:3, 3] - T_true[:3, 3]) < 0.05
    assert rotation_error_deg(r.T_reference_source, T_true) < 1.0
    # From the same turned start the local registration alone does not get there.
    local = sgd_icp.register(transformed(source, T_TURN), reference)
    assert not local.global_init
    assert rotation_error_deg(local.T_reference_source, T_true) > 1.0


def test_same_result_as_the_cli(car_pair, tmp_path):
    cli = find_cli()
    if cli is None:
        pytest.skip("sgdicp CLI not found (set SGDICP_BIN or build it with scripts/build.sh)")
    _, reference_path, source, reference, _ = car_pair
    turned = transformed(source, T_TURN).astype(np.float32)
    path = tmp_path / "turned.ply"
    sgd_icp.write_points(path, turned)
    out = subprocess.run([str(cli), "register", str(path), str(reference_path), "--init", "global",
                          "--json"], capture_output=True, text=True, timeout=120, check=True)
    expected = json.loads(out.stdout)
    r = sgd_icp.register(sgd_icp.read_points(path), reference, init="global")
    for field in ("global_reliable", "global_winner_rank", "global_hypotheses", "global_score",
                  "global_runner_up_score", "iterations"):
        assert getattr(r, field) == expected[field], field
    np.testing.assert_allclose(r.T_reference_source, np.array(expected["transform"]), rtol=0,
                               atol=1e-12)


def test_reference_index_and_seed_give_the_same_result():
    reference = synthetic_scene(3, 20000)
    source = transformed(synthetic_scene(4, 20000), T_TURN)
    index = sgd_icp.ReferenceIndex(reference)
    a = sgd_icp.register(source, index, init="global", seed=5)
    b = sgd_icp.register(source, index, init="global", seed=5)
    np.testing.assert_array_equal(a.T_reference_source, b.T_reference_source)
    assert a.global_reliable, a.message


def test_plane_has_no_reliable_solution():
    rng = np.random.default_rng(1)
    plane = np.c_[rng.uniform(-5, 5, (4000, 2)), np.zeros(4000)].astype(np.float32)
    r = sgd_icp.register(transformed(plane, T_TURN), plane, init="global")
    assert not r.global_reliable
    assert "no reliable global solution" in r.message


def test_wrong_uses_are_refused(scene):
    source, reference, _ = scene
    with pytest.raises(sgd_icp.InvalidInputError, match="or 'global', got 'globl'"):
        sgd_icp.register(source, reference, init="globl")
    with pytest.raises(sgd_icp.InvalidSettingsError, match="only with an SGD method"):
        sgd_icp.register(source, reference, init="global", method="icp")


# ---- the global_* keywords: the global settings table, as the CLI's --global-* options


def test_global_keywords_reach_the_estimate():
    reference = synthetic_scene(3, 20000)
    source = transformed(synthetic_scene(4, 20000), T_TURN)
    assert sgd_icp.register(source, reference, init="global").global_reliable
    # More feature-grid points asked for than the clouds have: the estimate stops, and says why.
    r = sgd_icp.register(source, reference, init="global", global_min_points=1_000_000)
    assert not r.global_reliable
    assert "at least 1000000 each needed" in r.message, r.message


@pytest.mark.parametrize(
    "keywords, error, match",
    [
        ({"global_confidence": 1.0}, sgd_icp.InvalidSettingsError,
         r"^global_confidence=1: must be in \(0, 1\)$"),
        ({"global_feature_radius": -2}, sgd_icp.InvalidSettingsError,
         r"^global_feature_radius=-2: must be in \(0, 1000\] voxels$"),
        ({"global_min_points": -1}, sgd_icp.InvalidSettingsError, "global_min_points must be >= 0"),
        ({"global_min_points": 1.5}, TypeError, "global_min_points must be an integer, got float"),
        ({"global_min_point": 50}, TypeError,
         r"unknown setting 'global_min_point'; the keywords of register\(init='global'\) are: "
         r"global_feature_points, .*global_min_points"),
    ],
)
def test_global_keyword_errors_name_the_keyword(scene, keywords, error, match):
    source, reference, _ = scene
    with pytest.raises(error, match=match):
        sgd_icp.register(source, reference, init="global", **keywords)


def test_global_keywords_need_init_global(scene):
    source, reference, _ = scene
    with pytest.raises(sgd_icp.InvalidSettingsError,
                       match=r"^global_min_points=50: only with init='global'$"):
        sgd_icp.register(source, reference, global_min_points=50)
    # An index for a global registration: the keywords are checked and change nothing.
    index = sgd_icp.ReferenceIndex.for_registration(reference, global_min_points=50)
    assert len(index) == len(sgd_icp.ReferenceIndex.for_registration(reference))
    with pytest.raises(sgd_icp.InvalidSettingsError, match="global_min_points=2"):
        sgd_icp.ReferenceIndex.for_registration(reference, global_min_points=2)


def test_global_keywords_are_the_cli_options_and_documented():
    keywords = [k for k, *_ in sgd_icp._core._settings_keywords("global")]
    assert keywords[0] == "global_feature_points" and "global_min_points" in keywords
    doc = sgd_icp.register.__doc__
    assert "global_feature_points (3000, [10, 10000000])" in doc
    assert "global_feature_radius (5.0, (0, 1000])" in doc
    cli = find_cli()
    if cli is None:
        pytest.skip("sgdicp CLI not found (set SGDICP_BIN or build it with scripts/build.sh)")
    help_text = subprocess.run([str(cli), "register", "--help-all"], capture_output=True, text=True,
                               timeout=60, check=True).stdout
    options = re.findall(r"--(global-[a-z-]+)", help_text)
    assert sorted(set(options)) == sorted(k.replace("_", "-") for k in keywords)
