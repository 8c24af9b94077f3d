"""The harness bench/peers/: pairs files, the worker process with its time limit, the session, and
bench/compare_peers.py going on after a peer that hangs or crashes (fake peers, fake_peers.py)."""

from __future__ import annotations

import csv
import importlib.util
import os
import sys
import time

import numpy as np
import pytest

import fake_peers
import peers  # bench/peers/, on sys.path by conftest.py
import sgd_icp
from conftest import REPO_ROOT, make_transform, synthetic_scene, transformed

# The fake pairs files have no voxel size of their own: the peers' warning is expected.
pytestmark = pytest.mark.filterwarnings("ignore:peers. no voxel size:UserWarning")

TIMEOUT_S = 1.0


@pytest.fixture(scope="module")
def pairs_file(tmp_path_factory) -> str:
    """A pairs file of two pairs: `small` (400 points, under fake_peers.HANG_ABOVE_POINTS) first,
    then `large` (4000 points), each a cloud and a moved copy with its exact ground truth."""
    folder = tmp_path_factory.mktemp("pairs")
    T_gt = make_transform(0.02, -0.01, 0.05, (0.1, -0.05, 0.02))
    lines = []
    for name, n in (("small", 400), ("large", 4000)):
        source = synthetic_scene(7, n)
        sgd_icp.write_points(folder / f"{name}_source.ply", source)
        sgd_icp.write_points(folder / f"{name}_reference.ply", transformed(source, T_gt))
        gt = " ".join(f"{v:.17g}" for v in T_gt[:3, :].reshape(-1))
        lines.append(f"{name}_source.ply {name}_reference.ply {gt}")
    path = folder / "fake.txt"
    path.write_text("# two pairs\n\n" + "\n".join(lines) + "\n")
    return str(path)


def fake_method(name: str, fn) -> peers.Method:
    return peers.Method(name, "fake", f"fake peer {name}", "1", "worker", fn)


def test_read_pairs_as_the_cli(pairs_file):
    pairs = peers.read_pairs(pairs_file)
    assert [(p.pairs_file, p.line) for p in pairs] == [("fake", 3), ("fake", 4)]
    assert os.path.isabs(pairs[0].source) and pairs[0].source.endswith("small_source.ply")
    assert pairs[1].T_gt.shape == (4, 4) and pairs[1].T_gt[3, 3] == 1.0


def test_read_pairs_names_the_bad_line(tmp_path):
    bad = tmp_path / "bad.txt"
    bad.write_text("# header\na.ply b.ply 1 0 0 0 0 1 0 0 0 0 1\n")
    with pytest.raises(sgd_icp.FormatError, match="line 2"):
        peers.read_pairs(bad)
    with pytest.raises(sgd_icp.IoError):
        peers.read_pairs(tmp_path / "missing.txt")


def test_errors_are_the_package_metrics():
    T_gt = make_transform(0.1, 0.2, -0.3, (1, 2, 3))
    T = make_transform(0.1, 0.25, -0.3, (1, 2, 3.5))
    e = peers.errors_against(T, T_gt)
    assert e.translation_m == pytest.approx(0.5)
    assert e.rotation_geodesic_deg == pytest.approx(np.degrees(0.05), rel=1e-6)
    assert e.rotation_euler_rad == pytest.approx(sgd_icp.rotation_error_euler_sum(T, T_gt))


def test_worker_stops_a_task_that_hangs_and_goes_on():
    with peers.Worker("fake") as w:
        assert w.call(fake_peers.echo, 1, timeout_s=60).value == 1
        t0 = time.perf_counter()
        reply = w.call(fake_peers.sleep_then_echo, 60, 2, timeout_s=TIMEOUT_S)
        assert reply.status == "timeout"
        assert time.perf_counter() - t0 < TIMEOUT_S + 10
        assert "1 s" in reply.note
        reply = w.call(fake_peers.echo, 3, timeout_s=60)
        assert (reply.status, reply.value, w.starts) == ("ok", 3, 2)


def test_worker_reports_a_crash_and_an_exception():
    with peers.Worker("fake") as w:
        reply = w.call(fake_peers.crash, timeout_s=60)
        assert reply.status == "crashed" and "SIGSEGV" in reply.note
        reply = w.call(fake_peers.fail, timeout_s=60)
        assert reply.status == "error" and "ValueError: bad input" in reply.note
        assert w.call(fake_peers.echo, 4, timeout_s=60).value == 4
        assert w.starts == 2  # restarted after the crash, not after the exception


def test_worker_sets_its_environment():
    with peers.Worker("fake", env={"OMP_NUM_THREADS": "1", "SGDICP_TEST_VAR": "x"}) as w:
        assert w.call(os.getenv, "SGDICP_TEST_VAR", timeout_s=60).value == "x"
    assert "SGDICP_TEST_VAR" not in os.environ


def test_session_records_a_timeout_and_goes_on(pairs_file):
    settings = peers.PeerSettings(timeout_s=TIMEOUT_S)
    hang = fake_method("hang", fake_peers.hanging_peer)
    ok = fake_method("ok", fake_peers.identity_peer)
    with peers.Session(settings, log=lambda msg: None) as session:
        small, large = session.prepare(peers.read_pairs(pairs_file), [hang, ok])
        assert session.points[large.source] == 4000
        first = session.run(hang, small)
        assert first.status == "ok" and first.time_ms == 1.0 and first.call_ms > 0
        t0 = time.perf_counter()
        stopped = session.run(hang, large)
        assert stopped.status == "timeout" and time.perf_counter() - t0 < TIMEOUT_S + 10
        assert stopped.time_ms == TIMEOUT_S * 1e3 and stopped.T is None
        after = session.run(ok, large)
        assert after.status == "ok"
        # the identity against the ground truth: the errors are the ground truth's own size
        assert after.translation_error_m == pytest.approx(np.linalg.norm(large.T_gt[:3, 3]))
        assert session.run(hang, small).status == "ok"  # a new worker, warmed up again


def test_session_records_a_crash(pairs_file):
    crash = fake_method("crash", fake_peers.crashing_peer)
    with peers.Session(peers.PeerSettings(timeout_s=30), log=lambda msg: None) as session:
        small, large = session.prepare(peers.read_pairs(pairs_file), [crash])
        o = session.run(crash, large)
        assert o.status == "crashed" and "SIGSEGV" in o.note
        assert session.run(crash, small).status == "ok"


def test_cli_runs_are_stopped_too(pairs_file, tmp_path):
    slow_cli = tmp_path / "sgdicp"
    slow_cli.write_text("#!/bin/sh\nsleep 60\n")
    slow_cli.chmod(0o755)
    t0 = time.perf_counter()
    run = peers.run_bench(str(slow_cli), peers.read_pairs(pairs_file), [], str(tmp_path), TIMEOUT_S,
                          peak_rss=True)
    assert run.status == "timeout" and time.perf_counter() - t0 < TIMEOUT_S + 10
    crashing_cli = tmp_path / "crash"
    crashing_cli.write_text("#!/bin/sh\nkill -SEGV $$\n")
    crashing_cli.chmod(0o755)
    run = peers.run_bench(str(crashing_cli), peers.read_pairs(pairs_file), [], str(tmp_path), 30)
    assert run.status == "crashed"


def test_the_cli_is_timed_warm_after_an_untimed_registration(pairs_file, tmp_path):
    """Our CLI runs the pair twice in one process, from the seed before the round's: only the
    second registration (the round's seed, 2019 + rep) is timed, as the peers' warm-up run is
    not."""
    args_file = tmp_path / "args"
    cli = tmp_path / "sgdicp"
    header = ("line,repeat,time_ms,build_ms,iterations,converged,translation_error_m,"
              "rotation_error_geodesic_deg,rotation_error_euler_rad,stop_reason")
    cli.write_text(
        "#!/bin/sh\n"
        f'echo "$@" > {args_file}\n'
        'while [ "$1" != "--csv" ]; do shift; done\n'
        f'printf "{header}\\n1,0,100,50,9,1,0.5,5,0.1,converged\\n'
        '1,1,7,3,9,1,0.25,2,0.05,converged\\n" > "$2"\n')
    cli.chmod(0o755)
    methods = {m.name: m for m in peers.build_methods(peers.PeerSettings(), str(cli), None)}
    with peers.Session(peers.PeerSettings(timeout_s=30), sgdicp=str(cli),
                       log=lambda msg: None) as session:
        pair = peers.read_pairs(pairs_file)[0]
        o = session.run(methods["sgdicp"], pair, rep=3)
    assert o.status == "ok", o.note
    assert o.time_ms == 7.0 and o.build_ms == 3.0 and o.translation_error_m == 0.25
    args = args_file.read_text().split()
    assert args[args.index("--seed") + 1] == "2021" and args[args.index("--repeat") + 1] == "2"


def load_compare_peers():
    spec = importlib.util.spec_from_file_location("compare_peers", REPO_ROOT / "bench" / "compare_peers.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_compare_peers_goes_on_after_a_hanging_peer(pairs_file, tmp_path, monkeypatch, capsys):
    cp = load_compare_peers()
    fakes = [fake_method("fake_hang", fake_peers.hanging_peer), fake_method("fake_ok", fake_peers.identity_peer)]
    monkeypatch.setattr(cp.peers, "build_methods", lambda *args, **kwargs: fakes)
    out = tmp_path / "out"
    status = cp.main([pairs_file, "--methods", "fake_hang,fake_ok", "--reps", "2", "--timeout", str(TIMEOUT_S),
                      "--out", str(out), "--no-install"])
    assert status == 0
    with open(out / "runs.csv", newline="") as f:
        rows = [(r["method"], r["line"], r["rep"], r["status"]) for r in csv.DictReader(f)]
    # The hanging peer times out once on the large pair and is not run there again; every other
    # run happens, in both rounds.
    assert sorted(rows) == sorted([
        ("fake_hang", "3", "0", "ok"), ("fake_hang", "4", "0", "timeout"), ("fake_hang", "3", "1", "ok"),
        ("fake_ok", "3", "0", "ok"), ("fake_ok", "4", "0", "ok"), ("fake_ok", "3", "1", "ok"),
        ("fake_ok", "4", "1", "ok"),
    ])
    assert "1 timed out" in (out / "report.md").read_text()


def test_scripts_say_how_to_install_the_package(tmp_path):
    """Without the package the scripts stop with the `pip install .` hint, not a traceback."""
    import subprocess

    blocker = tmp_path / "sgd_icp"
    blocker.mkdir()
    (blocker / "__init__.py").write_text("raise ImportError('blocked for the test')\n")
    env = dict(os.environ, PYTHONPATH=str(tmp_path))
    for script in ("bench/compare_peers.py", "eval/reproduce.py", "bench/kdtree_build_peers.py"):
        p = subprocess.run([sys.executable, str(REPO_ROOT / script), "--help"], capture_output=True,
                           text=True, env=env)
        assert p.returncode == 1, script
        assert "pip install ." in p.stderr and "Traceback" not in p.stderr, script


def test_small_gicp_runs_in_its_worker(pairs_file):
    pytest.importorskip("small_gicp")
    settings = peers.PeerSettings()
    methods = {m.name: m for m in peers.build_methods(settings, None, None)}
    icp = methods["sg_icp_full_1t"]
    assert icp.available, icp.why_not
    with peers.Session(settings, log=lambda msg: None) as session:
        small, large = session.prepare(peers.read_pairs(pairs_file), [icp])
        o = session.run(icp, large)
    assert o.status == "ok", o.note
    assert 0 < o.time_ms < o.call_ms and o.iterations >= 1 and o.source_points_used == 4000
    assert o.translation_error_m < 0.01 and o.rotation_error_geodesic_deg < 0.5


def test_voxel_table_prefixes_and_warns_once_for_an_unknown_pairs_file():
    settings = peers.PeerSettings()
    assert settings.voxel_for("pcl_bunny") == 0.002
    assert settings.voxel_for("sevenscenes_table1_3apart") == 0.02  # longest prefix
    with pytest.warns(UserWarning, match="no voxel size for the pairs file 'my_scans'"):
        assert settings.voxel_for("my_scans") == settings.default_voxel_m
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert settings.voxel_for("my_scans") == settings.default_voxel_m  # once per stem


def test_the_harness_is_not_part_of_the_package():
    """bench/peers/ is the repository's, imported from bench/; the installed package has no peers."""
    assert importlib.util.find_spec("sgd_icp.peers") is None
    assert not os.path.exists(os.path.join(os.path.dirname(sgd_icp.__file__), "peers"))
    assert os.path.dirname(os.path.abspath(peers.__file__)) == str(REPO_ROOT / "bench" / "peers")
