"""Registrations by the peer libraries (small_gicp, Open3D), one function per kind, run in a worker
process (worker.py) or in the caller's.

Timed region of every runner: building the search structure + normals/covariances (+ voxel
downsampling where used) + the registration, from clouds already in the library's own container;
reading the files and converting numpy arrays into that container are not timed. The libraries
are imported on first use, so that this module imports without them.
"""

from __future__ import annotations

import importlib
import math
import time
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from sgd_icp import read_points


@dataclass
class Task:
    """One registration: the clouds' files and the peers' settings (picklable)."""

    source: str
    reference: str
    max_distance_m: float  # maximum correspondence distance
    max_iterations: int
    voxel_m: float  # voxel size of the downsampled variants


@dataclass
class Outcome:
    """The result of one registration (or of a build alone), as measured where it ran."""

    T: np.ndarray | None = None  # T_reference_source; None for a build alone or a failure
    time_ms: float = math.nan  # the timed region
    cpu_ms: float = math.nan  # process CPU time in the timed region (threads used ~ cpu/time)
    build_ms: float = math.nan  # search-structure build alone, where known
    iterations: int = -1
    converged: bool | None = None
    source_points_used: int = -1  # after downsampling, where the method downsamples
    peak_rss_mb: float = math.nan
    status: str = "ok"  # ok, error, timeout, crashed, non-finite
    note: str = ""
    call_ms: float = math.nan  # the caller's wall time of the whole call (process, worker, ...)
    translation_error_m: float = math.nan
    rotation_error_geodesic_deg: float = math.nan
    rotation_error_euler_rad: float = math.nan


_clouds: dict[str, np.ndarray] = {}


def cloud_f64(path: str) -> np.ndarray:
    """The finite points of a file as float64 (N, 3), read once per process (sgd_icp.read_points,
    the CLI's readers)."""
    if path not in _clouds:
        _clouds[path] = read_points(path).astype(np.float64)
    return _clouds[path]


def preload(module: str) -> None:
    """Imports `module` (a worker's start-up, outside any timed region)."""
    importlib.import_module(module)


def timed(fn: Callable[[], Any]) -> tuple[Any, float, float]:
    """fn()'s result, its wall time and its process CPU time, ms."""
    c0 = time.process_time()
    t0 = time.perf_counter()
    result = fn()
    t1 = time.perf_counter()
    c1 = time.process_time()
    return result, (t1 - t0) * 1e3, (c1 - c0) * 1e3


def small_gicp_register(task: Task, registration: str, threads: int, voxel: bool) -> Outcome:
    """small_gicp point-to-point ICP ("ICP") or GICP ("GICP"), at full resolution or after its
    voxel downsampling (GICP: its recommended preprocess_points pipeline)."""
    import small_gicp

    target = small_gicp.PointCloud(cloud_f64(task.reference))
    source = small_gicp.PointCloud(cloud_f64(task.source))
    nt, res = threads, task.voxel_m

    def body():
        if voxel and registration == "GICP":
            # What small_gicp.align(numpy) does: downsample, KdTree, covariances of 10 neighbours.
            tgt, tree = small_gicp.preprocess_points(
                target, downsampling_resolution=res, num_neighbors=10, num_threads=nt
            )
            src, _ = small_gicp.preprocess_points(
                source, downsampling_resolution=res, num_neighbors=10, num_threads=nt
            )
        elif voxel:  # point-to-point needs no covariances: downsample both, KdTree of the target
            tgt = small_gicp.voxelgrid_sampling(target, res, num_threads=nt)
            src = small_gicp.voxelgrid_sampling(source, res, num_threads=nt)
            tree = small_gicp.KdTree(tgt, num_threads=nt)
        else:
            tgt, src = target, source
            tree = small_gicp.KdTree(tgt, num_threads=nt)
            if registration == "GICP":
                small_gicp.estimate_covariances(tgt, tree, num_neighbors=10, num_threads=nt)
                small_gicp.estimate_covariances(src, num_neighbors=10, num_threads=nt)
        r = small_gicp.align(
            tgt,
            src,
            tree,
            registration_type=registration,
            max_correspondence_distance=task.max_distance_m,
            num_threads=nt,
            max_iterations=task.max_iterations,
        )
        return r, src.size()

    (r, n_src), ms, cpu = timed(body)
    return Outcome(
        T=np.array(r.T_target_source),
        time_ms=ms,
        cpu_ms=cpu,
        iterations=int(r.iterations),
        converged=bool(r.converged),
        source_points_used=int(n_src),
        note=f"voxel={res}" if voxel else "",
    )


def small_gicp_kdtree_build(task: Task) -> Outcome:
    """small_gicp.KdTree(reference) alone, one thread."""
    import small_gicp

    cloud = small_gicp.PointCloud(cloud_f64(task.reference))
    _, ms, cpu = timed(lambda: small_gicp.KdTree(cloud, num_threads=1))
    return Outcome(time_ms=ms, cpu_ms=cpu, build_ms=ms)


def open3d_register(task: Task, kind: str) -> Outcome:
    """Open3D registration_icp, "point_to_point" or "point_to_plane" (target normals of 30
    neighbours, estimated in the timed region)."""
    import open3d as o3d

    reg = o3d.pipelines.registration
    target = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(cloud_f64(task.reference)))
    source = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(cloud_f64(task.source)))
    criteria = reg.ICPConvergenceCriteria(max_iteration=task.max_iterations)

    def body():
        if kind == "point_to_plane":
            target.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(knn=30))
            estimation = reg.TransformationEstimationPointToPlane()
        else:
            estimation = reg.TransformationEstimationPointToPoint()
        # registration_icp builds the target's KD-tree itself.
        return reg.registration_icp(source, target, task.max_distance_m, np.eye(4), estimation, criteria)

    r, ms, cpu = timed(body)
    return Outcome(T=np.array(r.transformation), time_ms=ms, cpu_ms=cpu, note=f"fitness={r.fitness:.4g}")
