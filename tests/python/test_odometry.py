"""sgd_icp.Odometry: a synthetic sequence with exact poses, failures, keywords, and the same
trajectory as `sgdicp odometry` on the KITTI scans."""

from __future__ import annotations

import subprocess

import numpy as np
import pytest

import sgd_icp
from conftest import find_cli, make_transform, shared_data_dir

KITTI = shared_data_dir() / "kitti_odometry_seq00"


def world(rng: np.random.Generator, n: int) -> np.ndarray:
    """A 30 x 12 x 3 m room with 10 pillars (radius 0.3 m): floor, walls, pillars."""
    kind = rng.integers(0, 4, n)
    a, b, c = rng.random(n), rng.random(n), rng.random(n)
    p = np.c_[-5 + 30 * a, -6 + 12 * b, np.zeros(n)]
    walls = kind == 1
    p[walls, 1] = np.where(b[walls] < 0.5, -6.0, 6.0)
    p[walls, 2] = 3 * c[walls]
    pillars = kind >= 2
    k = (10 * a[pillars]).astype(int)
    th = 2 * np.pi * b[pillars]
    p[pillars] = np.c_[
        -3 + 3.2 * k + 0.3 * np.cos(th), np.where(k % 2, 3.0, -3.5) + 0.3 * np.sin(th), 3 * c[pillars]
    ]
    return p


def sequence(frames: int, seed: int = 1) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Frames in the sensor frame (a fresh sample of the world each) and their exact poses."""
    rng = np.random.default_rng(seed)
    T = make_transform(0, 0, 0, (0, 0, 1.2))
    T0_inv = np.linalg.inv(T)
    clouds, poses = [], []
    for f in range(frames):
        p = world(rng, 30000)
        local = (p - T[:3, 3]) @ T[:3, :3]
        local = local[np.linalg.norm(local, axis=1) < 12.0][:8000]
        clouds.append((local + rng.normal(0, 0.005, local.shape)).astype(np.float32))
        poses.append(T0_inv @ T)
        T = T @ make_transform(0, 0, np.radians(1.0), (0.3 * (1 + 0.2 * np.sin(0.3 * f)), 0, 0))
    return clouds, poses


def test_synthetic_sequence_follows_the_truth():
    clouds, truth = sequence(15)
    odometry = sgd_icp.Odometry()
    for cloud in clouds:
        odometry.register_frame(cloud)
    assert len(odometry) == 15
    assert odometry.poses.shape == (15, 4, 4)
    np.testing.assert_allclose(odometry.poses[0], np.eye(4))
    assert not any(r.failed for r in odometry.reports)
    end_error = np.linalg.inv(truth[-1]) @ odometry.poses[-1]
    assert np.linalg.norm(end_error[:3, 3]) < 0.05  # 4 m travelled
    assert 0 < odometry.voxel_size < 0.2
    assert odometry.map_points > 0


def test_a_voxel_from_a_close_first_frame_grows_with_the_frames_range():
    clouds, truth = sequence(6)
    first = clouds[0][np.linalg.norm(clouds[0], axis=1) < 5.0]  # a sensor starting near a wall
    odometry = sgd_icp.Odometry()
    odometry.register_frame(first)
    small = odometry.voxel_size
    for cloud in clouds[1:]:
        odometry.register_frame(cloud)
    assert small < 0.05
    assert odometry.voxel_size > 2 * small  # 1 % of the 12 m frames
    assert "range grew" in odometry.reports[1].message
    assert not any(r.failed for r in odometry.reports)
    end_error = np.linalg.inv(truth[-1]) @ odometry.poses[-1]
    assert np.linalg.norm(end_error[:3, 3]) < 0.05


def test_an_empty_frame_fails_and_gets_the_prediction():
    clouds, _ = sequence(3)
    odometry = sgd_icp.Odometry()
    for cloud in clouds:
        odometry.register_frame(cloud)
    T1, T2 = odometry.poses[1], odometry.poses[2]
    T3 = odometry.register_frame(np.zeros((0, 3)))
    report = odometry.last_report
    assert report.failed and report.index == 3
    assert "no point" in report.message
    np.testing.assert_allclose(T3, T2 @ np.linalg.inv(T1) @ T2, atol=1e-9)
    T4 = odometry.skip_frame("unreadable")
    assert odometry.last_report.message == "unreadable"
    assert T4.shape == (4, 4)


def test_a_place_paced_back_and_forth_fills_the_map_and_never_raises():
    """Two views of one place, back and forth, one point per voxel: the map's voxels fill and
    frames soon add no point. Such a frame used to end the map's normals, and the next one raised
    InvalidInputError ("needs reference normals"); now every frame registers."""
    clouds, truth = sequence(2)
    odometry = sgd_icp.Odometry(max_points_per_voxel=1)
    sizes = []
    for k in range(8):
        odometry.register_frame(clouds[k % 2])
        assert not odometry.last_report.failed, odometry.last_report.message
        sizes.append(odometry.map_points)
    assert sizes[-1] == sizes[-3]  # the last frames added no point
    np.testing.assert_allclose(odometry.poses[-1][:3, 3], truth[1][:3, 3], atol=0.02)


def test_a_frame_of_another_scene_is_lost_counted_and_kept_out_of_the_map():
    clouds, truth = sequence(7)
    odometry = sgd_icp.Odometry()
    for cloud in clouds[:4]:
        odometry.register_frame(cloud)
    map_points = odometry.map_points
    rng = np.random.default_rng(2)
    ball = rng.normal(size=(6000, 3))
    odometry.register_frame((2.0 * ball / np.linalg.norm(ball, axis=1, keepdims=True)).astype(np.float32))
    lost = odometry.last_report
    assert lost.failed and "lost" in lost.message and not lost.recovered
    assert lost.overlap == 0.0
    assert odometry.map_points == map_points
    for cloud in clouds[4:]:
        odometry.register_frame(cloud)
        assert not odometry.last_report.failed, odometry.last_report.message
    assert odometry.lost_frames == 1
    assert odometry.recovered_frames == sum(r.recovered for r in odometry.reports)
    assert {r.start for r in odometry.reports} <= {"prediction", "last pose", "wide basin"}
    end_error = np.linalg.inv(truth[-1]) @ odometry.poses[-1]
    assert np.linalg.norm(end_error[:3, 3]) < 0.05


def test_the_map_as_an_array():
    clouds, _ = sequence(4)
    odometry = sgd_icp.Odometry()
    assert odometry.map_cloud().shape == (0, 3)
    for cloud in clouds:
        odometry.register_frame(cloud)
    full = odometry.map_cloud()
    assert full.shape == (odometry.map_points, 3) and full.dtype == np.float32
    assert np.isfinite(full).all()
    thin = odometry.map_cloud(voxel_size=0.5)
    assert 0 < len(thin) < len(full)
    with pytest.raises(sgd_icp.InvalidSettingsError, match="voxel_size"):
        odometry.map_cloud(voxel_size=-1.0)
    with pytest.raises(sgd_icp.InvalidSettingsError, match="voxel_size"):
        odometry.map_cloud(voxel_size=float("nan"))


def test_the_whole_map_keeps_what_the_local_map_drops():
    clouds, _ = sequence(8)
    odometry = sgd_icp.Odometry(max_range=6.0)
    assert odometry.whole_map().shape == (0, 3)
    with pytest.raises(sgd_icp.InvalidSettingsError, match="voxel size"):
        odometry.keep_whole_map(voxel_size=-1.0)
    odometry.keep_whole_map(voxel_size=0.2)
    for cloud in clouds:
        odometry.register_frame(cloud)
    whole = odometry.whole_map()
    assert whole.dtype == np.float32 and np.isfinite(whole).all()
    # One point per 0.2 m voxel, and more of them than the local map, which forgot the first
    # frames' far side.
    keys = np.floor(whole.astype(np.float64) / 0.2).astype(np.int64)
    assert len(np.unique(keys, axis=0)) == len(whole)
    assert len(whole) > len(odometry.map_cloud(voxel_size=0.2))


def test_keywords_are_the_cli_options():
    odometry = sgd_icp.Odometry(method="icp", voxel_size=0.5, max_points_per_voxel=5, max_iterations=30)
    assert odometry.method == "icp"
    with pytest.raises(sgd_icp.InvalidSettingsError, match="max_range"):
        sgd_icp.Odometry(max_range=0.0)
    with pytest.raises(sgd_icp.InvalidSettingsError, match="min_range"):
        sgd_icp.Odometry(min_range=200.0)
    with pytest.raises(TypeError):
        sgd_icp.Odometry(no_such_setting=1)
    with pytest.raises(TypeError):
        sgd_icp.Odometry(voxel_size="big")
    with pytest.raises(sgd_icp.InvalidSettingsError):
        sgd_icp.Odometry(method="nope")
    # The odometry thins frames and map itself: the registration's grid is refused, not ignored.
    with pytest.raises(sgd_icp.InvalidSettingsError, match="downsample_to"):
        sgd_icp.Odometry(downsample_to=5000)


def test_each_frame_carries_the_covariance_of_its_pose():
    """uncertainty= gives every registered frame the (6, 6) covariance of its pose relative to the
    map: zeros for the first, NaN for a frame without one; without it, NaN everywhere."""
    clouds, _ = sequence(4)
    odometry = sgd_icp.Odometry(uncertainty="laplace")
    for cloud in clouds:
        odometry.register_frame(cloud)
    odometry.register_frame(np.zeros((0, 3)))
    reports = odometry.reports
    first = reports[0].covariance
    assert first.shape == (6, 6) and first.dtype == np.float64
    assert (first == 0).all()
    for report in reports[1:4]:
        assert not report.failed, report.message
        c = report.covariance
        assert c.shape == (6, 6) and np.isfinite(c).all()
        np.testing.assert_allclose(c, c.T, rtol=1e-12, atol=0)
        assert np.linalg.eigvalsh(c).min() > 0
        assert np.sqrt(c[0, 0]) < 0.01  # metres: millimetres for 8000 points with 5 mm noise
    assert reports[4].failed and np.isnan(reports[4].covariance).all()

    plain = sgd_icp.Odometry()
    for cloud in clouds[:2]:
        plain.register_frame(cloud)
    assert all(r.covariance.shape == (6, 6) and np.isnan(r.covariance).all() for r in plain.reports)
    # A batch method estimates none: its keyword is refused.
    with pytest.raises(TypeError, match="SGD methods only"):
        sgd_icp.Odometry(method="icp", uncertainty="laplace")


def test_a_fixed_max_distance_turns_the_adaptive_threshold_off():
    clouds, _ = sequence(3)
    fixed = sgd_icp.Odometry(max_distance=0.5, max_distance_unit="m")
    adaptive = sgd_icp.Odometry()
    for cloud in clouds:
        fixed.register_frame(cloud)
        adaptive.register_frame(cloud)
    assert fixed.reports[2].threshold_m == 0.0
    assert adaptive.reports[2].threshold_m > 0.0


@pytest.mark.skipif(not (KITTI / "velodyne").is_dir(), reason="no KITTI scans in ../shared/data")
def test_cli_and_python_give_the_same_trajectory(tmp_path):
    cli = find_cli()
    if cli is None:
        pytest.skip("no sgdicp binary (set SGDICP_BIN)")
    out = tmp_path / "poses.txt"
    subprocess.run([str(cli), "odometry", str(KITTI), "--poses-out", str(out), "-q"], check=True,
                   capture_output=True)
    cli_poses = np.loadtxt(out).reshape(-1, 3, 4)
    odometry = sgd_icp.Odometry()
    for f in sorted((KITTI / "velodyne").glob("*.bin")):
        odometry.register_frame(sgd_icp.read_points(f))
    np.testing.assert_allclose(odometry.poses[:, :3, :], cli_poses, atol=1e-6)


@pytest.mark.skipif(not (KITTI / "velodyne").is_dir(), reason="no KITTI scans in ../shared/data")
def test_a_chosen_step_rule_is_used_from_every_start(tmp_path):
    """Tracking takes Gauss-Newton steps unless a step rule is given: `--optimizer adam` and
    optimizer="adam" then give Adam's trajectory, the same in the CLI and in Python, and not the
    default's."""
    cli = find_cli()
    if cli is None:
        pytest.skip("no sgdicp binary (set SGDICP_BIN)")
    out = tmp_path / "poses.txt"
    subprocess.run([str(cli), "odometry", str(KITTI), "--poses-out", str(out), "-q",
                    "--optimizer", "adam"], check=True, capture_output=True)
    cli_poses = np.loadtxt(out).reshape(-1, 3, 4)
    adam, default = sgd_icp.Odometry(optimizer="adam"), sgd_icp.Odometry()
    for f in sorted((KITTI / "velodyne").glob("*.bin")):
        cloud = sgd_icp.read_points(f)
        adam.register_frame(cloud)
        default.register_frame(cloud)
    np.testing.assert_allclose(adam.poses[:, :3, :], cli_poses, atol=1e-6)
    assert np.abs(default.poses - adam.poses).max() > 1e-6


HANDHELD = shared_data_dir() / "balm_handheld_lidar"


def handheld_scans(indices: list[int]) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """The hand-held LiDAR's scans `indices` and their reference poses T_world_scan."""
    names = sorted((HANDHELD / "scans").iterdir())
    rows = np.loadtxt(HANDHELD / "poses.txt")
    poses = []
    for i in indices:
        T = np.eye(4)
        T[:3, :] = rows[i].reshape(3, 4)
        poses.append(T)
    return [sgd_icp.read_point_cloud(names[i]).points for i in indices], poses


@pytest.mark.skipif(not (HANDHELD / "poses.txt").is_file() or not (KITTI / "velodyne").is_dir(),
                    reason="no hand-held LiDAR or KITTI scans in ../shared/data")
def test_a_localizer_places_frames_in_a_fixed_map_and_loses_what_it_does_not_hold():
    even, even_poses = handheld_scans([0, 2, 4, 6, 8, 10])
    odd, odd_poses = handheld_scans([1, 3, 5, 7, 9])
    world = np.vstack([p @ T[:3, :3].T + T[:3, 3] for p, T in zip(even, even_poses)])
    localizer = sgd_icp.Localizer(world)
    assert isinstance(localizer, sgd_icp.Odometry) and localizer.map_build_ms == 0.0
    for scan in odd[:2]:
        localizer.register_frame(scan)
    localizer.register_frame(sgd_icp.read_point_cloud(KITTI / "velodyne" / "000000.bin").points)
    assert localizer.last_report.failed
    for scan in odd[2:]:
        localizer.register_frame(scan)
    reports = localizer.reports
    assert reports[0].start == "global" and not reports[0].recovered
    assert localizer.lost_frames == 1 and localizer.map_build_ms > 0.0
    placed = [k for k in range(len(reports)) if k != 2]
    for k, T in zip(placed, odd_poses):
        assert np.linalg.norm(localizer.poses[k][:3, 3] - T[:3, 3]) < 0.05, reports[k].message
    # From a pose given: the first frame starts there.
    from_init = sgd_icp.Localizer(world, init=odd_poses[0])
    from_init.register_frame(odd[0])
    assert from_init.last_report.start == "prediction"
    assert np.linalg.norm(from_init.poses[0][:3, 3] - odd_poses[0][:3, 3]) < 0.05
    with pytest.raises(sgd_icp.InvalidInputError, match="no finite point"):
        sgd_icp.Localizer(np.full((5, 3), np.nan))
    with pytest.raises(sgd_icp.InvalidInputError, match="not finite"):
        sgd_icp.Localizer(world, init=np.full((4, 4), np.nan))


def test_frames_with_times_are_deskewed_and_bad_times_refused():
    clouds, _ = sequence(3)
    times = [np.linspace(0.0, 0.1, len(c)) for c in clouds]
    plain, timed, off = sgd_icp.Odometry(), sgd_icp.Odometry(), sgd_icp.Odometry(deskew="none")
    for cloud, t in zip(clouds, times):
        plain.register_frame(cloud)
        timed.register_frame(cloud, times=t)
        off.register_frame(cloud, times=t)
    # The first two frames are registered as measured; the third is deskewed by the predicted
    # motion (a sequence that moves), unless deskew="none".
    np.testing.assert_array_equal(off.poses, plain.poses)
    np.testing.assert_array_equal(timed.poses[:2], plain.poses[:2])
    assert not np.array_equal(timed.poses[2], plain.poses[2])
    with pytest.raises(sgd_icp.InvalidInputError, match="one per point"):
        timed.register_frame(clouds[0], times=np.zeros(5))
    with pytest.raises(sgd_icp.InvalidInputError, match="not finite"):
        timed.register_frame(clouds[0], times=np.full(len(clouds[0]), np.nan))
    with pytest.raises(sgd_icp.InvalidSettingsError, match="deskew mode"):
        sgd_icp.Odometry(deskew="sideways")
