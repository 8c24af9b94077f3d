"""Peers that misbehave on purpose, for the tests of the harness bench/peers/ (test_peers.py). Module-level
functions, so that a worker process can import them."""

from __future__ import annotations

import os
import signal
import time

import numpy as np

from peers import Outcome, Task  # bench/peers/, on sys.path by conftest.py
from peers.runners import cloud_f64

HANG_ABOVE_POINTS = 1000  # the hanging peer hangs on sources larger than this


def echo(value):
    return value


def sleep_then_echo(seconds: float, value):
    time.sleep(seconds)
    return value


def crash() -> None:
    os.kill(os.getpid(), signal.SIGSEGV)


def fail() -> None:
    raise ValueError("bad input")


def identity_peer(task: Task) -> Outcome:
    """Returns the identity at once, timed as 1 ms."""
    return Outcome(T=np.eye(4), time_ms=1.0, iterations=1, converged=True,
                   source_points_used=len(cloud_f64(task.source)))


def hanging_peer(task: Task) -> Outcome:
    """The identity on small sources, and no answer for a minute on large ones."""
    if len(cloud_f64(task.source)) > HANG_ABOVE_POINTS:
        time.sleep(60)
    return identity_peer(task)


def crashing_peer(task: Task) -> Outcome:
    """The identity on small sources; kills its process on large ones."""
    if len(cloud_f64(task.source)) > HANG_ABOVE_POINTS:
        crash()
    return identity_peer(task)
