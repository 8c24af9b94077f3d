"""sgd_icp.distributed on a LocalCluster of 2 single-threaded workers: a pairs file with a bad pair
in the middle gives, in file order, the rows of sequential sgd_icp.register calls and the bad
pair's error; references are indexed once per worker; the command line writes the same rows."""

from __future__ import annotations

import csv
import subprocess
import sys

import numpy as np
import pytest

import sgd_icp
from conftest import REPO_ROOT, make_transform, synthetic_scene, transformed

distributed = pytest.importorskip("distributed")
from sgd_icp.distributed import read_jobs, register_pair, register_pairs  # noqa: E402

DEG = np.pi / 180


@pytest.fixture(scope="module")
def pairs_file(tmp_path_factory):
    """A pairs file of 5 pairs over 2 references; the third pair's source is not a cloud."""
    folder = tmp_path_factory.mktemp("pairs")
    T_gts = [make_transform(0, 0, (3 + 2 * k) * DEG, (0.05 * k, 0.02, 0)) for k in range(5)]
    sgd_icp.write_points(folder / "ref_a.ply", synthetic_scene(21, n=8000))
    sgd_icp.write_points(folder / "ref_b.ply", synthetic_scene(22, n=8000))
    (folder / "bad.xyz").write_text("1 2 3\nnot a number\n")
    lines = ["# test pairs"]
    for k, T in enumerate(T_gts):
        reference = "ref_a.ply" if k % 2 == 0 else "ref_b.ply"
        ref_points = sgd_icp.read_points(folder / reference)
        source = f"src_{k}.ply"
        if k == 2:
            source = "bad.xyz"
        else:
            sgd_icp.write_points(folder / source, transformed(ref_points, np.linalg.inv(T)))
        lines.append(" ".join([source, reference] + [f"{v:.17g}" for v in T[:3].reshape(-1)]))
    path = folder / "pairs.txt"
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None)
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def sequential(pairs_file, method, **settings):
    """The transforms of plain sgd_icp.register calls on the same files (None for the bad pair)."""
    out = []
    for source, reference, _, _ in sgd_icp.read_pairs(pairs_file):
        try:
            points = sgd_icp.read_points(source)
        except sgd_icp.Error:
            out.append(None)
            continue
        r = sgd_icp.register(points, sgd_icp.read_points(reference), method=method, **settings)
        out.append(r.T_reference_source)
    return out


@pytest.mark.parametrize(
    "method, settings",
    [("sgd", {"seed": 7}), ("icp-plane", {}), ("sgd", {"settings": sgd_icp.Settings.paper()})],
    ids=["sgd", "icp-plane", "paper-settings"],
)
def test_cluster_matches_sequential_in_order(pairs_file, client, method, settings):
    rows = register_pairs(pairs_file, client, method, **settings)
    expected = sequential(pairs_file, method, **settings)
    assert [r.index for r in rows] == list(range(5))
    assert [r.line for r in rows] == [2, 3, 4, 5, 6]
    for row, T in zip(rows, expected):
        if T is None:
            assert not row.ok and row.T_reference_source is None
            assert row.error.startswith("FormatError") and "bad.xyz" in row.error
        else:
            assert row.ok, row.error
            np.testing.assert_array_equal(row.T_reference_source, T)
            assert row.translation_error_m < 0.01 and row.rotation_error_deg < 0.3
    assert {r.worker for r in rows} <= set(client.scheduler_info()["workers"])


def test_reference_is_indexed_once_per_worker(pairs_file, client):
    client.restart()  # empty caches
    rows = register_pairs(pairs_file, client, seed=1)
    builds = {}
    for r in rows:
        if r.ok:
            builds.setdefault((r.worker, r.reference), []).append(r.reference_cached)
    for flags in builds.values():
        assert flags.count(False) == 1, builds


def test_list_of_pairs_with_init(pairs_file, client, tmp_path):
    jobs = read_jobs(pairs_file)
    good = [j for j in jobs if "bad" not in j.source]
    T_file = tmp_path / "init.txt"
    T_file.write_text(" ".join(f"{v:.17g}" for v in good[0].T_gt[:3].reshape(-1)))
    pairs = [(good[0].source, good[0].reference, str(T_file)),
             (good[1].source, good[1].reference, good[1].T_gt),
             (good[2].source, good[2].reference)]
    rows = register_pairs(pairs, client, seed=3)
    for row, (source, reference, *init) in zip(rows, pairs):
        T_init = sgd_icp.read_transform(init[0]) if init and isinstance(init[0], str) else (
            init[0] if init else None)
        expected = sgd_icp.register(sgd_icp.read_points(source), sgd_icp.read_points(reference),
                                    init=T_init, seed=3)
        assert row.ok and row.line is None and row.translation_error_m is None
        np.testing.assert_array_equal(row.T_reference_source, expected.T_reference_source)


def test_local_run_without_cluster_is_the_same_row(pairs_file):
    job = read_jobs(pairs_file)[0]
    row = register_pair(job, "sgd", {"seed": 7})
    assert row.ok and row.worker == ""
    np.testing.assert_array_equal(row.T_reference_source, sequential(pairs_file, "sgd", seed=7)[0])


def test_invalid_settings_raise_before_sending(pairs_file, client):
    with pytest.raises(TypeError, match="no_such_option"):
        register_pairs(pairs_file, client, no_such_option=1)
    with pytest.raises(sgd_icp.InvalidSettingsError):
        register_pairs(pairs_file, client, method="no-such-method")
    with pytest.raises(TypeError, match=r"pairs\[0\]"):
        register_pairs([("only-one",)], client)


def test_command_line_writes_rows_in_order(pairs_file, tmp_path):
    out_csv = tmp_path / "rows.csv"
    run = subprocess.run(
        [sys.executable, "-m", "sgd_icp.distributed", str(pairs_file), "--workers", "2",
         "--seed", "7", "--csv", str(out_csv), "--no-progress"],
        capture_output=True, text=True, timeout=300, cwd=REPO_ROOT / "tests")
    assert run.returncode == 1, run.stderr  # one pair failed
    assert "5 pairs, 1 failed" in run.stdout and "FAILED FormatError" in run.stdout
    with open(out_csv) as f:
        rows = list(csv.DictReader(f))
    assert [int(r["line"]) for r in rows] == [2, 3, 4, 5, 6]
    expected = sequential(pairs_file, "sgd", seed=7)
    for row, T in zip(rows, expected):
        assert (row["ok"] == "True") == (T is not None)
        if T is not None:
            got = np.array([float(v) for v in row["T_reference_source"].split()]).reshape(4, 4)
            np.testing.assert_array_equal(got, T)


def test_command_line_rejects_bad_arguments_before_starting_a_cluster(tmp_path):
    bad = tmp_path / "pairs.txt"
    bad.write_text("only_one_field.ply\n")
    for args, message in [([str(tmp_path / "missing.txt")], "cannot open"),
                          ([str(bad)], "pairs.txt: line 1"),
                          ([str(bad), "--workers", "0"], "--workers")]:
        run = subprocess.run([sys.executable, "-m", "sgd_icp.distributed", *args],
                             capture_output=True, text=True, timeout=60, cwd=REPO_ROOT / "tests")
        assert run.returncode == 2 and message in run.stderr, (args, run.stderr)


def test_missing_reference_is_reported_in_its_row(pairs_file, client):
    good = read_jobs(pairs_file)[0]
    rows = register_pairs([(good.source, str(pairs_file.parent / "missing.ply")),
                           (good.source, good.reference)], client, seed=7)
    assert not rows[0].ok and rows[0].error.startswith("IoError") and "missing.ply" in rows[0].error
    assert rows[1].ok


def test_lost_worker_is_retried(pairs_file):
    """A worker killed (SIGKILL) while it registers a pair: Dask runs its task again on a worker
    that is alive, and every row still comes back, in order, equal to the sequential result."""
    import os
    import signal
    import threading
    import time

    # Slow pairs (300 full ICP iterations each, no early stop) so that the kill lands mid-task.
    slow = {"max_iterations": 300, "translation_tolerance": 0.0, "rotation_tolerance": 0.0}
    good = [j for j in read_jobs(pairs_file) if "bad" not in j.source]
    pairs = [(j.source, j.reference) for j in good] * 2
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None)
    client = distributed.Client(cluster)
    try:
        out = {}
        runner = threading.Thread(
            target=lambda: out.update(rows=register_pairs(pairs, client, "icp", **slow)))
        runner.start()
        victim, deadline = None, time.monotonic() + 60
        while victim is None and time.monotonic() < deadline:
            busy = [w for w, keys in client.processing().items() if keys]
            victim = busy[0] if busy else None
            time.sleep(0.05)
        assert victim is not None, "no task started"
        time.sleep(0.2)  # inside the task, not at its start
        pid = client.run(os.getpid, workers=[victim])[victim]
        os.kill(pid, signal.SIGKILL)
        runner.join(timeout=240)
        assert not runner.is_alive(), "register_pairs did not return after the worker was lost"
    finally:
        client.close()
        cluster.close()
    rows = out["rows"]
    assert [r.index for r in rows] == list(range(len(pairs)))
    assert all(r.ok for r in rows), [r.error for r in rows]
    # The task that was running on the victim finished elsewhere: not every row names the victim,
    # and the victim's rows are only those done before the kill.
    assert any(r.worker != victim for r in rows)
    for row, (source, reference) in zip(rows, pairs):
        expected = sgd_icp.register(sgd_icp.read_points(source), sgd_icp.read_points(reference),
                                    method="icp", **slow)
        np.testing.assert_array_equal(row.T_reference_source, expected.T_reference_source)
