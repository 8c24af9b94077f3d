"""Many registrations on a Dask cluster: sgd_icp.distributed.register_pairs.

>>> from sgd_icp.distributed import register_pairs
>>> rows = register_pairs("pairs/kitti_seq00.txt")                 # a LocalCluster on this machine
>>> rows = register_pairs(pairs, client=Client("tcp://host:8786"), method="gicp", seed=7)

Paths, not arrays, travel to the workers: each worker reads its clouds itself and keeps the
reference indexes it built (keyed by file and settings), so a reference shared by several pairs is
indexed once per worker. Results come back in input order, equal to sgd_icp.register on the same
files with the same settings; a pair that fails (a bad file, an invalid cloud) is reported in its
row. dask.distributed is imported only here (pip install sgd-icp[distributed]). See
docs/distributed.md.
"""

from __future__ import annotations

import os
import threading
import time
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Any, Optional, Sequence, Union

import numpy as np

import sgd_icp

__all__ = ["PairResult", "register_pair", "register_pairs", "read_jobs"]

PathLike = Union[str, "os.PathLike[str]"]


@dataclass
class PairResult:
    """One row of register_pairs: the pair, and its result or its error."""

    index: int  #: position in the input (0-based)
    source: str
    reference: str
    line: Optional[int] = None  #: line in the pairs file (None for a list of pairs)
    ok: bool = False  #: False when the pair failed; `error` then says why
    error: Optional[str] = None  #: "ExceptionType: message"
    T_reference_source: Optional[np.ndarray] = None  #: (4, 4) float64, metres
    converged: bool = False
    stop_reason: str = ""
    iterations: int = 0
    points_processed: int = 0
    inlier_rmse_m: float = float("nan")
    degenerate: bool = False
    time_ms: float = 0.0  #: registration (result.time_ms)
    build_ms: float = 0.0  #: reference index built for this pair (0 when it came from the cache)
    reference_cached: bool = False  #: the worker had already indexed this reference
    translation_error_m: Optional[float] = None  #: against the pairs file's ground truth
    rotation_error_deg: Optional[float] = None  #: geodesic, against the ground truth
    worker: str = ""  #: the worker that ran it ("" for a local run)
    T_gt: Optional[np.ndarray] = field(default=None, repr=False)


@dataclass(frozen=True)
class _Job:
    index: int
    source: str
    reference: str
    init: Any = None  # None (identity), a (4, 4) array or a transform file
    T_gt: Optional[np.ndarray] = None
    line: Optional[int] = None


def read_jobs(pairs: Union[PathLike, Sequence[Sequence[Any]]]) -> list[_Job]:
    """The registration problems of `pairs`: a pairs file (read by the library's parser,
    sgd_icp.read_pairs, the format of `sgdicp bench`), or a sequence of (source, reference) or
    (source, reference, init) with init a (4, 4) array, a transform file or None."""
    if isinstance(pairs, (str, os.PathLike)):
        return [
            _Job(i, source, reference, None, T_gt, line)
            for i, (source, reference, T_gt, line) in enumerate(sgd_icp.read_pairs(pairs))
        ]
    jobs = []
    for i, pair in enumerate(pairs):
        if isinstance(pair, (str, os.PathLike)) or len(pair) not in (2, 3):
            raise TypeError(
                f"pairs[{i}] must be (source, reference) or (source, reference, init), got {pair!r}"
            )
        init = pair[2] if len(pair) == 3 else None
        if isinstance(init, os.PathLike):
            init = os.fspath(init)
        jobs.append(_Job(i, os.fspath(pair[0]), os.fspath(pair[1]), init))
    return jobs


# ---- on the worker

_CACHE_LOCK = threading.Lock()
_INDEXES: "OrderedDict[tuple, Any]" = OrderedDict()  # this process's reference indexes


def _settings_key(method: str, settings: dict) -> str:
    return repr((method, sorted((k, repr(v)) for k, v in settings.items())))


def _reference_index(path: str, method: str, settings: dict, capacity: int):
    """(index, build_ms, cached): the index of `path` for these settings, built once per process
    (the newest `capacity` are kept); a changed file is read again."""
    try:
        st = os.stat(path)
    except OSError:
        sgd_icp.read_points(path)  # raises the library's IoError, which names the file
        raise
    key = (os.path.abspath(path), st.st_mtime_ns, st.st_size, _settings_key(method, settings))
    with _CACHE_LOCK:
        if key in _INDEXES:
            _INDEXES.move_to_end(key)
            return _INDEXES[key], 0.0, True
    points = sgd_icp.read_points(path)
    options = dict(settings)
    base = options.pop("settings", None)
    index = sgd_icp.ReferenceIndex.for_registration(points, method=method, settings=base, **options)
    with _CACHE_LOCK:
        _INDEXES[key] = index
        while len(_INDEXES) > capacity:
            _INDEXES.popitem(last=False)
    return index, index.build_ms, False


def register_pair(job: _Job, method: str = "sgd", settings: Optional[dict] = None,
                  cache_size: int = 8) -> PairResult:
    """Registers one job where it runs (a worker, or here): reads the source, takes the reference
    index from this process's cache, and returns its row; an error of the library (a bad file, an
    invalid cloud) is reported in the row, not raised."""
    settings = dict(settings or {})
    row = PairResult(job.index, job.source, job.reference, job.line, T_gt=job.T_gt)
    try:
        from distributed import get_worker

        row.worker = get_worker().address
    except (ImportError, ValueError):
        pass
    try:
        index, row.build_ms, row.reference_cached = _reference_index(
            job.reference, method, settings, cache_size
        )
        source = sgd_icp.read_points(job.source)
        init = sgd_icp.read_transform(job.init) if isinstance(job.init, str) else job.init
        r = sgd_icp.register(source, index, init=init, method=method, **settings)
    except (sgd_icp.Error, OSError) as e:
        row.error = f"{type(e).__name__}: {e}"
        return row
    row.ok = True
    row.T_reference_source = r.T_reference_source
    row.converged, row.stop_reason, row.degenerate = r.converged, r.stop_reason, r.degenerate
    row.iterations, row.points_processed = r.iterations, r.points_processed
    row.inlier_rmse_m, row.time_ms = r.inlier_rmse_m, r.time_ms
    if job.T_gt is not None:
        row.translation_error_m = sgd_icp.translation_error(r.T_reference_source, job.T_gt)
        row.rotation_error_deg = float(
            np.degrees(sgd_icp.rotation_error_geodesic(r.T_reference_source, job.T_gt))
        )
    return row


# ---- on the client


def _check_settings(method: str, settings: dict) -> None:
    """Raises here, before any task is sent, the error every pair would report (an unknown
    method or keyword, an invalid value): the index of a small cloud for these settings."""
    probe = np.random.default_rng(0).random((64, 3))
    options = dict(settings)
    base = options.pop("settings", None)
    sgd_icp.ReferenceIndex.for_registration(probe, method=method, settings=base, **options)


def local_client(workers: Optional[int] = None, threads_per_worker: int = 1):
    """A dask.distributed Client of a LocalCluster with `workers` processes (default: the cores)
    of `threads_per_worker` threads each."""
    from distributed import Client, LocalCluster

    cluster = LocalCluster(
        n_workers=workers or os.cpu_count() or 1,
        threads_per_worker=threads_per_worker,
        processes=True,
        dashboard_address=None,
    )
    return Client(cluster)


def register_pairs(
    pairs: Union[PathLike, Sequence[Sequence[Any]]],
    client=None,
    method: str = "sgd",
    *,
    retries: int = 2,
    cache_size: int = 8,
    progress: bool = False,
    **settings,
) -> list[PairResult]:
    """Registers every pair on a Dask cluster and returns one PairResult per pair, in input order.

    pairs: a pairs file (shared/data/PAIRS.md; errors then carry its ground truth) or a sequence of
    (source, reference[, init]) paths. client: a dask.distributed.Client (None: a LocalCluster on
    this machine, one single-threaded worker per core, closed at the end). method and **settings:
    those of sgd_icp.register (settings= a Settings or BatchSettings, and the keyword overrides,
    seed= among them). retries: how often Dask runs a task again that raised an error the library
    does not report in its row (a task whose worker is lost is rescheduled by the scheduler itself,
    up to its distributed.scheduler.allowed-failures).
    cache_size: reference indexes each worker keeps. progress: show dask's progress bar.

    Paths travel to the workers, which must see the files under the same names (a shared file
    system). A pair whose files cannot be read or registered is reported in its row (ok False,
    error); an invalid method or setting raises here before anything is sent.
    """
    return _run_jobs(read_jobs(pairs), client, method, settings, retries=retries,
                     cache_size=cache_size, progress=progress)


def _run_jobs(jobs: list, client, method: str, settings: dict, *, retries: int = 2,
              cache_size: int = 8, progress: bool = False) -> list[PairResult]:
    """register_pairs of jobs already read (the command line's, from several pairs files)."""
    _check_settings(method, settings)
    own_client = client is None
    if own_client:
        client = local_client()
    try:
        futures = client.map(
            register_pair,
            jobs,
            method=method,
            settings=settings,
            cache_size=cache_size,
            retries=retries,
            pure=False,
        )
        if progress:
            from distributed import progress as progress_bar

            progress_bar(futures)
        return [_row_of(future, job) for future, job in zip(futures, jobs)]
    finally:
        if own_client:
            cluster = client.cluster
            client.close()
            cluster.close()


def _row_of(future, job: "_Job") -> PairResult:
    """The future's row, or a row with the error of a task that failed after its retries (a lost
    worker)."""
    try:
        return future.result()
    except Exception as e:  # noqa: BLE001 - any task failure is reported in its row
        return PairResult(job.index, job.source, job.reference, job.line,
                          error=f"{type(e).__name__}: {e}", T_gt=job.T_gt)
