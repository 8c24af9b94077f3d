"""Pairs files (shared/data/PAIRS.md), read as the CLI reads them (include/sgdicp/pairs.hpp), and
the errors of a result against a pair's ground truth, with the package's metrics.

A line is `SOURCE REFERENCE t00 t01 t02 t03 t10 ... t23`: the ground truth T_reference_source as a
row-major 3x4 matrix, paths relative to the pairs file's folder; empty lines and lines starting
with '#' are comments.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from sgd_icp import (
    FormatError,
    IoError,
    rotation_error_euler_sum,
    rotation_error_geodesic,
    translation_error,
)


@dataclass
class Pair:
    """One registration problem of a pairs file."""

    pairs_file: str  # stem of the pairs file, e.g. kitti_seq00
    line: int  # line in the pairs file
    source: str  # path, resolved against the pairs file's folder
    reference: str
    T_gt: np.ndarray  # ground truth T_reference_source, (4, 4)
    index: int = 0  # position in the caller's list of pairs

    @property
    def label(self) -> str:
        return f"{self.pairs_file}:{self.line}"


def read_pairs(path: str | os.PathLike) -> list[Pair]:
    """The pairs of a pairs file. Raises IoError (cannot read) or FormatError (naming the line)."""
    path = os.fspath(path)
    try:
        with open(path, encoding="utf-8") as f:
            lines = f.read().splitlines()
    except OSError as e:
        raise IoError(f"{path}: cannot open: {e.strerror or e}") from e
    folder = os.path.dirname(os.path.abspath(path))
    stem = os.path.splitext(os.path.basename(path))[0]
    pairs = []
    for number, line in enumerate(lines, 1):
        fields = line.split()
        if not fields or fields[0].startswith("#"):
            continue
        try:
            values = [float(v) for v in fields[2:]]
        except ValueError:
            values = []
        if len(fields) != 14 or len(values) != 12 or not all(map(math.isfinite, values)):
            raise FormatError(f"{path}: line {number}: expected SOURCE REFERENCE and 12 numbers")
        T = np.eye(4)
        T[:3, :] = np.array(values).reshape(3, 4)
        pairs.append(
            Pair(
                stem,
                number,
                os.path.normpath(os.path.join(folder, fields[0])),
                os.path.normpath(os.path.join(folder, fields[1])),
                T,
            )
        )
    if not pairs:
        raise FormatError(f"{path}: no pairs in file")
    return pairs


def pair_line(pair: Pair) -> str:
    """The pairs-file line of `pair` (absolute paths, the ground truth to full precision)."""
    gt = " ".join(f"{v:.17g}" for v in pair.T_gt[:3, :].reshape(-1))
    return f"{pair.source} {pair.reference} {gt}"


def write_pairs(path: str | os.PathLike, pairs: list[Pair]) -> None:
    """Writes `pairs` as a pairs file, one per line, in order."""
    with open(path, "w", encoding="utf-8") as f:
        f.writelines(pair_line(p) + "\n" for p in pairs)


# The CLI's success thresholds (`sgdicp bench --success` defaults, apps/bench.cpp): a registration
# succeeds when its translation error [m] and geodesic rotation error [deg] are below a pair.
SUCCESS_THRESHOLDS = ((0.05, 1.0), (2.0, 5.0))


@dataclass
class Errors:
    """Errors of an estimate T_reference_source against the ground truth."""

    translation_m: float = float("nan")  # |t - t_gt|
    rotation_geodesic_deg: float = float("nan")  # angle of R^T R_gt
    rotation_euler_rad: float = float("nan")  # the paper's |d roll| + |d pitch| + |d yaw|


def errors_against(T: np.ndarray, T_gt: np.ndarray) -> Errors:
    """The errors of `T` against `T_gt` by the package's metrics (the CLI's definitions); nan
    where `T` is not finite."""
    T = np.asarray(T, dtype=np.float64)
    if not np.all(np.isfinite(T)):
        return Errors()
    return Errors(
        translation_error(T, T_gt),
        math.degrees(rotation_error_geodesic(T, T_gt)),
        rotation_error_euler_sum(T, T_gt),
    )
