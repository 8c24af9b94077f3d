"""PCL as a peer: the C++ adapter bench/pcl_adapter (built with -DSGDICP_BUILD_BENCHMARKS=ON) as a
child process with a line protocol, so that its clouds are loaded once; a run that does not
answer within the time limit kills it, and the next request starts it again."""

from __future__ import annotations

import glob
import os
import select
import subprocess

import numpy as np

from .runners import Outcome


class PeerTimeout(RuntimeError):
    """The adapter did not answer in time (it was stopped)."""


class PeerCrashed(RuntimeError):
    """The adapter died during a request."""


def find_pcl_adapter(explicit: str | None, repo_root: str) -> str | None:
    """`explicit` if it exists, else the adapter of build-bench/ or any build*/ of `repo_root`."""
    if explicit:
        return explicit if os.path.exists(explicit) else None
    for pattern in (
        "build-bench/bench/pcl_adapter/sgdicp_pcl_adapter",
        "build*/bench/pcl_adapter/sgdicp_pcl_adapter",
    ):
        for candidate in sorted(glob.glob(os.path.join(repo_root, pattern))):
            if os.access(candidate, os.X_OK):
                return candidate
    return None


class PclAdapter:
    """The adapter process; `starts` counts its starts (a caller redoes its warm-up after one)."""

    def __init__(self, exe: str, load_timeout_s: float = 120.0):
        self.exe = exe
        self.load_timeout_s = load_timeout_s
        self.starts = 0
        self._p = None
        self._loaded: dict[str, str] = {}  # .f32 path -> name in the adapter

    @property
    def alive(self) -> bool:
        return self._p is not None and self._p.poll() is None

    def start(self) -> None:
        self.close()
        self._p = subprocess.Popen(
            [self.exe],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
            bufsize=1,
        )
        self._loaded = {}
        self.starts += 1

    def _ask(self, line: str, timeout_s: float) -> list[str]:
        if not self.alive:
            self.start()
        try:
            self._p.stdin.write(line + "\n")
            self._p.stdin.flush()
        except (BrokenPipeError, OSError) as e:
            self._kill()
            raise PeerCrashed(f"PCL adapter gone ({e})") from e
        ready, _, _ = select.select([self._p.stdout], [], [], timeout_s)
        if not ready:
            self._kill()
            raise PeerTimeout(f"no answer within {timeout_s:g} s (the PCL adapter was stopped)")
        answer = self._p.stdout.readline()
        if not answer:
            code = self._kill()
            raise PeerCrashed(f"the PCL adapter exited ({code})")
        parts = answer.split()
        if parts[0] != "ok":
            raise RuntimeError(answer.strip())
        return parts[1:]

    def register(self, method: str, source_f32: str, reference_f32: str, max_distance_m: float,
                 max_iterations: int, timeout_s: float) -> Outcome:
        """One registration by `method` (icp, icp_plane, gicp) of two headerless .f32 clouds."""
        s = self._ensure(source_f32)
        r = self._ensure(reference_f32)
        v = self._ask(f"run {method} {s} {r} {max_distance_m} {max_iterations}", timeout_s)
        T = np.array([float(x) for x in v[5:21]]).reshape(4, 4)
        return Outcome(T=T, time_ms=float(v[0]), cpu_ms=float(v[1]), iterations=int(v[2]),
                       converged=v[3] == "1", note=f"fitness={float(v[4]):.4g}")

    def _ensure(self, f32_path: str) -> str:
        if not self.alive:
            self.start()
        if f32_path not in self._loaded:
            name = f"c{len(self._loaded)}"
            self._ask(f"load {name} {f32_path}", self.load_timeout_s)
            self._loaded[f32_path] = name
        return self._loaded[f32_path]

    def _kill(self) -> str:
        p, self._p = self._p, None
        if p is None:
            return "not running"
        if p.poll() is None:
            p.kill()
        code = p.wait()
        return f"status {code}"

    def close(self) -> None:
        if self._p is None:
            return
        try:
            self._p.stdin.write("quit\n")
            self._p.stdin.flush()
            self._p.wait(timeout=10)
            self._p = None
        except (OSError, subprocess.TimeoutExpired):
            self._kill()
