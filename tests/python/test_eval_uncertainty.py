"""The uncertainty evaluations of eval/ on a small problem: the MCMC reference (an energy written
independently of the library) agrees with laplace on the fixed-pair posterior, and svgd and sgld
lie near it; the Monte-Carlo calibration writes its table and figure."""

from __future__ import annotations

import csv
import subprocess
import sys

import pytest

from conftest import REPO_ROOT

pytest.importorskip("scipy")
pytest.importorskip("matplotlib")


def run_script(name: str, *args: str) -> None:
    subprocess.run([sys.executable, str(REPO_ROOT / "eval" / name), *args], check=True,
                   capture_output=True, text=True, timeout=300)


def test_mcmc_reference_agrees_with_the_methods_on_a_small_problem(tmp_path):
    run_script("mcmc_reference.py", "--datasets", "synthetic", "--trials", "1", "--points", "500",
               "--steps", "4000", "--pairings", "fixed", "--out", str(tmp_path),
               "--figure", str(tmp_path / "mcmc.png"))
    rows = {r["method"]: r for r in csv.DictReader(open(tmp_path / "mcmc.csv"))}
    assert set(rows) == {"laplace", "sgld", "svgd"}
    assert float(rows["laplace"]["rhat_max"]) < 1.05  # the reference converged
    # Laplace is the fixed-pair posterior: the library's sigma, kappa and pairs are the script's.
    assert float(rows["laplace"]["sigma_ratio"]) == pytest.approx(1.0, abs=1e-4)
    assert float(rows["laplace"]["kl_mcmc_method"]) < 0.1
    assert float(rows["laplace"]["kl_method_mcmc"]) < 0.1
    # The samplers near it (measured 0.96-1.11 on this problem; docs/uncertainty.md).
    for method in ("sgld", "svgd"):
        for block in ("std_ratio_t", "std_ratio_r"):
            assert 0.75 < float(rows[method][block]) < 1.4, (method, block)
    assert (tmp_path / "mcmc.png").stat().st_size > 10000


def test_calibration_writes_its_table_and_figure(tmp_path):
    run_script("calibrate_uncertainty.py", "--datasets", "synthetic", "--trials", "2",
               "--methods", "laplace,svgd", "--out", str(tmp_path),
               "--figure", str(tmp_path / "calibration.png"))
    table = (tmp_path / "calibration.md").read_text()
    for row in ("laplace (naive)", "laplace (tempered)", "svgd (naive)", "svgd (tempered)"):
        assert f"| synthetic | {row} |" in table
    assert (tmp_path / "calibration.png").stat().st_size > 10000
