"""NaN and infinity from Python: in points (rows dropped and counted; nothing finite left is an
error), in any entry of init, and in every floating keyword of register() and the settings."""

from __future__ import annotations

import re

import numpy as np
import pytest

import sgd_icp
from conftest import synthetic_scene

NON_FINITE = [np.nan, np.inf, -np.inf]
GOOD = synthetic_scene(5, 2000)


def keywords(method: str | None) -> list[str]:
    """The keyword settings register() lists for the SGD (None) or a batch method, read from the
    message of an unknown keyword (the library's settings table, not a copy)."""
    extra = {} if method is None else {"method": method}
    with pytest.raises(TypeError) as info:
        sgd_icp.register(GOOD, GOOD, not_a_setting=1, **extra)
    listed = re.search(r"keyword settings are: (.*)$", str(info.value)).group(1)
    return [k for k in listed.split(", ") if k != "max_distance_unit"]


def floating_keywords(method: str | None) -> list[str]:
    """The keywords that take a float: the others refuse one with a TypeError of their kind."""
    extra = {} if method is None else {"method": method}
    found = []
    for k in keywords(method):
        try:
            sgd_icp.register(GOOD, GOOD, **{k: 0.5}, **extra, max_iterations=1)
        except TypeError:
            continue  # integer, flag or choice
        except ValueError as e:
            if f"{k}=0.5" not in str(e):
                continue  # refused for another reason (cost= with a batch method)
            # else 0.5 is out of its range: a float all the same
        found.append(k)
    return found


@pytest.mark.parametrize("method", [None, "icp", "gicp"])
@pytest.mark.parametrize("value", NON_FINITE)
def test_every_floating_keyword_rejects_non_finite_values(method, value):
    floating = floating_keywords(method)
    assert "max_distance" in floating and "kernel_scale" in floating
    extra = {} if method is None else {"method": method}
    for k in floating:
        with pytest.raises(sgd_icp.InvalidSettingsError, match=f"{k}={value}") as info:
            sgd_icp.register(GOOD, GOOD, **{k: value}, **extra)
        assert "must be in" in str(info.value)
    if method is None:
        for k in floating:
            with pytest.raises(sgd_icp.InvalidSettingsError, match=f"{k}={value}"):
                sgd_icp.Settings(**{k: value})


@pytest.mark.parametrize("value", NON_FINITE)
def test_neighbourhood_epsilon_and_viewpoint_reject_non_finite_values(value):
    s = sgd_icp.Settings()
    s.neighborhood.epsilon = value
    with pytest.raises(sgd_icp.InvalidSettingsError, match="epsilon"):
        s.validate()
    with pytest.raises(sgd_icp.InvalidSettingsError, match="epsilon"):
        sgd_icp.register(GOOD, GOOD, settings=s)
    v = sgd_icp.Settings()
    v.neighborhood.viewpoint = [0.0, value, 0.0]
    with pytest.raises(sgd_icp.InvalidSettingsError, match="viewpoint"):
        sgd_icp.register(GOOD, GOOD, settings=v)


@pytest.mark.parametrize("value", NON_FINITE)
@pytest.mark.parametrize("method", ["sgd", "icp"])
def test_every_entry_of_init_is_checked(value, method):
    for r in range(4):
        for c in range(4):
            init = np.eye(4)
            init[r, c] = value
            with pytest.raises(ValueError, match="initial transform is not a finite rigid"):
                sgd_icp.register(GOOD, GOOD, init=init, method=method)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("value", NON_FINITE)
def test_non_finite_points_are_dropped_counted_or_rejected(dtype, value):
    source = GOOD.astype(dtype)
    source[7, 1] = value
    reference = GOOD.astype(dtype)
    reference[[3, 4], 2] = value
    r = sgd_icp.register(source, reference)
    assert r.source_non_finite_dropped == 1 and r.reference_non_finite_dropped == 2
    assert np.isfinite(r.T_reference_source).all()
    with pytest.raises(ValueError, match="source has no finite points: all 2000 rows hold a NaN"):
        sgd_icp.register(np.full_like(source, value), reference)
    with pytest.raises(ValueError, match="reference has no finite points"):
        sgd_icp.ReferenceIndex(np.full_like(reference, value))
