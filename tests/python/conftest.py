"""Shared helpers of the sgd_icp tests: synthetic scenes, transforms, the real data and the CLI."""

from __future__ import annotations

import os
import re
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
# The peer-comparison harness bench/peers/ (not part of the installed package): importable as
# `peers` by test_peers.py, fake_peers.py and bench/compare_peers.py, and by their worker processes
# (multiprocessing's spawn passes sys.path on).
if str(REPO_ROOT / "bench") not in sys.path:
    sys.path.insert(0, str(REPO_ROOT / "bench"))


def shared_data_dir() -> Path:
    """The real data beside the repository (repo_root/../shared/data), or $SGDICP_SHARED_DATA."""
    return Path(os.environ.get("SGDICP_SHARED_DATA", REPO_ROOT.parent / "shared" / "data"))


def make_transform(
    roll: float, pitch: float, yaw: float, t: tuple[float, float, float]
) -> np.ndarray:
    """A 4x4 transform with R = Rz(yaw) Ry(pitch) Rx(roll) (radians) and translation t (metres)."""
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    T = np.eye(4)
    T[:3, :3] = rz @ ry @ rx
    T[:3, 3] = t
    return T


def transformed(points: np.ndarray, T: np.ndarray) -> np.ndarray:
    """points (N, 3) moved by T, in the dtype of points."""
    return (points.astype(np.float64) @ T[:3, :3].T + T[:3, 3]).astype(points.dtype)


def synthetic_scene(seed: int, n: int = 60000) -> np.ndarray:
    """A small man-made scene without symmetries (floor, two walls, a box, a ball), n points about
    4 cm apart with 2 mm noise, float32 metres (the scene of tests/test_registration.cpp)."""
    rng = np.random.default_rng(seed)
    a, b = rng.random(n), rng.random(n)
    kind = np.arange(n) % 5
    p = np.zeros((n, 3))
    floor, wall_x, wall_y, box, ball = (kind == k for k in range(5))
    p[floor] = np.c_[6 * a[floor], 4 * b[floor], np.zeros(floor.sum())]
    p[wall_x] = np.c_[6 * a[wall_x], np.zeros(wall_x.sum()), 2.5 * b[wall_x]]
    p[wall_y] = np.c_[np.zeros(wall_y.sum()), 4 * a[wall_y], 2.5 * b[wall_y]]
    p[box] = np.c_[2 + 0.8 * a[box], 1.5 + 0.5 * b[box], np.full(box.sum(), 0.9)]
    th, ph = 2 * np.pi * a[ball], np.arccos(2 * b[ball] - 1)
    p[ball] = (
        np.array([4.2, 2.8, 0.6])
        + 0.5 * np.c_[np.sin(ph) * np.cos(th), np.sin(ph) * np.sin(th), np.cos(ph)]
    )
    p += rng.normal(0.0, 0.002, size=p.shape)
    return p.astype(np.float32)


def read_pairs(name: str) -> list[tuple[Path, Path, np.ndarray]]:
    """The pairs of shared/data/pairs/NAME.txt: (source, reference, T_gt 4x4); skips if absent."""
    path = shared_data_dir() / "pairs" / f"{name}.txt"
    if not path.is_file():
        pytest.skip(f"real data not found: {path}")
    pairs = []
    for line in path.read_text().splitlines():
        fields = line.split()
        if not fields or fields[0].startswith("#"):
            continue
        T = np.eye(4)
        T[:3, :] = np.array([float(v) for v in fields[2:14]]).reshape(3, 4)
        pairs.append((path.parent / fields[0], path.parent / fields[1], T))
    return pairs


def find_cli() -> Path | None:
    """The sgdicp executable: $SGDICP_BIN, else $BUILD_DIR/sgdicp, build/sgdicp or build-ci/sgdicp
    of the repository, else sgdicp on PATH."""
    candidates = []
    if os.environ.get("SGDICP_BIN"):
        candidates.append(Path(os.environ["SGDICP_BIN"]))
    if os.environ.get("BUILD_DIR"):
        candidates.append(REPO_ROOT / os.environ["BUILD_DIR"] / "sgdicp")
    candidates += [REPO_ROOT / "build" / "sgdicp", REPO_ROOT / "build-ci" / "sgdicp"]
    on_path = shutil.which("sgdicp")
    if on_path:
        candidates.append(Path(on_path))
    return next((c for c in candidates if c.is_file() and os.access(c, os.X_OK)), None)


# The Debian packages of the system libraries that the open3d wheel links to (the NEEDED entries of
# its libOpen3D.so); `scripts/setup.sh --open3d` installs the same list (test_open3d_skip.py checks).
OPEN3D_DEBIAN_PACKAGES = "libegl1 libgl1 libx11-6 libusb-1.0-0 libudev1 libidn2-0 libgomp1"


def import_open3d():
    """open3d, or a skip of the calling test module when it is not installed or cannot load: a pip
    wheel on a machine without the system libraries it links to raises ImportError
    (`libusb-1.0.so.0: cannot open shared object file`), which pytest.importorskip does not skip.
    With SGDICP_REQUIRE_OPEN3D=1 (a run meant to test Open3D) the module fails instead."""
    try:
        import open3d
    except ModuleNotFoundError as e:
        if e.name == "open3d":
            why = "open3d is not installed (pip install \".[open3d]\")"
        else:
            why = f"open3d cannot be imported ({e}): pip install --force-reinstall open3d"
    except (ImportError, OSError) as e:
        library = re.search(r"lib[\w.+-]*\.so[\w.]*", str(e))
        why = (f"open3d is installed but cannot load {library.group(0) if library else 'its libraries'} "
               f"({e}): install the system libraries its wheel needs with scripts/setup.sh --open3d "
               f"(apt-get install {OPEN3D_DEBIAN_PACKAGES})")
    else:
        return open3d
    if os.environ.get("SGDICP_REQUIRE_OPEN3D") == "1":
        pytest.fail(why + " [SGDICP_REQUIRE_OPEN3D=1]", pytrace=False)
    pytest.skip(why, allow_module_level=True)


@pytest.fixture(scope="session")
def scene() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(source, reference, T_gt): two independent samplings of the synthetic scene, the reference
    moved by a known transform (5, -8, 15 degrees; 0.25 m)."""
    T_gt = make_transform(np.radians(5), np.radians(-8), np.radians(15), (-0.25, 0.1, 0.05))
    return synthetic_scene(1), transformed(synthetic_scene(2), T_gt), T_gt


@pytest.fixture(scope="session")
def car_pair():
    """(source path, reference path, source points, reference points, T_gt) of the libpointmatcher
    car CSV pair (~25k points each, ~14 degrees apart)."""
    import sgd_icp

    source, reference, T_gt = read_pairs("libpointmatcher_car")[0]
    return source, reference, sgd_icp.read_points(source), sgd_icp.read_points(reference), T_gt
