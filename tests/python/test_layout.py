"""scripts/check_layout.py, the ctest test `layout`: the parts' layering and the files' size."""

from __future__ import annotations

import importlib.util
import re
import shutil
import subprocess
import sys
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]
CHECK = REPO_ROOT / "scripts" / "check_layout.py"
_spec = importlib.util.spec_from_file_location("check_layout", CHECK)
check_layout = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(check_layout)


def parts() -> list[str]:
    """SGDICP_PARTS of the top-level CMakeLists.txt, the one list of the parts and their order."""
    text = (REPO_ROOT / "CMakeLists.txt").read_text(encoding="utf-8")
    match = re.search(r"set\(SGDICP_PARTS([^)]*)\)", text)
    assert match, "CMakeLists.txt defines SGDICP_PARTS"
    return match.group(1).split()


def run(root: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(CHECK), "--root", str(root), *parts()],
                          capture_output=True, text=True, check=False)


def copy_tree(tmp_path: Path) -> Path:
    root = tmp_path / "repo"
    # The folders the check reads: its own list, so that a copy cannot drift from it.
    for folder in check_layout.SIZE_CHECKED:
        shutil.copytree(REPO_ROOT / folder, root / folder,
                        ignore=shutil.ignore_patterns("__pycache__", "*.so"))
    return root


def test_the_repository_keeps_its_layout():
    result = run(REPO_ROOT)
    assert result.returncode == 0, result.stderr


def test_every_part_folder_is_in_the_list():
    listed = set(parts())
    for base in (REPO_ROOT / "src", REPO_ROOT / "include" / "sgdicp"):
        folders = {p.name for p in base.iterdir() if p.is_dir()}
        assert folders <= listed, f"{base}: {folders - listed} not in SGDICP_PARTS"


def test_an_include_up_the_layers_fails(tmp_path):
    root = copy_tree(tmp_path)
    low = root / "src" / "points" / "scaling.cpp"
    low.write_text(low.read_text(encoding="utf-8") + '#include "sgdicp/registration/settings.hpp"\n',
                   encoding="utf-8")
    result = run(root)
    assert result.returncode == 1
    assert "src/points/scaling.cpp: includes sgdicp/registration/settings.hpp" in result.stderr


def test_a_public_header_with_a_private_include_fails(tmp_path):
    root = copy_tree(tmp_path)
    header = root / "include" / "sgdicp" / "registration" / "registration.hpp"
    header.write_text('#include "registration/solver_support.hpp"\n' +
                      header.read_text(encoding="utf-8"), encoding="utf-8")
    result = run(root)
    assert result.returncode == 1
    assert "a public header includes the private registration/solver_support.hpp" in result.stderr


def test_a_file_over_the_limit_fails(tmp_path):
    root = copy_tree(tmp_path)
    (root / "tests" / "test_long.cpp").write_text("// x\n" * 701, encoding="utf-8")
    result = run(root)
    assert result.returncode == 1
    assert "tests/test_long.cpp: 701 lines, more than 700" in result.stderr
