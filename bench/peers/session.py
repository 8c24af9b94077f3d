"""The methods of a comparison (sgd-icp's CLI and the peer libraries) and a Session that runs them
on pairs, each registration in a child process with a time limit.

Where each kind runs:
- "cli": sgd-icp by its CLI (`sgdicp bench --csv`, time_ms = KD-tree build + align()), one process
  per registration, warm as the peers are: the process first registers the pair once untimed
  (the round's seed - 1), then the timed registration (the round's seed).
- "worker": a Python peer (small_gicp, Open3D) in a worker process of its library (worker.py),
  warm: the clouds are read once per worker and one untimed warm-up run per method precedes the
  timed runs (again after the worker was restarted).
- "pcl": PCL in its C++ adapter (pcl.py), the same way.
A run longer than the time limit is stopped and recorded as "timeout", a child that dies as
"crashed"; neither stops the session.
"""

from __future__ import annotations

import functools
import importlib
import os
import subprocess
import sys
import tempfile
import warnings
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from sgd_icp import read_point_cloud
from . import runners
from .cli import run_bench
from .pairs import Pair, errors_against
from .pcl import PclAdapter, PeerCrashed, PeerTimeout
from .runners import Outcome, Task
from .worker import Worker

# small_gicp's README value 0.25 m for outdoor LiDAR, scaled down for the small scenes; metres.
DEFAULT_VOXEL_M = {
    "kitti_seq00": 0.25,
    "kitti_seq00_moved_copies": 0.25,
    "libpointmatcher_car": 0.25,
    "pcl_kinect_frames": 0.02,
    "eth_kinect_map_moved_copies": 0.02,
    "pcl_bunny": 0.002,
    "sevenscenes_redkitchen": 0.02,  # Kinect frames (bench/make_sevenscenes_pairs.py)
    "sevenscenes_table1": 0.02,  # eval/reproduce.py's sevenscenes_table1_Napart pairs files
}


@dataclass
class PeerSettings:
    """The protocol's settings: the same for every peer; sgd-icp runs with its own defaults."""

    max_distance_m: float = 0.5  # peers' maximum correspondence distance
    max_iterations: int = 30  # peers' iteration limit (Open3D's default)
    timeout_s: float = 30.0  # a registration (or CLI run) longer than this is stopped
    threads: int = os.cpu_count() or 1  # of small_gicp's multi-threaded variants
    voxel_m: dict[str, float] = field(default_factory=lambda: dict(DEFAULT_VOXEL_M))
    default_voxel_m: float = 0.25  # for a pairs file not in voxel_m
    _warned: set[str] = field(default_factory=set, repr=False, compare=False)

    def voxel_for(self, pairs_file: str) -> float:
        """The voxel of a pairs file stem: its entry, else the longest entry it starts with (the
        7-Scenes Table I files sevenscenes_table1_1apart, ...), else default_voxel_m with a
        warning (once per stem): a 0.25 m grid on a small scene would be an unfair peer."""
        if pairs_file in self.voxel_m:
            return self.voxel_m[pairs_file]
        prefixes = [k for k in self.voxel_m if pairs_file.startswith(k)]
        if prefixes:
            return self.voxel_m[max(prefixes, key=len)]
        if pairs_file not in self._warned:
            self._warned.add(pairs_file)
            warnings.warn(f"peers: no voxel size for the pairs file '{pairs_file}'; the peers "
                          f"downsample it with {self.default_voxel_m} m (add it to voxel_m)",
                          stacklevel=2)
        return self.default_voxel_m


@dataclass
class Method:
    """A method of the comparison. `spec` by kind: "cli", extra CLI arguments; "worker", a
    picklable fn(Task) -> Outcome; "pcl", the adapter's method name."""

    name: str
    family: str  # sgd-icp, small_gicp, open3d, pcl, build-only
    description: str
    threads: str
    kind: str
    spec: Any = None
    available: bool = True
    why_not: str = ""
    module: str | None = None  # the library a worker imports when it starts (untimed)


def module_available(module: str, pip_name: str, install: bool) -> tuple[bool, str]:
    """Whether `module` imports (checked in a child Python, so that this process does not load
    it), after `pip install pip_name` if it does not and `install`; (False, why) if not."""

    def check() -> str:
        p = subprocess.run([sys.executable, "-c", f"import {module}"], capture_output=True, text=True)
        return "" if p.returncode == 0 else (p.stderr.strip().splitlines() or ["?"])[-1]

    why = check()
    if not why:
        return True, ""
    if not install:
        return False, f"import {module} failed ({why}); pip install {pip_name}"
    print(f"[setup] {module} missing, running pip install {pip_name}", file=sys.stderr, flush=True)
    p = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", pip_name],
                       capture_output=True, text=True)
    if p.returncode != 0:
        return False, f"pip install {pip_name} failed: {p.stderr.strip()[-200:]}"
    importlib.invalidate_caches()
    why = check()  # e.g. Open3D needs libusb-1.0-0 from apt
    return (True, "") if not why else (False, f"import {module} failed after install ({why})")


def build_methods(settings: PeerSettings, sgdicp: str | None, pcl_adapter: str | None,
                  install: bool = False) -> list[Method]:
    """Every method, available or not (why_not says why). sgdicp: the CLI; pcl_adapter: the PCL
    adapter's executable (pcl.find_pcl_adapter); install: pip-install missing Python peers."""
    nt = settings.threads
    cli_ok = bool(sgdicp) and os.path.exists(sgdicp)
    cli_why = "" if cli_ok else f"{sgdicp} not found (scripts/build.sh)"
    methods = [
        Method("sgdicp", "sgd-icp", "sgd-icp defaults (CLI), d_max 0.5 scaled", "1", "cli", [],
               cli_ok, cli_why),
        Method("sgdicp_dmax0.5m", "sgd-icp", "sgd-icp defaults but d_max = 0.5 m", "1", "cli",
               ["-d", str(settings.max_distance_m), "--max-distance-unit", "m"], cli_ok, cli_why),
        Method("sgdicp_plane", "sgd-icp", "sgd-icp --method sgd-plane (normals on first use)", "1",
               "cli", ["--method", "sgd-plane"], cli_ok, cli_why),
        Method("sgdicp_gicp", "sgd-icp", "sgd-icp --method sgd-gicp (covariances on first use)",
               "1", "cli", ["--method", "sgd-gicp"], cli_ok, cli_why),
        Method("sgdicp_plane_vox", "sgd-icp",
               "sgd-icp --method sgd-plane on the peers' voxel grid (--voxel-size, timed)", "1",
               "cli", ["--method", "sgd-plane", "--voxel-size", "{voxel}"], cli_ok, cli_why),
        Method("sgdicp_gicp_vox", "sgd-icp",
               "sgd-icp --method sgd-gicp on the peers' voxel grid (--voxel-size, timed)", "1",
               "cli", ["--method", "sgd-gicp", "--voxel-size", "{voxel}"], cli_ok, cli_why),
    ]
    ok, why = module_available("small_gicp", "small_gicp", install)
    for reg, label in (("ICP", "icp"), ("GICP", "gicp")):
        for voxel in (False, True):
            for threads in (1, nt):
                name = f"sg_{label}_{'vox' if voxel else 'full'}_{threads}t"
                desc = (f"small_gicp {reg}, {'voxel-downsampled' if voxel else 'full resolution'}, "
                        f"{threads} thread(s)")
                run = functools.partial(runners.small_gicp_register, registration=reg, threads=threads,
                                        voxel=voxel)
                methods.append(Method(name, "small_gicp", desc, str(threads), "worker", run, ok, why,
                                      "small_gicp"))
    ok3, why3 = module_available("open3d", "open3d", install)
    for kind, name in (("point_to_point", "o3d_p2p_1t"), ("point_to_plane", "o3d_p2plane_1t")):
        desc = f"Open3D ICP {kind.replace('_', '-')}" + (
            " (normals of 30 neighbours, timed)" if kind == "point_to_plane" else "")
        run = functools.partial(runners.open3d_register, kind=kind)
        methods.append(Method(name, "open3d", desc, "1", "worker", run, ok3, why3, "open3d"))
    pcl_why = "" if pcl_adapter else (
        "PCL adapter not built (apt-get install libpcl-dev; cmake -DSGDICP_BUILD_BENCHMARKS=ON)")
    for method, name, desc in (
            ("icp", "pcl_icp_1t", "PCL IterativeClosestPoint (point-to-point)"),
            ("icp_plane", "pcl_p2plane_1t",
             "PCL ICP with normals (point-to-plane; normals of 30 neighbours, timed)"),
            ("gicp", "pcl_gicp_1t", "PCL GeneralizedIterativeClosestPoint")):
        methods.append(Method(name, "pcl", desc, "1", "pcl", method, pcl_adapter is not None, pcl_why))
    methods.append(Method("sg_kdtree_build", "build-only",
                          "small_gicp.KdTree(reference) build alone, 1 thread", "1", "worker",
                          runners.small_gicp_kdtree_build, ok, why, "small_gicp"))
    return methods


def _worker_family(method: Method) -> str:
    """The worker a method runs in: one per library (the KdTree build runs with small_gicp)."""
    return "small_gicp" if method.family == "build-only" else method.family


class Session:
    """Runs methods on pairs; see the module's docstring. A context manager (close() ends the
    children and removes the temporary files)."""

    def __init__(self, settings: PeerSettings, sgdicp: str | None = None,
                 pcl_adapter: str | None = None,
                 log: Callable[[str], None] = lambda msg: print(msg, file=sys.stderr, flush=True)):
        self.settings = settings
        self.sgdicp = sgdicp
        self.log = log
        self.points: dict[str, int] = {}  # cloud path -> finite points, for readable clouds
        self._tmp = tempfile.TemporaryDirectory(prefix="sgdicp_peers_")
        self._pcl_exe = pcl_adapter
        self._pcl: PclAdapter | None = None
        self._f32: dict[str, str] = {}  # cloud path -> .f32 copy for the PCL adapter
        self._workers: dict[str, Worker] = {}
        self._warm_up: dict[str, list[tuple[Method, Pair]]] = {}  # backend -> runs to redo on start
        self._warm_starts: dict[str, int] = {}  # backend -> its `starts` at the last warm-up

    def prepare(self, pairs: list[Pair], methods: list[Method]) -> list[Pair]:
        """Reads every cloud of `pairs` once (counts; .f32 copies if a PCL method is active) and
        registers one untimed warm-up run per worker or PCL method on the smallest pair (done
        when its process starts). Returns the pairs whose clouds could be read."""
        uses_pcl = any(m.kind == "pcl" for m in methods)
        paths = list(dict.fromkeys(path for p in pairs for path in (p.source, p.reference)))
        self.log(f"[setup] reading {len(paths)} clouds")
        for path in paths:
            if path in self.points:
                continue
            try:
                points = read_point_cloud(path).points
            except (OSError, ValueError) as e:
                self.log(f"[setup] cannot read {path}: {e}")
                continue
            self.points[path] = len(points)
            if uses_pcl:
                f32 = os.path.join(self._tmp.name, f"c{len(self._f32)}.f32")
                points.astype("<f4").tofile(f32)
                self._f32[path] = f32
        readable = [p for p in pairs if p.source in self.points and p.reference in self.points]
        if readable:
            smallest = min(readable, key=lambda p: self.points[p.source])
            for m in methods:
                if m.kind in ("worker", "pcl"):
                    self._warm_up.setdefault(self._backend_name(m), []).append((m, smallest))
        return readable

    def run(self, method: Method, pair: Pair, rep: int = 0) -> Outcome:
        """One registration of `pair` by `method` (round `rep`: the CLI's seed is 2019 + rep), with
        its errors against the ground truth; status "timeout", "crashed", "error" or "non-finite"
        instead of an exception."""
        try:
            if method.kind == "cli":
                o = self._run_cli(method, pair, rep)
            elif method.kind == "worker":
                o = self._run_worker(method, pair)
            elif method.kind == "pcl":
                o = self._run_pcl(method, pair)
            else:
                raise ValueError(f"unknown kind of method {method.kind!r}")
        except Exception as e:  # noqa: BLE001 - a failing method is a row, never fatal
            o = Outcome(status="error", note=str(e).replace("\n", " ")[:300])
        if o.T is not None:
            e = errors_against(o.T, pair.T_gt)
            o.translation_error_m = e.translation_m
            o.rotation_error_geodesic_deg = e.rotation_geodesic_deg
            o.rotation_error_euler_rad = e.rotation_euler_rad
            if not np.all(np.isfinite(o.T)) and o.status == "ok":
                o.status = "non-finite"
        return o

    def _task(self, pair: Pair) -> Task:
        s = self.settings
        return Task(pair.source, pair.reference, s.max_distance_m, s.max_iterations,
                    s.voxel_for(pair.pairs_file))

    def _run_cli(self, method: Method, pair: Pair, rep: int) -> Outcome:
        # "{voxel}" in a CLI method's arguments: the pairs file's voxel size, the peers' own.
        voxel = str(self.settings.voxel_for(pair.pairs_file))
        args = [a.replace("{voxel}", voxel) for a in method.spec]
        # `--repeat 2` from the seed before the round's: repeat 0 warms the process (its caches,
        # its allocator's pages) as the peers' untimed warm-up run does theirs, and repeat 1 is
        # the round's registration (seed 2019 + rep), the one timed.
        run = run_bench(self.sgdicp, [pair],
                        ["--seed", str(2019 + rep - 1), "--repeat", "2"] + args,
                        self._tmp.name, self.settings.timeout_s, peak_rss=True)
        if run.status == "timeout":
            return Outcome(status="timeout", time_ms=self.settings.timeout_s * 1e3, note=run.note,
                           call_ms=run.wall_ms)
        if run.status != "ok":
            return Outcome(status=run.status, note=run.note, call_ms=run.wall_ms)
        row = next((r for r in run.rows if r["repeat"] == "1"), None)
        if row is None:
            return Outcome(status="error", note="no timed row (repeat 1) in the CLI's CSV",
                           call_ms=run.wall_ms)
        # The CSV has no T; its errors are the CLI's, by the same definitions.
        return Outcome(time_ms=float(row["time_ms"]), build_ms=float(row["build_ms"]),
                       iterations=int(row["iterations"]), converged=row["converged"] == "1",
                       peak_rss_mb=run.peak_rss_mb, call_ms=run.wall_ms,
                       translation_error_m=float(row["translation_error_m"]),
                       rotation_error_geodesic_deg=float(row["rotation_error_geodesic_deg"]),
                       rotation_error_euler_rad=float(row["rotation_error_euler_rad"]),
                       note=f"stop={row['stop_reason']}")

    def _run_worker(self, method: Method, pair: Pair) -> Outcome:
        family = _worker_family(method)
        if family not in self._workers:
            self._workers[family] = Worker(family, env={"OMP_NUM_THREADS": "1"})
        worker = self._workers[family]
        if not worker.alive:
            worker.start()
        self._warm(family, worker)
        return self._call(worker, method, pair)

    def _call(self, worker: Worker, method: Method, pair: Pair) -> Outcome:
        reply = worker.call(method.spec, self._task(pair), timeout_s=self.settings.timeout_s)
        if reply.status == "timeout":
            o = Outcome(status="timeout", time_ms=self.settings.timeout_s * 1e3, note=reply.note)
        elif reply.status == "ok":
            o = reply.value
        else:
            o = Outcome(status=reply.status, note=reply.note)
        o.call_ms = reply.wall_ms
        return o

    def _run_pcl(self, method: Method, pair: Pair) -> Outcome:
        if self._pcl is None:
            self._pcl = PclAdapter(self._pcl_exe)
        if not self._pcl.alive:
            self._pcl.start()
        self._warm("pcl", self._pcl)
        return self._pcl_call(method, pair)

    def _pcl_call(self, method: Method, pair: Pair) -> Outcome:
        """One PCL run; the adapter's timeout or crash as a status."""
        s = self.settings
        try:
            return self._pcl.register(method.spec, self._f32[pair.source], self._f32[pair.reference],
                                      s.max_distance_m, s.max_iterations, s.timeout_s)
        except PeerTimeout as e:
            return Outcome(status="timeout", time_ms=s.timeout_s * 1e3, note=str(e))
        except PeerCrashed as e:
            return Outcome(status="crashed", note=str(e))

    def _backend_name(self, method: Method) -> str:
        return "pcl" if method.kind == "pcl" else _worker_family(method)

    def _warm(self, name: str, backend: Worker | PclAdapter) -> None:
        """Once per start of `name`'s process: the import of its libraries (its start-up time
        limit), then the untimed warm-up run of each of its methods (the registration time limit;
        a warm-up that fails is dropped, so that a hanging one costs that limit only once)."""
        if self._warm_starts.get(name) == backend.starts:
            return
        self._warm_starts[name] = backend.starts
        runs = self._warm_up.get(name, [])
        if isinstance(backend, Worker):
            for module in dict.fromkeys(m.module for m, _ in runs if m.module):
                reply = backend.call(runners.preload, module, timeout_s=backend.start_timeout_s)
                if reply.status != "ok":
                    self.log(f"[warm-up] import {module}: {reply.status} {reply.note}")
        for m, pair in list(runs):
            try:
                o = self._pcl_call(m, pair) if m.kind == "pcl" else self._call(backend, m, pair)
            except Exception as e:  # noqa: BLE001 - e.g. the adapter's "err" answer
                o = Outcome(status="error", note=str(e))
            if o.status != "ok":
                self.log(f"[warm-up] {m.name} {pair.label}: {o.status} {o.note} (no warm-up for it)")
                runs.remove((m, pair))
        if backend.starts != self._warm_starts[name]:  # a warm-up stopped it: warm the next start
            self._warm_starts.pop(name)

    def close(self) -> None:
        for w in self._workers.values():
            w.close()
        self._workers.clear()
        if self._pcl is not None:
            self._pcl.close()
            self._pcl = None
        self._tmp.cleanup()

    def __enter__(self) -> Session:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
