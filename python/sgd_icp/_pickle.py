"""Pickling of the settings classes (Settings, BatchSettings, their parts, Distance), so that they
can be sent to other processes (multiprocessing, concurrent.futures, Dask: sgd_icp.distributed).

A settings object pickles as its class and the values of its read-write attributes, nested
settings and Distances as the same; unpickling builds the defaults and sets them back, so the
copy compares equal to the original.
"""

from __future__ import annotations

import copyreg

from . import _core

_CLASSES = (
    _core.Settings,
    _core.BatchSettings,
    _core.OptimizerSettings,
    _core.ConvergenceSettings,
    _core.RefinementSettings,
    _core.NeighborhoodSettings,
    _core.UncertaintySettings,
)


def _fields(cls: type) -> list[str]:
    return [
        name
        for name, value in vars(cls).items()
        if not name.startswith("_") and isinstance(value, property) and value.fset is not None
    ]


def _rebuild(cls: type, state: dict):
    obj = cls()
    for name, value in state.items():
        setattr(obj, name, value)
    return obj


def _reduce_settings(obj):
    cls = type(obj)
    return _rebuild, (cls, {name: getattr(obj, name) for name in _fields(cls)})


def _reduce_distance(d):
    return _core.Distance, (d.value, d.unit)


def register() -> None:
    for cls in _CLASSES:
        copyreg.pickle(cls, _reduce_settings)
    copyreg.pickle(_core.Distance, _reduce_distance)
