"""bench/soak_odometry.py: the back-and-forth order, the folder of links, the block statistics of a
report, RSS at the block ends, and the check's targets, on fake reports and a fake CLI (the real
run is CI's soak stage)."""

from __future__ import annotations

import importlib.util
import sys
import types

import pytest

from conftest import REPO_ROOT

SCRIPT = REPO_ROOT / "bench" / "soak_odometry.py"
HEADER = ("frame,file,failed,recovered,start,converged,iterations,source_points,map_points,"
          "overlap,inlier_ratio,inlier_rmse_m,threshold_m,index_build_ms,time_ms,constraint_ratio,"
          "doubtful,message\n")


@pytest.fixture(scope="module")
def so():
    spec = importlib.util.spec_from_file_location("soak_odometry_under_test", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def test_back_and_forth_order(so):
    assert so.back_and_forth(4) == [0, 1, 2, 3, 2, 1]
    assert so.played(4, 14) == [0, 1, 2, 3, 2, 1, 0, 1, 2, 3, 2, 1, 0, 1]
    order = so.played(77, 1000)
    assert len(so.back_and_forth(77)) == 152
    assert all(a != b for a, b in zip(order, order[1:]))  # no frame twice in a row at the turns
    assert all(abs(a - b) == 1 for a, b in zip(order, order[1:]))  # a continuous path
    assert set(order) == set(range(77))


def test_block_ends(so):
    assert so.block_ends(2000, 1000) == [1000, 2000]
    assert so.block_ends(2500, 1000) == [1000, 2000, 2500]
    assert so.block_ends(7, 10) == [7]


def test_percentile_interpolates_as_numpy(so):
    values = [float(v) for v in range(1, 101)]
    assert so.percentile(values, 50) == pytest.approx(50.5)
    assert so.percentile(values, 95) == pytest.approx(95.05)
    assert so.percentile([3.0, 1.0, 2.0, 4.0], 50) == pytest.approx(2.5)
    assert so.percentile([7.0], 95) == 7.0


def report_row(k: int, failed: bool, map_points: int, time_ms: float, message: str) -> str:
    return (f'{k},{k:06d}.bin,{int(failed)},0,prediction,{int(not failed)},80,4000,{map_points},'
            f'0.9,0.9,0.01,0.2,0,{time_ms},"{message}"\n')


def test_block_statistics_from_a_fake_report(so, tmp_path):
    # 5 frames a block; frame 5 (the first block's last) and frame 7 are lost, with messages
    # that hold commas; times 10, 20, ..., 100 ms.
    report = tmp_path / "report.csv"
    report.write_text(HEADER + "".join(
        report_row(k, k in (4, 6), 1000 * (k + 1), 10.0 * (k + 1),
                   "lost: no start registered it (prediction: overlap 0.1, global: ambiguous)"
                   if k in (4, 6) else "converged")
        for k in range(10)))
    frames = so.report_frames(report)
    assert len(frames) == 10 and [f.failed for f in frames].count(True) == 2
    blocks = so.make_blocks(frames, [50.0, 51.5], 5)
    assert [(b.first, b.last) for b in blocks] == [(1, 5), (6, 10)]
    assert [b.rss_mb for b in blocks] == [50.0, 51.5]
    assert [b.median_ms for b in blocks] == [30.0, 80.0]
    assert blocks[0].p95_ms == pytest.approx(48.0)
    assert blocks[0].map_points == 4000  # frame 5 is lost: the map of the last registered one
    assert blocks[1].map_points == 10000
    assert [b.lost for b in blocks] == [1, 1]


def test_rss_at_block_ends_is_the_first_sample_at_or_after_each(so):
    samples = [(0, 10.0), (3, 11.0), (5, 12.0), (9, 13.0)]
    assert so.rss_at(samples, [4, 8, 10]) == [12.0, 13.0, 13.0]  # 10: the last sample taken
    assert so.rss_at(samples, [5]) == [12.0]


def fake_run(so, blocks: int, per_block: int = 100, rss=None, time_ms=None, map_points=None,
             failed=()):
    """A run of blocks x per_block frames: RSS at the block ends, each block's frame time and
    map size from the given lists (steady when not given), frames in `failed` lost."""
    rss = rss or [80.0] * blocks
    time_ms = time_ms or [50.0] * blocks
    map_points = map_points or [100000] * blocks
    frames = [so.Frame(k in failed, time_ms[k // per_block], map_points[k // per_block])
              for k in range(blocks * per_block)]
    run = so.Run(frames, rss, max(rss), 60.0)
    made = so.make_blocks(frames, rss, per_block)
    return made, so.totals(made, run), run


def test_check_passes_a_steady_run(so):
    _, total, run = fake_run(so, 4, rss=[80.0, 85.0, 86.0, 87.0])
    assert so.check(total, 400, run) == []
    assert total["rss_growth_mb"] == pytest.approx(7.0)


def test_check_fails_a_growing_rss(so):
    _, total, run = fake_run(so, 6, rss=[80.0 + 5 * i for i in range(6)])  # a leak: +25 MB
    failures = so.check(total, 600, run)
    assert len(failures) == 1 and "RSS grew 25.0 MB" in failures[0]


def test_check_fails_a_failed_frame(so):
    blocks, total, run = fake_run(so, 3, failed={250})
    failures = so.check(total, 300, run)
    assert len(failures) == 1 and "1 frames lost" in failures[0]
    assert [b.lost for b in blocks] == [0, 0, 1]


def test_check_fails_a_growing_time_against_block_2(so):
    # Block 1 (the map filling) is slower; block 2 is the reference from three blocks on.
    _, total, run = fake_run(so, 3, time_ms=[90.0, 50.0, 70.0])
    assert total["time_reference_block"] == 2 and total["time_ratio"] == pytest.approx(1.4)
    assert any("1.40x block 2's" in f for f in so.check(total, 300, run))
    _, total, run = fake_run(so, 3, time_ms=[90.0, 50.0, 60.0])
    assert so.check(total, 300, run) == []


def test_with_two_blocks_time_is_compared_with_block_1(so):
    _, total, run = fake_run(so, 2, time_ms=[50.0, 70.0])
    assert total["time_reference_block"] == 1 and total["time_ratio"] == pytest.approx(1.4)
    assert len(so.check(total, 200, run)) == 1


def test_check_fails_a_growing_map(so):
    _, total, run = fake_run(so, 3, map_points=[100000, 105000, 111000])
    failures = so.check(total, 300, run)
    assert len(failures) == 1 and "1.110x" in failures[0]
    _, total, run = fake_run(so, 3, map_points=[100000, 105000, 110000])
    assert so.check(total, 300, run) == []


def test_links_play_the_sequence_back_and_forth(so, tmp_path):
    scans = tmp_path / "data" / "balm_handheld_lidar" / "scans"
    scans.mkdir(parents=True)
    for i in range(4):
        (scans / f"{100 + i:06d}.bin").write_bytes(bytes([i]))
    out = tmp_path / "out"
    folder = so.link_frames("handheld", tmp_path / "data", out, 9)
    links = sorted(folder.iterdir())
    assert [p.name for p in links] == [f"{k:06d}.bin" for k in range(9)]
    assert [p.read_bytes()[0] for p in links] == [0, 1, 2, 3, 2, 1, 0, 1, 2]
    folder = so.link_frames("handheld", tmp_path / "data", out, 3)  # a shorter run after it
    assert len(list(folder.iterdir())) == 3


def test_sevenscenes_links_are_a_sevenscenes_folder(so, tmp_path):
    data = tmp_path / "data" / "sevenscenes_redkitchen"
    data.mkdir(parents=True)
    for i in range(3):
        (data / f"frame-{i:06d}.depth.png").write_bytes(bytes([i]))
        (data / f"frame-{i:06d}.pose.txt").write_text("pose")
    (data / "camera-intrinsics.txt").write_text("585 0 320\n0 585 240\n0 0 1\n")
    folder = so.link_frames("sevenscenes", tmp_path / "data", tmp_path / "out", 5)
    names = sorted(p.name for p in folder.iterdir())
    assert names == ["camera-intrinsics.txt"] + [f"frame-{k:06d}.depth.png" for k in range(5)]
    played = [(folder / f"frame-{k:06d}.depth.png").read_bytes()[0] for k in range(5)]
    assert played == [0, 1, 2, 1, 0]


def fake_cli(tmp_path, rows: int, exit_status: int, layout: str = "clouds"):
    """An executable that writes a report of `rows` frames, one every 10 ms, prints a summary
    with `layout` and exits with `exit_status` (a run that dies midway, as at frame 1534 once)."""
    script = tmp_path / "fake-sgdicp"
    script.write_text(f"""#!{sys.executable}
import sys, time
report = open(sys.argv[sys.argv.index("--report") + 1], "w")
report.write({HEADER!r})
report.flush()
for k in range({rows}):
    report.write(f"{{k}},{{k:06d}}.bin,0,0,prediction,1,80,4000,{{1000 * k}},0.9,0.9,0.01,0.2,0,40,"
                 '"converged"\\n')
    report.flush()
    time.sleep(0.01)
print("method: sgd, layout: {layout}, voxel 0.2 m")
if {exit_status}:
    print("Segmentation fault", file=sys.stderr)
sys.exit({exit_status})
""")
    script.chmod(0o755)
    return script


def test_a_cli_run_that_dies_midway_fails(so, tmp_path, monkeypatch):
    monkeypatch.setattr(so, "POLL_S", 0.02)
    cli = fake_cli(tmp_path, 25, 3)
    run = so.run_cli(cli, tmp_path, tmp_path / "work", "handheld", 30, 10)
    assert len(run.frames) == 25 and "exit status 3" in run.error and "Segmentation" in run.error
    assert len(run.rss_mb) == 3 and run.peak_rss_mb > 0 and run.wall_s > 0.2
    blocks = so.make_blocks(run.frames, run.rss_mb, 10)
    failures = so.check(so.totals(blocks, run), 30, run)
    assert any("did 25 of 30" in f for f in failures)


def test_a_cli_run_of_the_wrong_layout_fails(so, tmp_path, monkeypatch):
    monkeypatch.setattr(so, "POLL_S", 0.02)
    run = so.run_cli(fake_cli(tmp_path, 20, 0, "clouds"), tmp_path, tmp_path / "w", "sevenscenes",
                     20, 10)
    assert len(run.frames) == 20 and run.layout == "clouds" and "not '7scenes'" in run.error
    run = so.run_cli(fake_cli(tmp_path, 20, 0, "7scenes"), tmp_path, tmp_path / "w", "sevenscenes",
                     20, 10)
    assert run.error == "" and [f.map_points for f in run.frames][-1] == 19000


class FakeOdometry:
    """sgd_icp.Odometry's interface as the soak uses it; frame k takes k ms."""

    def __init__(self):
        self.reports = []

    def register_frame(self, points):
        self._report(False, "converged")

    def skip_frame(self, message):
        self._report(True, message)

    def _report(self, failed, message):
        k = len(self.reports)
        self.reports.append(types.SimpleNamespace(failed=failed, time_ms=float(k),
                                                  map_points=100 * k, message=message))

    @property
    def last_report(self):
        return self.reports[-1]


def test_python_mode_reads_with_the_clis_depth_settings(so, tmp_path, monkeypatch):
    reads = []

    def read_depth_image(path, intrinsics, **settings):
        reads.append((path.name, intrinsics.name, settings))
        if path.name == "frame-000002.depth.png":
            raise OSError("truncated PNG")
        return [[0.0, 0.0, 1.0]]

    fake = types.SimpleNamespace(Odometry=FakeOdometry, read_depth_image=read_depth_image,
                                 read_points=None)
    monkeypatch.setitem(sys.modules, "sgd_icp", fake)
    for i in range(6):
        (tmp_path / f"frame-{i:06d}.depth.png").write_bytes(b"")
    run = so.run_python(tmp_path, "sevenscenes", 5, 2)
    assert [r[0] for r in reads] == [f"frame-{i:06d}.depth.png" for i in range(5)]
    assert all(r[1] == "camera-intrinsics.txt" and r[2] == so.CLI_DEPTH for r in reads)
    assert [f.failed for f in run.frames] == [False, False, True, False, False]
    assert len(run.rss_mb) == 3 and run.peak_rss_mb >= max(run.rss_mb) > 0
    blocks = so.make_blocks(run.frames, run.rss_mb, 2)
    assert [b.lost for b in blocks] == [0, 1, 0] and blocks[1].map_points == 300


def test_check_needs_two_blocks(so, monkeypatch, capsys):
    monkeypatch.setattr(sys, "argv", ["soak_odometry.py", "--sequence", "handheld", "--frames",
                                      "1000", "--check"])
    with pytest.raises(SystemExit):
        so.parse_args()
    assert "two blocks" in capsys.readouterr().err
    monkeypatch.setattr(sys, "argv", ["soak_odometry.py", "--sequence", "handheld", "--frames",
                                      "2000", "--check"])
    args = so.parse_args()
    assert (args.frames, args.block, args.check, args.python) == (2000, 1000, True, False)


def test_heap_in_use_follows_a_live_allocation_and_its_release(so):
    before = so.heap_in_use_mb()
    if before != before:  # NaN: not glibc 2.33+
        pytest.skip("mallinfo2 is not available")
    buffer = bytearray(64 * 2**20)
    held = so.heap_in_use_mb()
    del buffer
    after = so.heap_in_use_mb()
    assert held - before > 60.0
    assert held - after > 60.0
