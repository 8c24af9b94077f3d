"""Settings mirror the C++ SgdSettings (names and defaults, as in docs/registration.md), and the
flat keyword overrides mean what docs/python-settings.md says."""

from __future__ import annotations

import copy
import pickle
from pathlib import Path

import pytest

from sgd_icp import (
    CostType,
    Distance,
    DistanceUnit,
    KernelType,
    OptimizerType,
    ScalingOrigin,
    Settings,
)

# The table of docs/registration.md, by attribute path.
DEFAULTS = {
    "batch_size": 160,
    "max_correspondence_distance": Distance.scaled(0.5),
    "optimizer.type": OptimizerType.adam,
    "optimizer.learning_rate": 0.01,
    "optimizer.damping": 1e-3,
    "convergence.window": 20,
    "convergence.chi2": 12.59,
    "convergence.max_path_efficiency": 0.5,
    "convergence.translation_tolerance": 1e-6,
    "convergence.rotation_tolerance": 1e-6,
    "refinement.stages": 3,
    "refinement.step_decay": 0.5,
    "refinement.distance_factor": 3.0,
    "refinement.min_distance": Distance.scaled(1e-4),
    "cost": CostType.point_to_plane,
    "coarse_cost": CostType.point_to_point,
    "voxel_size_m": 0.0,
    "downsample_to": 20000,
    "kernel": KernelType.none,
    "kernel_scale": Distance.scaled(0.01),
    "trim_ratio": 1.0,
    "neighborhood.k": 20,
    "neighborhood.num_threads": 0,
    "neighborhood.regularize": True,
    "neighborhood.epsilon": 1e-3,
    "scaling_origin": ScalingOrigin.center,
    "average_iterates": True,
    "max_iterations": 4000,
    "seed": 2019,
    "evaluation_points": 2000,
    "record_trace": False,
}

PAPER_CHANGES = {
    "optimizer.type": OptimizerType.sgd,
    "optimizer.learning_rate": 2.0,
    "refinement.stages": 0,
    "scaling_origin": ScalingOrigin.lower_corner,
    "average_iterates": False,
    "cost": CostType.point_to_point,
    "downsample_to": 0,
    "adapt_small_sources": False,
    "robust_scaling": False,
}


def get(settings: Settings, path: str):
    value = settings
    for part in path.split("."):
        value = getattr(value, part)
    return value


def test_defaults_are_the_documented_ones():
    s = Settings()
    for path, expected in DEFAULTS.items():
        assert get(s, path) == expected, path


def test_paper_presets():
    for path, expected in {**DEFAULTS, **PAPER_CHANGES}.items():
        assert get(Settings.paper(), path) == expected, path
    adam = Settings.paper("adam")
    assert adam.optimizer.type == OptimizerType.adam and adam.optimizer.learning_rate == 0.01
    assert Settings.paper(OptimizerType.adam) == adam
    assert Settings.paper(optimizer="sgd", batch_size=100).batch_size == 100


def test_keyword_overrides_set_the_documented_fields():
    s = Settings(
        batch_size=100,
        learning_rate=0.02,
        max_distance=1.5,
        max_distance_unit="m",
        min_distance=0.002,
        max_iterations=50,
        seed=7,
        damping=0.01,
        window=10,
        chi2=10.0,
        translation_tolerance=1e-5,
        rotation_tolerance=1e-5,
        refine_stages=2,
        step_decay=0.6,
        distance_factor=2.5,
        average=False,
        scaling_origin="lower_corner",
        evaluation_points=0,
        record_trace=True,
        cost="point-to-plane",
        kernel="geman-mcclure",
        kernel_scale=0.05,
        trim=0.8,
        neighbors=12,
    )
    expected = {
        "batch_size": 100,
        "optimizer.learning_rate": 0.02,
        "max_correspondence_distance": Distance.metres(1.5),
        "refinement.min_distance": Distance.metres(0.002),
        "max_iterations": 50,
        "seed": 7,
        "optimizer.damping": 0.01,
        "convergence.window": 10,
        "convergence.chi2": 10.0,
        "convergence.translation_tolerance": 1e-5,
        "convergence.rotation_tolerance": 1e-5,
        "refinement.stages": 2,
        "refinement.step_decay": 0.6,
        "refinement.distance_factor": 2.5,
        "average_iterates": False,
        "scaling_origin": ScalingOrigin.lower_corner,
        "evaluation_points": 0,
        "record_trace": True,
        "cost": CostType.point_to_plane,
        "kernel": KernelType.geman_mcclure,
        "kernel_scale": Distance.metres(0.05),
        "trim_ratio": 0.8,
        "neighborhood.k": 12,
    }
    for path, value in expected.items():
        assert get(s, path) == value, path


@pytest.mark.parametrize(
    "name, rate",
    [
        ("sgd", 2.0),
        ("momentum", 0.2),
        ("rmsprop", 0.01),
        ("adam", 0.01),
        ("gauss-newton", 1.0),
        ("gauss_newton", 1.0),
        (OptimizerType.sgd, 2.0),
    ],
)
def test_optimizer_keyword_sets_its_usual_step_like_the_cli(name, rate):
    s = Settings(optimizer=name)
    assert s.optimizer.learning_rate == pytest.approx(rate)
    assert Settings(optimizer=name, learning_rate=0.5).optimizer.learning_rate == 0.5


def test_distances_keep_their_unit():
    s = Settings(max_distance=Distance.metres(2.0), min_distance=0.01)
    assert s.max_correspondence_distance == Distance.metres(2.0)
    assert s.refinement.min_distance == Distance.scaled(0.01)
    d = Distance(3, "m")
    assert d.unit == DistanceUnit.metres and d.value == 3.0 and repr(d) == "Distance.metres(3.0)"
    assert d.to_scaled(6.0) == 0.5 and Distance.scaled(0.5).to_scaled(6.0) == 0.5


def test_settings_are_values():
    s = Settings(seed=5)
    t = s.replace(batch_size=80)
    assert t.batch_size == 80 and s.batch_size == 160 and t.seed == 5
    c = copy.deepcopy(s)
    assert c == s and c is not s
    c.optimizer.learning_rate = 0.5  # nested attributes are changed in place
    assert c.optimizer.learning_rate == 0.5 and c != s and s.optimizer.learning_rate == 0.01
    assert pickle.loads(pickle.dumps(OptimizerType.adam)) is OptimizerType.adam


def test_string_names_are_accepted_for_enums():
    s = Settings()
    s.optimizer.type = "rmsprop"
    s.scaling_origin = "corner"
    s.cost = "plane_to_plane"
    s.kernel = "huber"
    assert s.optimizer.type == OptimizerType.rmsprop
    assert s.scaling_origin == ScalingOrigin.lower_corner
    assert s.cost == CostType.plane_to_plane and s.kernel == KernelType.huber


def test_neighborhood_settings():
    s = Settings(neighbors=8)
    s.neighborhood.viewpoint = (0.0, 0.0, 10.0)
    assert list(s.neighborhood.viewpoint) == [0.0, 0.0, 10.0]
    assert s.neighborhood.k == 8
    with pytest.raises(ValueError, match="viewpoint must be 3 numbers"):
        s.neighborhood.viewpoint = (1.0, 2.0)


@pytest.mark.parametrize("name", ["sgd", "momentum", "rmsprop", "adam", "gauss-newton"])
def test_paper_preset_uses_the_same_step_table(name):
    # One table of step sizes: Settings.paper(rule) and Settings(optimizer=rule) agree (the paper
    # preset with Gauss-Newton ran with 0.01 instead of 1 before).
    assert Settings.paper(name).optimizer.learning_rate == Settings(optimizer=name).optimizer.learning_rate


def test_scaling_origin_spellings():
    for name in ("corner", "lower_corner", "lower-corner", ScalingOrigin.lower_corner):
        assert Settings(scaling_origin=name).scaling_origin == ScalingOrigin.lower_corner
    assert Settings(scaling_origin="center").scaling_origin == ScalingOrigin.center


def test_settings_compare_field_by_field():
    assert Settings() == Settings() and Settings(seed=3) != Settings()
    s = Settings()
    s.neighborhood.viewpoint = (0.0, 0.0, 1.0)
    assert s != Settings()


def test_settings_pickle_to_equal_copies():
    import sgd_icp

    cases = [
        sgd_icp.Settings(),
        sgd_icp.Settings.paper(),
        sgd_icp.Settings(seed=3, neighbors=7, max_distance=1.0, max_distance_unit="m"),
        sgd_icp.BatchSettings.gicp(),
        sgd_icp.BatchSettings(trim=0.8),
        sgd_icp.Distance(0.3, "m"),
    ]
    for settings in cases:
        copy = pickle.loads(pickle.dumps(settings))
        assert type(copy) is type(settings) and copy == settings
    changed = pickle.loads(pickle.dumps(sgd_icp.Settings(seed=3)))
    changed.seed = 4
    assert changed != sgd_icp.Settings(seed=3)


def _properties(cls):
    return [name for name, value in vars(cls).items() if isinstance(value, property)]


def test_repr_shows_every_attribute_with_its_value():
    # The repr is made from the bound attributes: a new setting cannot be left out of it.
    import sgd_icp

    s = sgd_icp.Settings(seed=7, optimizer="rmsprop", uncertainty="sgld")
    s.neighborhood.viewpoint = (1.0, 2.0, 3.0)
    b = sgd_icp.BatchSettings.gicp(max_iterations=30)
    for obj in (s, s.optimizer, s.convergence, s.refinement, s.neighborhood, s.uncertainty, b):
        text = repr(obj)
        assert text.startswith(type(obj).__name__ + "(")
        for name in _properties(type(obj)):
            assert text.count(f"{name}=") >= 1, (name, text)
    text = repr(s)
    assert "seed=7" in text and "type=OptimizerType.rmsprop" in text
    assert "method=UncertaintyType.sgld" in text and "viewpoint=(1.0, 2.0, 3.0)" in text
    assert "cost=CostType.plane_to_plane" in repr(b) and "max_iterations=30" in repr(b)
    assert repr(sgd_icp.Distance.metres(0.5)) == "Distance.metres(0.5)"


@pytest.mark.parametrize("keyword", ["beta1", "settle_tolerance", "cap_batch_to_source"])
def test_a_retired_keyword_says_it_is_no_longer_a_setting(keyword):
    import sgd_icp

    with pytest.raises(TypeError, match=f"unknown setting '{keyword}'.*no longer a setting"):
        sgd_icp.Settings(**{keyword: 1})


def test_register_help_lists_the_common_settings_before_the_grouped_others():
    import sgd_icp

    doc = sgd_icp.register.__doc__
    common = doc.index("The common ones:")
    others = doc.index("The others, by the part of the run that reads them:")
    assert common < others
    for keyword in ("voxel_size", "max_distance", "seed", "threads", "uncertainty"):
        assert common < doc.index(f"{keyword} (", common) < others, keyword
    for part in ("Step rule:", "Refinement:", "Uncertainty:"):
        assert others < doc.index(part, others), part
    assert doc.index("refine_stages (", others) > others


def test_the_stub_lists_the_common_keywords_first():
    import inspect

    import sgd_icp

    stub = (Path(sgd_icp.__file__).parent / "_core.pyi").read_text()
    register = stub[stub.index("def register("):]
    header = register[: register.index(") ->")]
    names = [line.strip().rstrip(",").split(":")[0] for line in header.splitlines()[1:]]
    star = names.index("*")
    assert names[star + 1: star + 6] == ["max_distance", "seed", "threads", "voxel_size",
                                         "uncertainty"], names[star:star + 8]
    assert inspect.signature  # the stub is parsed as text: its order is what IDEs show


def test_odometry_takes_grouped_settings_like_register():
    import numpy as np

    import sgd_icp

    settings = sgd_icp.Settings(refine_stages=2)
    odometry = sgd_icp.Odometry(settings=settings, voxel_size=0.5)
    rng = np.random.default_rng(4)
    frame = rng.uniform(-10, 10, (3000, 3)).astype(np.float32)
    frame[:, 2] = np.round(frame[:, 2])  # a few planes: something to register
    odometry.register_frame(frame)
    odometry.register_frame(frame)
    assert not odometry.reports[1].failed
    with pytest.raises(TypeError, match="settings must be a sgd_icp.Settings"):
        sgd_icp.Odometry(settings=sgd_icp.BatchSettings())
