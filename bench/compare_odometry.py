#!/usr/bin/env python3
"""sgd-icp odometry against KISS-ICP on the same frames, one run: lost frames, RPE, end drift,
segment drift, ATE and whole-run wall time (reading included on both sides), per sequence and frame rate.

    python bench/compare_odometry.py ../shared/data/balm_handheld_lidar \\
        ../shared/data/sevenscenes_redkitchen --steps 1,2,3
    python bench/compare_odometry.py ../shared/data/kitti_odometry_seq00 --methods sgd,icp-plane

A sequence folder is one of:
- a 7-Scenes folder: frame-*.depth.png back-projected with camera-intrinsics.txt, reference its
  frame-*.pose.txt (re-orthonormalised);
- a folder of scans/*.bin (KITTI Velodyne layout) with poses.txt, one 3x4 world pose per scan
  (the hand-held LiDAR of ../shared/data/balm_handheld_lidar);
- a KITTI sequence folder (velodyne/*.bin): reference the maintainers' ICP pseudo ground truth of
  reference_relative_poses_icp.txt when present (the official poses are 0.15 m per frame off for
  frames 0-10, PROVENANCE.md), else poses_*.txt moved into the scanner frame with calib.txt's Tr.

`--steps 1,2,3` runs every frame, every second and every third (30/15/10 Hz for a Kinect,
2/1/0.67 Hz for the hand-held LiDAR). `--reverse` plays the frames backwards (the reference
too): sequences with motions no default was measured on. `--steps 5 --irregular 1,2,3` reads,
for each seed, every next frame 1 to 5 frames on at random (a logger dropping frames). A frame is lost when its relative pose
error against the reference exceeds 20 cm or 2 deg. Both sides are timed as their users run them: sgd-icp reads with
sgd_icp.read_points / read_depth_image; KISS-ICP reads the .bin with NumPy and decodes the depth
PNG with Pillow and back-projects it in NumPy (its own loaders do the same).

Timing: `--repeats N` runs each side N times per sequence, alternating, and reports the median
wall time (and the ratio of ours to KISS-ICP's); the machine is shared, so one run decides little.

Threads: `--threads N` (default 1) is sgd-icp's `threads=` (its registration, each mini-batch's
queries in two halves from 2, and the surfaces of a frame's points that enter the map) and
KISS-ICP's `max_num_threads`: both sides on the same number of threads.

KISS-ICP (pip kiss-icp) is configured for each sensor: deskewing off (the scans come without
per-point times), on with `--deskew azimuth` (both sides then take each point's time from its
azimuth, KISS-ICP's rule for KITTI); max range 100 m for
LiDAR (its default), 5 m for the Kinect with initial threshold 0.1 m and min motion 0.005 m (its
LiDAR defaults, 2 m and 0.1 m, are larger than the whole motion); voxel its own rule (max range /
100), and with --kiss-our-voxel once more with sgd-icp's voxel size. sgd-icp runs with its
defaults. Metrics are
computed here in NumPy, independently of the library's trajectory_metrics.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

import sgd_icp

LOST_M, LOST_DEG = 0.20, 2.0


def orthonormal(T: np.ndarray) -> np.ndarray:
    U, _, Vt = np.linalg.svd(T[:3, :3])
    out = T.copy()
    out[:3, :3] = U @ np.diag([1, 1, np.linalg.det(U @ Vt)]) @ Vt
    return out


def homogeneous(rows: np.ndarray) -> np.ndarray:
    P = rows.reshape(-1, 3, 4)
    return np.concatenate([P, np.tile([[[0, 0, 0, 1.0]]], (len(P), 1, 1))], axis=1)


@dataclass
class Sequence:
    name: str
    files: list[Path]
    reference: np.ndarray  # T_0_k of the sensor, frame 0 at the identity
    kinect: bool
    intrinsics: Path | None = None


def kitti_reference(folder: Path, frames: int) -> np.ndarray:
    ref = folder / "reference_relative_poses_icp.txt"
    if ref.is_file():
        pairs = {}
        for line in ref.read_text().splitlines():
            v = line.split()
            if len(v) < 14 or v[0].startswith("#"):
                continue
            T = np.eye(4)
            T[:3, :] = np.array(v[2:14], dtype=float).reshape(3, 4)
            pairs[(int(v[0]), int(v[1]))] = T
        poses = [np.eye(4)]
        for k in range(1, frames):
            # Direct (0, k) when measured, else chained from the previous frame.
            poses.append(pairs[(0, k)] if (0, k) in pairs else poses[k - 1] @ pairs[(k - 1, k)])
        return np.array(poses)
    P = homogeneous(np.loadtxt(sorted(folder.glob("poses*.txt"))[0])[:frames])
    Tr = np.eye(4)
    for line in (folder / "calib.txt").read_text().splitlines():
        if line.startswith("Tr:"):
            Tr[:3, :] = np.array(line.split()[1:13], dtype=float).reshape(3, 4)
    return np.linalg.inv(Tr) @ np.linalg.inv(P[0]) @ P @ Tr


def frame_indices(count: int, step: int, irregular_seed: int | None) -> list[int]:
    """Every step-th of `count` frames; with a seed, each next frame 1 to `step` frames on, drawn
    at random: a logger that drops frames, a rate that is not steady."""
    if irregular_seed is None:
        return list(range(0, count, step))
    rng = np.random.default_rng(irregular_seed)
    indices = [0]
    while (k := indices[-1] + int(rng.integers(1, step + 1))) < count:
        indices.append(k)
    return indices


def open_sequence(folder: Path, step: int, max_frames: int, reverse: bool = False,
                  irregular_seed: int | None = None) -> Sequence:
    depth = sorted(folder.glob("frame-*.depth.png"))
    scans = (folder / "scans").is_dir()  # the hand-held LiDAR's layout, else KITTI's velodyne/
    every = depth or sorted((folder / ("scans" if scans else "velodyne")).glob("*.bin"))
    kinect, K = (True, folder / "camera-intrinsics.txt") if depth else (False, None)
    pick = frame_indices(len(every), step, irregular_seed)
    files = [every[i] for i in pick]
    if depth:
        P = np.array([orthonormal(np.loadtxt(str(f).replace(".depth.png", ".pose.txt"))) for f in files])
    elif scans:
        P = homogeneous(np.loadtxt(folder / "poses.txt"))[: len(every)][pick]
    else:
        P = kitti_reference(folder, len(every))[pick]
    if reverse:  # the same frames played backwards: a sequence no default was tuned on
        files, P = files[::-1], P[::-1]
    if max_frames:
        files, P = files[:max_frames], P[:max_frames]
    rate = f"every {step}" if irregular_seed is None else f"every 1-{step} (seed {irregular_seed})"
    name = f"{folder.name} {rate}" + (" reversed" if reverse else "")
    return Sequence(name, files, np.linalg.inv(P[0]) @ P, kinect, K)


def angle_deg(R: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1))))


def ate_rmse_m(est: np.ndarray, ref: np.ndarray) -> float:
    """RMSE of the positions after the rigid least-squares alignment of the estimated onto the
    reference positions (Umeyama 1991, no scale): evo_ape's ATE without --correct_scale. Unlike
    the end drift, every frame's position counts, not the last one's alone."""
    p, q = est[:, :3, 3], ref[:, :3, 3]
    pc, qc = p - p.mean(axis=0), q - q.mean(axis=0)
    U, _, Vt = np.linalg.svd(qc.T @ pc)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
    aligned = (U @ D @ Vt @ pc.T).T + q.mean(axis=0)
    return float(np.sqrt(np.mean(np.sum((aligned - q) ** 2, axis=1))))


SEGMENT_FRACTIONS = (0.125, 0.25, 0.5)


def segment_drift_percent(est: np.ndarray, ref: np.ndarray, fraction: float) -> float:
    """The KITTI devkit's drift on segments of `fraction` of the path (its 100-800 m segments are
    longer than these sequences): from every frame, the translation error of the relative pose to
    the first frame a segment length further along the reference path, over that length, mean
    over the start frames. Unlike the end drift, one lucky or unlucky last frame does not decide
    it (errors that cancel by the end count)."""
    inv = np.linalg.inv
    steps = [np.linalg.norm(ref[k + 1][:3, 3] - ref[k][:3, 3]) for k in range(len(ref) - 1)]
    along = np.concatenate([[0.0], np.cumsum(steps)])
    length = fraction * along[-1]
    errors = []
    for i in range(len(ref)):
        j = int(np.searchsorted(along, along[i] + length))
        if j >= len(ref) or along[j] <= along[i]:
            break
        e = inv(inv(ref[i]) @ ref[j]) @ (inv(est[i]) @ est[j])
        errors.append(np.linalg.norm(e[:3, 3]) / (along[j] - along[i]))
    return float(100 * np.mean(errors)) if errors else float("nan")


def metrics(est: np.ndarray, ref: np.ndarray) -> dict[str, Any]:
    inv = np.linalg.inv
    E = [inv(inv(ref[k]) @ ref[k + 1]) @ (inv(est[k]) @ est[k + 1]) for k in range(len(est) - 1)]
    t = np.array([np.linalg.norm(e[:3, 3]) for e in E])
    r = np.array([angle_deg(e[:3, :3]) for e in E])
    end = inv(inv(ref[0]) @ ref[-1]) @ (inv(est[0]) @ est[-1])
    path = sum(np.linalg.norm(ref[k + 1][:3, 3] - ref[k][:3, 3]) for k in range(len(ref) - 1))
    return {
        "lost": int(np.sum((t > LOST_M) | (r > LOST_DEG))),
        "rpe_t_median_m": float(np.median(t)),
        "rpe_r_median_deg": float(np.median(r)),
        "rpe_t_rmse_m": float(np.sqrt(np.mean(t**2))),
        "rpe_r_rmse_deg": float(np.sqrt(np.mean(r**2))),
        "end_percent": float(100 * np.linalg.norm(end[:3, 3]) / path),
        "end_deg": angle_deg(end[:3, :3]),
        "ate_m": ate_rmse_m(est, ref),
        "segments_percent": [segment_drift_percent(est, ref, f) for f in SEGMENT_FRACTIONS],
    }


def kiss_reader(seq: Sequence) -> Callable[[Path], np.ndarray]:
    """How a KISS-ICP user reads the frames: NumPy for .bin, Pillow + NumPy for depth PNGs."""
    if not seq.kinect:
        return lambda f: np.fromfile(f, dtype=np.float32).reshape(-1, 4)[:, :3].astype(np.float64)
    from PIL import Image

    K = np.loadtxt(seq.intrinsics)

    def read(f: Path) -> np.ndarray:
        z = np.asarray(Image.open(f), dtype=np.float64) / 1000.0
        v, u = np.nonzero((z > 0) & (z < 65.535))
        d = z[v, u]
        return np.stack([(u - K[0, 2]) * d / K[0, 0], (v - K[1, 2]) * d / K[1, 1], d], axis=1)

    return read


def azimuth_times(points: np.ndarray) -> np.ndarray:
    """Each point's place in a clockwise sweep from behind, in [0, 1] (sgd_icp's
    azimuth_times_s, KISS-ICP's rule for KITTI)."""
    return 0.5 * (1.0 - np.arctan2(points[:, 1], points[:, 0]) / np.pi)


def run_ours(seq: Sequence, method: str, threads: int,
             deskew: str = "auto") -> tuple[np.ndarray, float, float, int]:
    start = time.perf_counter()
    odometry = sgd_icp.Odometry(method=method, threads=threads, deskew=deskew)
    for f in seq.files:
        odometry.register_frame(
            sgd_icp.read_depth_image(f, seq.intrinsics) if seq.kinect else sgd_icp.read_points(f)
        )
    wall = time.perf_counter() - start
    return odometry.poses, wall, odometry.voxel_size, odometry.recovered_frames


def run_kiss(seq: Sequence, voxel_size: float | None, threads: int,
             deskew: bool = False) -> tuple[np.ndarray, float]:
    from kiss_icp.config import load_config
    from kiss_icp.kiss_icp import KissICP

    config = load_config(None)
    config.data.deskew = deskew
    config.registration.max_num_threads = threads
    if seq.kinect:
        config.data.max_range = 5.0
        config.mapping.voxel_size = 0.05
        config.adaptive_threshold.initial_threshold = 0.1
        config.adaptive_threshold.min_motion_th = 0.005
    if voxel_size is not None:
        config.mapping.voxel_size = voxel_size
    read = kiss_reader(seq)
    start = time.perf_counter()
    odometry = KissICP(config=config)
    poses = []
    for f in seq.files:
        points = read(f)
        odometry.register_frame(points, azimuth_times(points) if deskew else np.zeros(len(points)))
        poses.append(odometry.last_pose.copy())
    return np.array(poses), time.perf_counter() - start


def print_table(rows: list[tuple[str, str, dict[str, Any], float, str]]) -> None:
    print("| sequence | run | lost | RPE median (mm / deg) | RPE RMSE (mm / deg) "
          "| end drift (% / deg) | segment drift (% at 1/8, 1/4, 1/2 of the path) "
          "| ATE RMSE (mm) | wall s (ms per frame) | notes |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for seq, name, m, wall, notes in rows:
        print(f"| {seq} | {name} | {m['lost']} | {1e3 * m['rpe_t_median_m']:.1f} / "
              f"{m['rpe_r_median_deg']:.3f} | {1e3 * m['rpe_t_rmse_m']:.1f} / "
              f"{m['rpe_r_rmse_deg']:.3f} | {m['end_percent']:.2f} / {m['end_deg']:.2f} | "
              f"{' / '.join(f'{x:.2f}' for x in m['segments_percent'])} | "
              f"{1e3 * m['ate_m']:.1f} | "
              f"{wall:.2f} ({1e3 * wall / m['frames']:.0f}) | {notes} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("folders", type=Path, nargs="+", help="sequence folders (see above)")
    parser.add_argument("--methods", default="sgd", help="sgd-icp methods, comma-separated [default: sgd]")
    parser.add_argument("--steps", default="1", help="frame steps, comma-separated [default: 1]")
    parser.add_argument("--max-frames", type=int, default=0, help="frames per run [default: 0 = all]")
    parser.add_argument("--no-kiss", action="store_true", help="sgd-icp only")
    parser.add_argument("--reverse", action="store_true",
                        help="play each sequence backwards (last frame first): motions and turns "
                        "the defaults were not measured on")
    parser.add_argument("--irregular", default="",
                        help="comma-separated seeds: for each, every next frame is 1 to --steps "
                        "frames on, drawn at random (dropped frames, an unsteady rate) "
                        "[default: none, every step-th frame]")
    parser.add_argument("--deskew", default="auto", choices=["auto", "none", "azimuth"],
                        help="sgd-icp's deskew= (auto: frames with times; none; azimuth: times "
                             "from each point's azimuth, KITTI's sweeps); azimuth also turns "
                             "KISS-ICP's deskewing on with the same times [default: auto]")
    parser.add_argument("--threads", type=int, default=1,
                        help="sgd-icp's num_threads and KISS-ICP's max_num_threads [default: 1]")
    parser.add_argument("--kiss-our-voxel", action="store_true",
                        help="also run KISS-ICP with sgd-icp's voxel size (on the hand-held LiDAR's "
                        "0.21 m it runs 2.5-13 s per frame and loses 16-31 frames)")
    parser.add_argument("--repeats", type=int, default=1,
                        help="runs of each side per sequence, alternating; the median wall time is "
                        "reported (the errors are the first run's) [default: 1]")
    args = parser.parse_args()
    rows = []
    for folder in args.folders:
        seeds = [int(s) for s in args.irregular.split(",")] if args.irregular else [None]
        for step, seed in ((int(s), seed) for s in args.steps.split(",") for seed in seeds):
            seq = open_sequence(folder, step, args.max_frames, args.reverse, seed)
            sides: dict[str, tuple[dict[str, Any], list[float], str]] = {}

            def record(name: str, poses: np.ndarray, wall: float, notes: str) -> None:
                if name not in sides:
                    m = metrics(poses, seq.reference) | {"frames": len(seq.files)}
                    sides[name] = (m, [], notes)
                sides[name][1].append(wall)

            for _ in range(max(args.repeats, 1)):
                voxel = None
                for method in args.methods.split(","):
                    poses, wall, voxel, recovered = run_ours(seq, method, args.threads,
                                                             args.deskew)
                    record(f"sgd-icp {method}", poses, wall,
                           f"voxel {voxel:.3f} m, {recovered} recovered")
                for v in [] if args.no_kiss else [None] + ([voxel] if args.kiss_our_voxel else []):
                    poses, wall = run_kiss(seq, v, args.threads, args.deskew == "azimuth")
                    record("KISS-ICP" if v is None else f"KISS-ICP voxel {v:.3f} m", poses, wall,
                           "its voxel rule" if v is None else f"voxel {v:.3f} m")
            kiss_wall = float(np.median(sides["KISS-ICP"][1])) if "KISS-ICP" in sides else None
            for name, (m, walls, notes) in sides.items():
                wall = float(np.median(walls))
                if name.startswith("sgd-icp") and kiss_wall:
                    notes += f", wall {wall / kiss_wall:.2f}x KISS-ICP's"
                if len(walls) > 1:
                    notes += f", wall s of {len(walls)} runs: " + " ".join(f"{w:.2f}" for w in walls)
                rows.append((seq.name, name, m, wall, notes))
            print(f"{seq.name}: {len(seq.files)} frames done", flush=True)
    print_table(rows)


if __name__ == "__main__":
    main()
