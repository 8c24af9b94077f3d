"""test_open3d.py skips, with the fix in its reason, when open3d is missing or installed without the
system libraries its wheel loads (an ImportError or OSError at import, which pytest.importorskip
does not skip), and fails instead with SGDICP_REQUIRE_OPEN3D=1. A stand-in open3d package that
raises as the real one does is put first on PYTHONPATH of a child pytest."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import pytest

from conftest import OPEN3D_DEBIAN_PACKAGES, REPO_ROOT

LIBUSB_ERROR = "libusb-1.0.so.0: cannot open shared object file: No such file or directory"


def run_test_open3d(tmp_path, raise_line: str, **env) -> subprocess.CompletedProcess:
    """pytest on test_open3d.py in a child whose `import open3d` runs `raise_line`."""
    fake = tmp_path / "fake" / "open3d"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text(raise_line + "\n")
    child_env = {k: v for k, v in os.environ.items() if k != "SGDICP_REQUIRE_OPEN3D"}
    child_env["PYTHONPATH"] = os.pathsep.join(
        [str(tmp_path / "fake")] + ([os.environ["PYTHONPATH"]] if os.environ.get("PYTHONPATH") else []))
    child_env.update(env)
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider",
         str(REPO_ROOT / "tests" / "python" / "test_open3d.py")],
        capture_output=True, text=True, cwd=REPO_ROOT, env=child_env, timeout=300)


@pytest.mark.parametrize("raise_line, library", [
    (f"raise ImportError({LIBUSB_ERROR!r})", "libusb-1.0.so.0"),
    ("raise OSError('libGL.so.1: cannot open shared object file: No such file or directory')", "libGL.so.1"),
])
def test_open3d_that_cannot_load_is_skipped_with_the_fix(tmp_path, raise_line, library):
    p = run_test_open3d(tmp_path, raise_line)
    out = p.stdout + p.stderr
    assert p.returncode in (0, 5), out  # 5: a module skipped whole collects no test
    assert re.search(r"\b1 skipped\b", out) and not re.search(r"\d+ errors?\b", out), out
    reason = next(line for line in out.splitlines() if line.startswith("SKIPPED"))
    assert f"cannot load {library}" in reason, reason
    assert "scripts/setup.sh --open3d" in reason and OPEN3D_DEBIAN_PACKAGES in reason, reason


def test_open3d_not_installed_is_skipped(tmp_path):
    p = run_test_open3d(tmp_path, "raise ModuleNotFoundError(\"No module named 'open3d'\", name='open3d')")
    out = p.stdout + p.stderr
    assert p.returncode in (0, 5) and re.search(r"\b1 skipped\b", out), out
    assert "open3d is not installed" in out, out


def test_open3d_that_cannot_load_fails_when_required(tmp_path):
    p = run_test_open3d(tmp_path, f"raise ImportError({LIBUSB_ERROR!r})", SGDICP_REQUIRE_OPEN3D="1")
    out = p.stdout + p.stderr
    assert p.returncode not in (0, 5) and "skipped" not in out, out
    assert "cannot load libusb-1.0.so.0" in out and "SGDICP_REQUIRE_OPEN3D=1" in out, out


def test_setup_installs_the_open3d_libraries():
    """scripts/setup.sh --open3d installs exactly the packages the skip reason names."""
    script = (REPO_ROOT / "scripts" / "setup.sh").read_text()
    listed = re.search(r"--open3d\) packages\+=\(([^)]*)\)", script)
    assert listed, "scripts/setup.sh has no --open3d package list"
    assert listed.group(1).split() == OPEN3D_DEBIAN_PACKAGES.split()
