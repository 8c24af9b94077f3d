#!/usr/bin/env python3
"""sgd-icp odometry against KISS-ICP on the same frames, one run: RPE, ATE, end drift, time per
frame, and the agreement of the two trajectories.

    python bench/compare_odometry.py ../shared/data/kitti_odometry_seq00 [--methods sgd,icp-plane]
    python bench/compare_odometry.py ../shared/data/sevenscenes_redkitchen --max-frames 100

The frames are those of a KITTI sequence folder (velodyne/*.bin) or of a 7-Scenes folder
(frame-*.depth.png back-projected with camera-intrinsics.txt; reference: its frame-*.pose.txt,
re-orthonormalised). For the Kinect KISS-ICP gets max range 5 m (voxel 5 cm by its rule),
initial threshold 0.1 m and min motion 0.005 m (its LiDAR defaults, 2 m and 0.1 m, are larger
than the whole motion). The reference trajectory is the
maintainers' ICP pseudo ground truth of reference_relative_poses_icp.txt when present (the
official poses are 0.15 m per frame off for frames 0-10, PROVENANCE.md), else poses_*.txt moved
into the scanner frame with calib.txt's Tr. KISS-ICP is run with its own defaults (max range
100 m, voxel max_range / 100 = 1 m, 20 points per voxel, adaptive threshold from 2 m), deskewing
off (the scans come without per-point times and sgd-icp does not deskew), on one thread (as
sgd-icp), and once more with sgd-icp's voxel size. Metrics are computed here, in NumPy, as
docs/odometry.md defines them (independently of the library's trajectory_metrics).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import sgd_icp


def orthonormal(T: np.ndarray) -> np.ndarray:
    U, _, Vt = np.linalg.svd(T[:3, :3])
    out = T.copy()
    out[:3, :3] = U @ np.diag([1, 1, np.linalg.det(U @ Vt)]) @ Vt
    return out


def read_reference(folder: Path, frames: int) -> tuple[np.ndarray, str]:
    """Poses T_0_k of the scanner (frame 0 at the identity) and where they came from."""
    poses7 = sorted(folder.glob("frame-*.pose.txt"))
    if poses7:
        P = np.array([orthonormal(np.loadtxt(f)) for f in poses7[:frames]])
        return np.linalg.inv(P[0]) @ P, "7-Scenes pose files (dense tracking)"
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
        return np.array(poses), "ICP pseudo ground truth (reference_relative_poses_icp.txt)"
    gt = sorted(folder.glob("poses*.txt"))[0]
    P = np.loadtxt(gt)[:frames].reshape(-1, 3, 4)
    P = np.concatenate([P, np.tile([[[0, 0, 0, 1.0]]], (len(P), 1, 1))], axis=1)
    Tr = np.eye(4)
    for line in (folder / "calib.txt").read_text().splitlines():
        if line.startswith("Tr:"):
            Tr[:3, :] = np.array(line.split()[1:13], dtype=float).reshape(3, 4)
    P = np.linalg.inv(Tr) @ np.linalg.inv(P[0]) @ P @ Tr
    return P, f"official poses ({gt.name}) in the scanner frame"


def angle_deg(R: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1))))


def metrics(est: np.ndarray, ref: np.ndarray) -> dict[str, float]:
    inv = np.linalg.inv
    E = [inv(inv(ref[k]) @ ref[k + 1]) @ (inv(est[k]) @ est[k + 1]) for k in range(len(est) - 1)]
    t = np.array([np.linalg.norm(e[:3, 3]) for e in E])
    r = np.array([angle_deg(e[:3, :3]) for e in E])
    # ATE: rigid Umeyama alignment of the estimated positions onto the reference.
    p, q = est[:, :3, 3], ref[:, :3, 3]
    pm, qm = p.mean(0), q.mean(0)
    U, _, Vt = np.linalg.svd((q - qm).T @ (p - pm))
    S = np.diag([1, 1, np.sign(np.linalg.det(U @ Vt))])
    R = U @ S @ Vt
    ate = np.sqrt(np.mean(np.sum((p @ R.T + qm - R @ pm - q) ** 2, axis=1)))
    end = inv(inv(ref[0]) @ ref[-1]) @ (inv(est[0]) @ est[-1])
    return {
        "rpe_t_rmse_m": float(np.sqrt(np.mean(t**2))),
        "rpe_r_rmse_deg": float(np.sqrt(np.mean(r**2))),
        "ate_rmse_m": float(ate),
        "end_t_m": float(np.linalg.norm(end[:3, 3])),
        "end_r_deg": angle_deg(end[:3, :3]),
    }


def run_ours(frames: list[np.ndarray], method: str, kinect: bool) -> tuple[np.ndarray, list[float], float]:
    odometry = sgd_icp.Odometry(method=method, **({"max_range": 5.0} if kinect else {}))
    times = []
    for f in frames:
        start = time.perf_counter()
        odometry.register_frame(f)
        times.append(1e3 * (time.perf_counter() - start))
    assert not any(r.failed for r in odometry.reports), [r.message for r in odometry.reports]
    return odometry.poses, times, odometry.voxel_size


def run_kiss(frames: list[np.ndarray], voxel_size: float | None, kinect: bool) -> tuple[np.ndarray, list[float]]:
    from kiss_icp.config import load_config
    from kiss_icp.kiss_icp import KissICP

    config = load_config(None)
    config.data.deskew = False
    config.registration.max_num_threads = 1
    if kinect:
        config.data.max_range = 5.0
        config.mapping.voxel_size = 0.05
        config.adaptive_threshold.initial_threshold = 0.1
        config.adaptive_threshold.min_motion_th = 0.005
    if voxel_size is not None:
        config.mapping.voxel_size = voxel_size
    odometry = KissICP(config=config)
    poses, times = [], []
    for f in frames:
        points = f.astype(np.float64)
        start = time.perf_counter()
        odometry.register_frame(points, np.zeros(len(points)))
        times.append(1e3 * (time.perf_counter() - start))
        poses.append(odometry.last_pose.copy())
    return np.array(poses), times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("folder", type=Path, help="KITTI sequence folder (velodyne/*.bin)")
    parser.add_argument("--methods", default="sgd,sgd-plane,icp-plane",
                        help="sgd-icp methods, comma-separated [default: sgd,sgd-plane,icp-plane]")
    parser.add_argument("--max-frames", type=int, default=0)
    args = parser.parse_args()
    depth = sorted(args.folder.glob("frame-*.depth.png"))
    kinect = bool(depth)
    files = depth or sorted((args.folder / "velodyne").glob("*.bin"))
    if args.max_frames:
        files = files[: args.max_frames]
    K = args.folder / "camera-intrinsics.txt"
    frames = [sgd_icp.read_depth_image(f, K) if kinect else sgd_icp.read_points(f) for f in files]
    ref, ref_name = read_reference(args.folder, len(frames))
    print(f"{len(frames)} frames of {args.folder}; reference: {ref_name}")
    rows, trajectories = [], {}
    voxel = None
    for method in args.methods.split(","):
        poses, times, voxel = run_ours(frames, method, kinect)
        trajectories[f"sgd-icp {method}"] = poses
        rows.append((f"sgd-icp {method} (voxel {voxel:.2f} m)", metrics(poses, ref), times))
    for v in (None, voxel):
        poses, times = run_kiss(frames, v, kinect)
        default = 0.05 if kinect else 1.0
        name = f"KISS-ICP (voxel {default if v is None else v:.2f} m)"
        trajectories[name] = poses
        rows.append((name, metrics(poses, ref), times))
    print("| run | RPE t RMSE (m) | RPE r RMSE (deg) | ATE RMSE (m) | end drift (m / deg) "
          "| median ms per frame (frames 1..) |")
    print("|---|---|---|---|---|---|")
    for name, m, times in rows:
        print(f"| {name} | {m['rpe_t_rmse_m']:.3f} | {m['rpe_r_rmse_deg']:.3f} | "
              f"{m['ate_rmse_m']:.3f} | {m['end_t_m']:.3f} / {m['end_r_deg']:.3f} | "
              f"{np.median(times[1:]):.1f} |")
    names = list(trajectories)
    kiss = next(n for n in names if n.startswith("KISS"))
    for n in names:
        if n.startswith("sgd-icp"):
            d = [np.linalg.norm(a[:3, 3] - b[:3, 3]) for a, b in zip(trajectories[n], trajectories[kiss])]
            print(f"agreement {n} vs {kiss}: largest position difference {max(d):.3f} m")


if __name__ == "__main__":
    main()
