#!/usr/bin/env python3
"""Point clouds and a pairs file from the 7-Scenes RedKitchen depth frames.

Reads ../shared/data/sevenscenes_redkitchen (PROVENANCE.md there): 16-bit depth PNGs in mm and
camera-to-world poses P (p_world = P p_cam). Writes, into a folder outside the repository
(default ../generated/sevenscenes_redkitchen beside it, or $SGDICP_GENERATED_DATA):

- frame-NNNNNN.ply: every valid depth pixel back-projected with the depth intrinsics, in the
  camera frame (metres, binary little-endian float32, no thinning);
- sevenscenes_redkitchen.txt: pairs of frames OFFSET apart (reference i, source i + OFFSET) for
  each offset, spread evenly over the frames, in the format of ../shared/data/PAIRS.md, with
  T_reference_source = inv(P_i) P_j from the poses after projecting their rotation blocks onto
  the nearest rotation (the dense-tracking poses have det 0.9995-0.9999).

Pairs with a repeated depth frame (byte-identical to the frame before it, while its pose still
moves) are skipped: for them the data's answer is not the pose difference.

Usage: python3 bench/make_sevenscenes_pairs.py [--data DIR] [--out DIR] [--offsets 1,3,5]
       [--pairs-per-offset 20 | N1,N2,...] [--name FILE]
The paper's Table I on this sequence (eval/reproduce.py): --offsets 1,3,10
--pairs-per-offset 600,100,100 --name sevenscenes_table1.txt (every consecutive pair, 100 pairs 3
and 10 frames apart).
Needs numpy, and the sgd_icp package (pip install .) or Pillow (pip install pillow): with the
package the frames are read by its depth-image reader (docs/depth.md), else by Pillow and numpy
(the same points; tests/python/test_depth.py compares the two).
"""

from __future__ import annotations

import argparse
import hashlib
import os
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
DEFAULT_DATA = REPO.parent / "shared" / "data" / "sevenscenes_redkitchen"
DEFAULT_OUT = REPO.parent / "generated" / "sevenscenes_redkitchen"
PAIRS_NAME = "sevenscenes_redkitchen.txt"


def frame_name(index: int, kind: str) -> str:
    return f"frame-{index:06d}.{kind}"


def read_intrinsics(data: Path) -> tuple[float, float, float, float]:
    K = np.loadtxt(data / "camera-intrinsics.txt")
    return float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2])


def read_pose(data: Path, index: int) -> np.ndarray:
    """Camera-to-world pose with its rotation block projected onto SO(3) (SVD)."""
    P = np.loadtxt(data / frame_name(index, "pose.txt"))
    U, _, Vt = np.linalg.svd(P[:3, :3])
    R = U @ Vt
    if np.linalg.det(R) < 0:
        U[:, -1] *= -1
        R = U @ Vt
    P[:3, :3] = R
    P[3] = [0.0, 0.0, 0.0, 1.0]
    return P


def repeated_frames(data: Path, count: int) -> set[int]:
    """Frames whose depth file is byte-identical to the previous frame's."""
    hashes = [hashlib.md5((data / frame_name(i, "depth.png")).read_bytes()).digest() for i in range(count)]
    return {i for i in range(1, count) if hashes[i] == hashes[i - 1]}


def back_project(data: Path, index: int, intrinsics) -> np.ndarray:
    """The library's reader (sgd_icp.read_depth_image) when the package is installed, else numpy."""
    try:
        import sgd_icp
    except ImportError:
        return back_project_numpy(data, index, intrinsics)
    points = sgd_icp.read_depth_image(data / frame_name(index, "depth.png"), intrinsics)
    return np.ascontiguousarray(points, dtype="<f4")


def back_project_numpy(data: Path, index: int, intrinsics) -> np.ndarray:
    """Every nonzero depth pixel, row by row (the same points as sgd_icp.read_depth_image)."""
    fx, fy, cx, cy = intrinsics
    from PIL import Image

    depth_mm = np.asarray(Image.open(data / frame_name(index, "depth.png")), dtype=np.float64)
    v, u = np.nonzero(depth_mm > 0)
    z = depth_mm[v, u] / 1000.0
    return np.stack([(u - cx) * z / fx, (v - cy) * z / fy, z], axis=1).astype("<f4")


def write_ply(path: Path, points: np.ndarray) -> None:
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(points)}\n"
        "property float x\nproperty float y\nproperty float z\nend_header\n"
    )
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(np.ascontiguousarray(points, dtype="<f4").tobytes())


def choose_pairs(count: int, offsets: list[int], per_offset: list[int],
                 repeated: set[int]) -> list[tuple[int, int]]:
    """(reference, source) pairs OFFSET apart (per_offset[k] of offset k), starts spread evenly,
    none with a repeated frame."""
    pairs = []
    for offset, wanted in zip(offsets, per_offset):
        last_start = count - 1 - offset
        for k in range(wanted):
            start = round(k * last_start / max(wanted - 1, 1))
            while start <= last_start and (start in repeated or start + offset in repeated):
                start += 1
            if start <= last_start and (start, start + offset) not in pairs:
                pairs.append((start, start + offset))
    return pairs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
    default_out = Path(os.environ["SGDICP_GENERATED_DATA"]) if os.environ.get("SGDICP_GENERATED_DATA") else DEFAULT_OUT
    parser.add_argument("--out", type=Path, default=default_out)
    parser.add_argument("--offsets", default="1,3,5")
    parser.add_argument("--pairs-per-offset", default="20",
                        help="pairs per offset: one count for all, or one per offset (comma-separated)")
    parser.add_argument("--name", default=PAIRS_NAME, help="file name of the pairs file in --out")
    parser.add_argument("--frames", type=int, default=600)
    args = parser.parse_args()

    offsets = [int(x) for x in args.offsets.split(",")]
    per_offset = [int(x) for x in args.pairs_per_offset.split(",")]
    if len(per_offset) == 1:
        per_offset *= len(offsets)
    if len(per_offset) != len(offsets):
        parser.error("--pairs-per-offset: one count, or one per offset")
    repeated = repeated_frames(args.data, args.frames)
    pairs = choose_pairs(args.frames, offsets, per_offset, repeated)
    intrinsics = read_intrinsics(args.data)
    args.out.mkdir(parents=True, exist_ok=True)
    for index in sorted({i for pair in pairs for i in pair}):
        ply = args.out / frame_name(index, "ply")
        if not ply.exists():
            write_ply(ply, back_project(args.data, index, intrinsics))

    lines = [
        "# 7-Scenes RedKitchen depth frames (Kinect, 640x480, all valid pixels back-projected, camera frame),",
        f"# pairs of frames {args.offsets} apart, none with a repeated depth frame; written by bench/make_sevenscenes_pairs.py",
        "# T_gt = inv(P_reference) P_source from the dense-tracking poses (rotations re-orthonormalised)",
        "# source reference T_gt (3x4 row-major, reference ~= T_gt * source)",
    ]
    for reference, source in pairs:
        T = np.linalg.inv(read_pose(args.data, reference)) @ read_pose(args.data, source)
        numbers = " ".join(f"{x:.9g}" for x in T[:3].reshape(-1))
        lines.append(f"{frame_name(source, 'ply')} {frame_name(reference, 'ply')} {numbers}")
    (args.out / args.name).write_text("\n".join(lines) + "\n")
    print(f"{len(pairs)} pairs ({len(repeated)} repeated frames skipped) -> {args.out / args.name}")


if __name__ == "__main__":
    main()
