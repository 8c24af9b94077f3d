"""A child process that runs one task at a time under a time limit.

A task that does not answer in time gets its child killed (a library that hangs cannot stall the
caller) and one that kills its child (a segfault) is reported; the next task starts a new child.
Tasks are picklable callables (module-level functions, functools.partial of them) and their
arguments; the child is started with multiprocessing's 'spawn' method, so it shares no state
(threads, OpenMP pools, locks) with the caller. As with any 'spawn' child, the caller's main
script is imported in the child: it must start its work under `if __name__ == "__main__":`.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import signal
import time
from dataclasses import dataclass
from typing import Any, Callable


@dataclass
class Reply:
    """What became of a task."""

    status: str  # "ok", "error" (the task raised), "timeout" or "crashed" (its child died)
    value: Any = None  # the task's return value when "ok"
    note: str = ""  # why, when not "ok"
    wall_ms: float = math.nan  # the caller's wall time: sending, the task, the answer


def _serve(conn, env: dict[str, str]) -> None:
    """The child's loop: (fn, args) in, ("ok", value) or ("error", message) out; None ends it."""
    os.environ.update(env)
    conn.send("ready")
    while True:
        try:
            task = conn.recv()
        except EOFError:
            return
        except Exception as e:  # noqa: BLE001 - e.g. the task's module cannot be imported here
            conn.send(("error", f"cannot unpickle the task: {e!r}"))
            continue
        if task is None:
            return
        fn, args = task
        try:
            answer = ("ok", fn(*args))
        except Exception as e:  # noqa: BLE001 - reported to the caller, the child goes on
            answer = ("error", f"{type(e).__name__}: {e}".replace("\n", " ")[:300])
        try:
            conn.send(answer)
        except Exception as e:  # noqa: BLE001 - an unpicklable result
            conn.send(("error", f"cannot send the result: {e!r}"))


class Worker:
    """One child process for tasks of one kind (e.g. one peer library).

    `env` is set in the child's environment before its interpreter starts (e.g.
    OMP_NUM_THREADS=1, read by OpenMP when a library loads). The child starts on the first call,
    or by start(); `starts` counts how often, so that a caller can redo per-process set-up (a
    warm-up run) after a restart.
    """

    def __init__(self, name: str, env: dict[str, str] | None = None, start_timeout_s: float = 120.0):
        self.name = name
        self.env = dict(env or {})
        self.start_timeout_s = start_timeout_s
        self.starts = 0
        self._proc = None
        self._conn = None

    @property
    def alive(self) -> bool:
        return self._proc is not None and self._proc.is_alive()

    def start(self) -> None:
        """Starts the child (a running one is stopped first); raises RuntimeError if it does not
        come up within start_timeout_s."""
        self.close()
        ctx = multiprocessing.get_context("spawn")
        parent, child = ctx.Pipe()
        proc = ctx.Process(target=_serve, args=(child, self.env), name=f"worker-{self.name}", daemon=True)
        saved = {k: os.environ.get(k) for k in self.env}
        os.environ.update(self.env)  # inherited by the spawned interpreter
        try:
            proc.start()
        finally:
            for k, v in saved.items():
                if v is None:
                    os.environ.pop(k, None)
                else:
                    os.environ[k] = v
        child.close()
        self._proc, self._conn = proc, parent
        self.starts += 1
        try:
            ready = parent.poll(self.start_timeout_s) and parent.recv() == "ready"
        except (EOFError, OSError):
            ready = False
        if not ready:
            note = self._stop(kill=True)
            raise RuntimeError(f"{self.name} worker did not start: {note}")

    def call(self, fn: Callable, *args: Any, timeout_s: float) -> Reply:
        """fn(*args) in the child; its reply, or "timeout" after timeout_s seconds (the child is
        killed) or "crashed" if the child dies. Never raises for what the task does."""
        if not self.alive:
            try:
                self.start()
            except RuntimeError as e:
                return Reply("crashed", note=str(e))
        t0 = time.perf_counter()

        def elapsed() -> float:
            return (time.perf_counter() - t0) * 1e3

        try:
            self._conn.send((fn, args))
            answered = self._conn.poll(timeout_s)
        except (BrokenPipeError, EOFError, OSError):
            return Reply("crashed", note=self._stop(kill=True), wall_ms=elapsed())
        if not answered:
            self._stop(kill=True)
            note = f"no answer within {timeout_s:g} s (the {self.name} worker was stopped)"
            return Reply("timeout", note=note, wall_ms=elapsed())
        try:
            status, value = self._conn.recv()
        except (EOFError, OSError):
            return Reply("crashed", note=self._stop(kill=False), wall_ms=elapsed())
        wall_ms = elapsed()
        if status == "ok":
            return Reply("ok", value, wall_ms=wall_ms)
        return Reply("error", note=str(value), wall_ms=wall_ms)

    def _stop(self, kill: bool) -> str:
        """Ends the child (killed, or waited for when it is dying anyway); how it ended."""
        proc, conn = self._proc, self._conn
        self._proc = self._conn = None
        if proc is None:
            return "no worker"
        if kill and proc.is_alive():
            proc.kill()
        proc.join(10)
        if conn is not None:
            conn.close()
        code = proc.exitcode
        if code is not None and code < 0:
            try:
                return f"the {self.name} worker died of {signal.Signals(-code).name}"
            except ValueError:
                return f"the {self.name} worker died of signal {-code}"
        return f"the {self.name} worker exited with status {code}"

    def close(self) -> None:
        """Stops the child, asking first."""
        if self._proc is None:
            return
        try:
            self._conn.send(None)
            self._proc.join(5)
        except (BrokenPipeError, OSError):
            pass
        self._stop(kill=True)

    def __enter__(self) -> Worker:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
