"""sgd-icp and its peer libraries (small_gicp, Open3D, PCL) on the same pairs under one protocol:
identity start, the same maximum correspondence distance and iteration limit for every peer, the
same timed region (search structure + normals/covariances + registration, file I/O excluded), and
every registration in a child process with a time limit, so that a library that hangs or crashes
is recorded ("timeout", "crashed") and the run goes on.

The runners of bench/compare_peers.py and eval/reproduce.py (docs/performance.md): a plain
package folder of the repository, not part of the installed sgd_icp package, which it needs
(`pip install .`). Scripts import it with bench/ on sys.path (a script in bench/ has it there
already; eval/reproduce.py and tests/python/conftest.py add it). The peer libraries are optional
and imported only in the worker processes that run them.

>>> import peers  # with bench/ on sys.path
>>> settings = peers.PeerSettings(timeout_s=30)
>>> methods = {m.name: m for m in peers.build_methods(settings, "build/sgdicp", None)}
>>> pairs = peers.read_pairs("../shared/data/pairs/libpointmatcher_car.txt")
>>> with peers.Session(settings, sgdicp="build/sgdicp") as session:
...     pairs = session.prepare(pairs, [methods["sg_icp_full_1t"]])
...     outcome = session.run(methods["sg_icp_full_1t"], pairs[0])
>>> outcome.status, outcome.time_ms, outcome.translation_error_m
"""

from .cli import BenchRun, run_bench
from .pairs import (
    SUCCESS_THRESHOLDS,
    Errors,
    Pair,
    errors_against,
    pair_line,
    read_pairs,
    write_pairs,
)
from .pcl import PclAdapter, PeerCrashed, PeerTimeout, find_pcl_adapter
from .runners import Outcome, Task
from .session import DEFAULT_VOXEL_M, Method, PeerSettings, Session, build_methods, module_available
from .worker import Reply, Worker

__all__ = [
    "DEFAULT_VOXEL_M",
    "SUCCESS_THRESHOLDS",
    "BenchRun",
    "Errors",
    "Method",
    "Outcome",
    "Pair",
    "PclAdapter",
    "PeerCrashed",
    "PeerSettings",
    "PeerTimeout",
    "Reply",
    "Session",
    "Task",
    "Worker",
    "build_methods",
    "errors_against",
    "find_pcl_adapter",
    "module_available",
    "pair_line",
    "read_pairs",
    "run_bench",
    "write_pairs",
]
