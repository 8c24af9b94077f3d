"""bench/compare_peers.py --pareto / --pareto-from: the dominance rule, the front, the per-pairs-file
medians, the offline report from a runs.csv, and the plot being optional (matplotlib)."""

from __future__ import annotations

import csv
import importlib.util
import math
import sys

import pytest

from conftest import REPO_ROOT

# The fake pairs files have no voxel size of their own: the peers' warning is expected.
pytestmark = pytest.mark.filterwarnings("ignore:peers. no voxel size:UserWarning")

SCRIPT = REPO_ROOT / "bench" / "compare_peers.py"
# The columns of runs.csv the Pareto report reads (compare_peers.row_of writes more).
RUN_COLUMNS = ["pairs_file", "line", "method", "family", "rep", "status", "time_ms", "translation_error_m",
               "rotation_error_deg", "note"]


def load_compare_peers(monkeypatch=None, without_package=False):
    """The script as a module; without_package: as if the sgd_icp package were not installed."""
    if without_package:
        monkeypatch.setitem(sys.modules, "sgd_icp", None)  # `import sgd_icp` raises ImportError
    spec = importlib.util.spec_from_file_location("compare_peers_pareto_under_test", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def cp():
    return load_compare_peers()


def stat(cp, method, time_ms, r_err_deg, success, t_err_m=0.01):
    return cp.MethodStats(method=method, time_ms=time_ms, t_err_m=t_err_m, r_err_deg=r_err_deg, success=success)


def test_dominance_needs_all_three_no_worse_and_one_better(cp):
    base = stat(cp, "b", 100.0, 0.5, 0.8)
    assert not cp.dominates(stat(cp, "a", 100.0, 0.5, 0.8), base)  # a tie on all three: no
    assert not cp.dominates(base, base)
    assert cp.dominates(stat(cp, "a", 99.0, 0.5, 0.8), base)  # strictly faster only
    assert cp.dominates(stat(cp, "a", 100.0, 0.4, 0.8), base)  # strictly more precise only
    assert cp.dominates(stat(cp, "a", 100.0, 0.5, 0.9), base)  # strictly more successful only
    # Fewer successes: not dominating, however much faster and more precise.
    fewer = stat(cp, "a", 1.0, 0.01, 0.7)
    assert not cp.dominates(fewer, base) and not cp.dominates(base, fewer)
    assert not cp.dominates(stat(cp, "a", 101.0, 0.1, 1.0), base)  # slower
    assert not cp.dominates(stat(cp, "a", 50.0, 0.6, 1.0), base)  # less precise
    # The translation error is not compared.
    assert not cp.dominates(stat(cp, "a", 100.0, 0.5, 0.8, t_err_m=0.0), stat(cp, "b", 100.0, 0.5, 0.8, t_err_m=1.0))
    # No ok run (NaN medians) counts as the worst, not as a tie.
    never_ok = stat(cp, "c", 100.0, math.nan, 0.0)
    assert cp.dominates(stat(cp, "a", 100.0, 5.0, 0.0), never_ok)
    assert not cp.dominates(never_ok, stat(cp, "a", 100.0, 5.0, 0.0))
    assert cp.dominates(stat(cp, "a", 100.0, 5.0, 0.0), stat(cp, "c", math.nan, 5.0, 0.0))


def test_front_of_a_hand_made_table(cp):
    table = [
        stat(cp, "sgdicp", 10.0, 0.20, 1.0),
        stat(cp, "sgdicp_gicp", 20.0, 0.05, 1.0),
        stat(cp, "fast_sloppy", 2.0, 2.00, 0.5),    # fastest: on the front
        stat(cp, "slow_same", 30.0, 0.20, 1.0),      # slower than sgdicp, the same otherwise
        stat(cp, "twin", 10.0, 0.20, 1.0),           # ties with sgdicp: both stay on the front
        stat(cp, "precise_unreliable", 5.0, 0.01, 0.9),  # best rotation, fewer successes: front
        stat(cp, "worst", 40.0, 3.00, 0.4),          # dominated by everyone but itself
    ]
    by = cp.dominated_by(table)
    assert cp.pareto_front(table) == ["sgdicp", "sgdicp_gicp", "fast_sloppy", "twin", "precise_unreliable"]
    assert by["slow_same"] == ["sgdicp", "sgdicp_gicp", "twin"]
    assert by["worst"] == ["sgdicp", "sgdicp_gicp", "fast_sloppy", "slow_same", "twin", "precise_unreliable"]
    assert by["sgdicp"] == [] and by["twin"] == []


def run(pairs_file, method, status, time_ms, t_err_m, r_err_deg, family="fake", line=3, rep=0):
    return dict(pairs_file=pairs_file, line=line, method=method, family=family, rep=rep, status=status,
                time_ms=time_ms, translation_error_m=t_err_m, rotation_error_deg=r_err_deg, note="")


def tiny_runs() -> list[dict]:
    """Two pairs files. On `kinect`: sgdicp 2 ok runs (one above the 1 deg threshold), o3d slower
    and less precise, pcl 1 ok + 1 crash, sg_kdtree_build (build-only, left out). On `kitti`:
    sgdicp fast but imprecise, sg_gicp slower and precise, pcl timed out once."""
    nan = math.nan
    return [
        run("kinect", "sgdicp", "ok", 10.0, 0.010, 0.2),
        run("kinect", "sgdicp", "ok", 14.0, 0.030, 1.5, rep=1),
        run("kinect", "o3d_p2p_1t", "ok", 40.0, 0.020, 0.9),
        run("kinect", "o3d_p2p_1t", "ok", 60.0, 0.040, 1.1, rep=1),
        run("kinect", "pcl_icp_1t", "ok", 200.0, 0.001, 0.1),
        run("kinect", "pcl_icp_1t", "crashed", nan, nan, nan, rep=1),
        run("kinect", "sg_kdtree_build", "ok", 1.0, nan, nan, family="build-only"),
        run("kitti", "sgdicp", "ok", 100.0, 0.040, 0.8),
        run("kitti", "sg_gicp_vox_1t", "ok", 300.0, 0.010, 0.1),
        run("kitti", "pcl_icp_1t", "ok", 500.0, 0.030, 0.9),
        run("kitti", "pcl_icp_1t", "timeout", 30000.0, nan, nan, rep=1),
    ]


def write_runs_csv(folder, rows) -> None:
    with open(folder / "runs.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=RUN_COLUMNS)
        w.writeheader()
        w.writerows(rows)


def test_dataset_stats_are_the_report_medians(cp):
    stats = cp.dataset_stats(tiny_runs(), (0.05, 1.0))
    assert list(stats) == ["kinect", "kitti"]
    kinect = {s.method: s for s in stats["kinect"]}
    assert list(kinect) == ["sgdicp", "o3d_p2p_1t", "pcl_icp_1t"]  # fastest first, build-only left out
    assert (kinect["sgdicp"].time_ms, kinect["sgdicp"].r_err_deg, kinect["sgdicp"].success) == (12.0, 0.85, 0.5)
    assert kinect["sgdicp"].t_err_m == pytest.approx(0.02)
    assert (kinect["pcl_icp_1t"].time_ms, kinect["pcl_icp_1t"].success, kinect["pcl_icp_1t"].runs) == (200.0, 0.5, 2)
    kitti = {s.method: s for s in stats["kitti"]}
    assert kitti["pcl_icp_1t"].time_ms == (500.0 + 30000.0) / 2  # a timeout counts with its limit
    assert kitti["pcl_icp_1t"].r_err_deg == 0.9 and kitti["pcl_icp_1t"].success == 0.5


def test_pareto_from_an_output_folder(cp, tmp_path, capsys):
    write_runs_csv(tmp_path, tiny_runs())
    (tmp_path / "report.md").write_text("# sgd-icp vs peers: end-to-end registration\n\n## Failed runs\n\n- x\n")
    assert cp.main(["--pareto-from", str(tmp_path)]) == 0
    report = (tmp_path / "report.md").read_text()
    assert report.startswith("# sgd-icp vs peers") and "## Failed runs\n\n- x\n" in report
    section = report[report.index("## Pareto"):]
    assert section in capsys.readouterr().out
    assert "translation < 0.05 m and rotation < 1 deg" in section
    kinect = section[section.index("### kinect"):section.index("### kitti")]
    # sgdicp: 12 ms, 0.85 deg, 50 %; o3d 50 ms, 1 deg, 50 %: dominated; pcl 200 ms, 0.1 deg, 50 %: front.
    assert "| sgdicp | 12 | 20 | 0.85 | 50 % | yes | – |" in kinect
    assert "| o3d_p2p_1t | 50 | 30 | 1 | 50 % | no | sgdicp |" in kinect
    assert "| pcl_icp_1t | 200 | 1 | 0.1 | 50 % | yes | – |" in kinect
    assert "sg_kdtree_build" not in kinect
    assert "- sgdicp dominates o3d_p2p_1t\n" in kinect
    kitti = section[section.index("### kitti"):]
    assert "| sg_gicp_vox_1t | 300 | 10 | 0.1 | 100 % | yes | – |" in kitti
    assert "| pcl_icp_1t | 1.52e+04 | 30 | 0.9 | 50 % | no | sgdicp, sg_gicp_vox_1t |" in kitti
    assert "- sgdicp dominates pcl_icp_1t\n" in kitti
    # A second run replaces the section instead of adding one; a stricter --success changes it.
    assert cp.main(["--pareto-from", str(tmp_path), "--success", "0.05,0.5"]) == 0
    report = (tmp_path / "report.md").read_text()
    assert report.count("## Pareto") == 1 and "## Failed runs" in report
    assert "rotation < 0.5 deg" in report and "| sgdicp | 12 | 20 | 0.85 | 50 % |" in report


def test_pareto_from_summary_csv_without_runs_csv(cp, tmp_path):
    with open(tmp_path / "summary.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["group", "method", "threads", "runs", "failed", "success", "success_2m5deg", "median_t_err_m",
                    "median_r_err_deg", "median_time_ms", "timeouts", "ratio_median", "ratio_geomean"])
        w.writerow(["bunny", "sgdicp", 1, 5, 0, 1.0, 1.0, 0.001, 0.05, 8.0, 0, 1.0, 1.0])
        w.writerow(["bunny", "pcl_icp_1t", 1, 5, 0, 1.0, 1.0, 0.001, 0.05, 80.0, 0, 10.0, 10.0])
        w.writerow(["ALL", "sgdicp", 1, 5, 0, 1.0, 1.0, 0.001, 0.05, 8.0, 0, 1.0, 1.0])
    assert cp.main(["--pareto-from", str(tmp_path)]) == 0
    report = (tmp_path / "report.md").read_text()
    assert report.startswith("## Pareto") and "### ALL" not in report
    assert "the run's --success thresholds" in report and "- sgdicp dominates pcl_icp_1t" in report


def test_pareto_from_an_empty_folder_fails(cp, tmp_path):
    assert cp.main(["--pareto-from", str(tmp_path)]) == 2
    assert not (tmp_path / "report.md").exists()


def test_a_missing_matplotlib_skips_only_the_plot(cp, tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # `import matplotlib` raises ImportError
    monkeypatch.setitem(sys.modules, "matplotlib.pyplot", None)
    write_runs_csv(tmp_path, tiny_runs())
    assert cp.main(["--pareto-from", str(tmp_path)]) == 0
    assert "plot skipped: matplotlib not installed" in capsys.readouterr().err
    assert "## Pareto" in (tmp_path / "report.md").read_text()
    assert not (tmp_path / "pareto.png").exists()


def test_the_plot(cp, tmp_path):
    pytest.importorskip("matplotlib")
    write_runs_csv(tmp_path, tiny_runs())
    assert cp.main(["--pareto-from", str(tmp_path)]) == 0
    assert (tmp_path / "pareto.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_pareto_from_works_without_the_package(tmp_path, monkeypatch, capsys):
    cp = load_compare_peers(monkeypatch, without_package=True)
    assert cp.peers is None
    write_runs_csv(tmp_path, tiny_runs())
    assert cp.main(["--pareto-from", str(tmp_path)]) == 0
    assert "- sgdicp dominates o3d_p2p_1t" in (tmp_path / "report.md").read_text()
    with pytest.raises(SystemExit, match="pip install"):  # anything else still needs it
        cp.main(["--quick"])


def test_the_fallback_success_threshold_is_the_package_one(cp):
    pytest.importorskip("sgd_icp")
    assert cp.SUCCESS_WITHOUT_PACKAGE == cp.peers.SUCCESS_THRESHOLDS[0]
    assert cp.build_parser().parse_args([]).success == cp.build_pareto_parser().parse_args(
        ["--pareto-from", "x"]).success


def test_pareto_after_a_run(tmp_path, monkeypatch, capsys):
    """--pareto at the end of a real run (fake peers): the section is in report.md and on stdout."""
    pytest.importorskip("sgd_icp")
    import fake_peers
    import sgd_icp
    from conftest import make_transform, synthetic_scene, transformed

    cp = load_compare_peers()
    T_gt = make_transform(0.02, -0.01, 0.05, (0.1, -0.05, 0.02))
    lines = []
    for name, n in (("small", 400), ("large", 4000)):
        source = synthetic_scene(7, n)
        sgd_icp.write_points(tmp_path / f"{name}_source.ply", source)
        sgd_icp.write_points(tmp_path / f"{name}_reference.ply", transformed(source, T_gt))
        gt = " ".join(f"{v:.17g}" for v in T_gt[:3, :].reshape(-1))
        lines.append(f"{name}_source.ply {name}_reference.ply {gt}")
    pairs_file = tmp_path / "fake.txt"
    pairs_file.write_text("\n".join(lines) + "\n")
    fakes = [cp.peers.Method("sgdicp_fake", "fake", "identity", "1", "worker", fake_peers.identity_peer),
             cp.peers.Method("fake_hang", "fake", "hangs on large", "1", "worker", fake_peers.hanging_peer)]
    monkeypatch.setattr(cp.peers, "build_methods", lambda *args, **kwargs: fakes)
    out = tmp_path / "out"
    assert cp.main([str(pairs_file), "--methods", "sgdicp_fake,fake_hang", "--reps", "1", "--timeout", "1",
                    "--out", str(out), "--no-install", "--pareto"]) == 0
    report = (out / "report.md").read_text()
    assert report.count("## Pareto") == 1 and "## Pareto" in capsys.readouterr().out
    # Both return the identity (same errors, no success); the hanging one times out on `large`.
    assert "| fake_hang | 500 |" in report and "- sgdicp_fake dominates fake_hang" in report
