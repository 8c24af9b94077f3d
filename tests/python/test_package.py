"""The installed package: its public names, type stubs (py.typed, _core.pyi) and docstrings."""

from __future__ import annotations

import ast
import enum
import importlib
import inspect
import re
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

import sgd_icp
from sgd_icp import _core

STUB = Path(_core.__file__).with_name("_core.pyi")
TOOLS = Path(__file__).resolve().parents[2] / "python" / "tools"


def stub_names() -> dict[str, set[str]]:
    """Top-level public names of the stub, each with the public members of its class."""
    tree = ast.parse(STUB.read_text())
    names: dict[str, set[str]] = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            members = set()
            for item in node.body:
                if isinstance(item, (ast.FunctionDef, ast.AnnAssign, ast.Assign)):
                    target = (
                        item.name
                        if isinstance(item, ast.FunctionDef)
                        else item.target.id
                        if isinstance(item, ast.AnnAssign)
                        else item.targets[0].id
                    )
                    if not target.startswith("_"):
                        members.add(target)
            names[node.name] = members
        elif isinstance(node, ast.FunctionDef):
            names[node.name] = set()
    return {k: v for k, v in names.items() if not k.startswith("_")}


def runtime_members(obj: type) -> set[str]:
    if issubclass(obj, enum.Enum):
        return set(obj.__members__)
    if issubclass(obj, BaseException):
        return set()
    return {n for n in vars(obj) if not n.startswith("_")}


def test_package_ships_its_stubs():
    assert STUB.is_file()
    assert STUB.with_name("py.typed").is_file()


def test_stubs_match_the_module():
    stubs = stub_names()
    runtime = {n for n in dir(_core) if not n.startswith("_")}
    assert set(stubs) == runtime
    for name, members in stubs.items():
        obj = getattr(_core, name)
        if isinstance(obj, type):
            assert members == runtime_members(obj), name


def stub_literal(alias: str) -> list[str]:
    """The strings of the Literal[...] in a `NAME = ...` alias of the stub."""
    for node in ast.parse(STUB.read_text()).body:
        if isinstance(node, ast.Assign) and node.targets[0].id == alias:
            for part in ast.walk(node.value):
                if isinstance(part, ast.Subscript) and getattr(part.value, "id", "") == "Literal":
                    return [e.value for e in part.slice.elts]
    raise AssertionError(f"{alias} has no Literal in the stub")


def test_stub_literals_name_every_choice():
    # A name list kept by hand in the stub must follow the module's enum (svgd was missing) or
    # method table (sgd-point was missing), which the error for an unknown name lists.
    assert stub_literal("_UncertaintyName") == list(sgd_icp.UncertaintyType.__members__)
    with pytest.raises(sgd_icp.InvalidSettingsError) as error:
        sgd_icp.register(np.zeros((8, 3)), np.zeros((8, 3)), method="none")
    listed = re.search(r"\(expected (.*)\)", str(error.value)).group(1)
    assert stub_literal("_MethodName") == re.split(r", | or ", listed)


def tool(name: str) -> ModuleType:
    """A module of python/tools (the stub's generator), which the package does not install."""
    sys.path.insert(0, str(TOOLS))
    try:
        return importlib.import_module(name)
    finally:
        sys.path.remove(str(TOOLS))


def test_stub_docstrings_are_the_modules():
    # The stub adds the types; its docstrings are copies of the module's, made by
    # python/tools/sync_stub.py (run it after changing a docstring in the bindings).
    assert tool("sync_stub").differences(STUB.read_text(), _core) == [], (
        "run python/tools/sync_stub.py to copy the module's docstrings into the stub"
    )


def test_stub_keywords_are_the_settings_tables():
    # The keyword parameters of Settings(), register() etc. are written from the module's
    # settings table by python/tools/stub_signatures.py (through sync_stub.py).
    assert tool("stub_signatures").differences(STUB.read_text(), _core) == [], (
        "run python/tools/sync_stub.py to write the settings keywords into the stub"
    )


def run_check(stub_text: str, tmp_path: Path) -> subprocess.CompletedProcess:
    """sync_stub.py --check on a copy of the stub with `stub_text`."""
    stub = tmp_path / "_core.pyi"
    stub.write_text(stub_text)
    return subprocess.run([sys.executable, str(TOOLS / "sync_stub.py"), "--check", "--stub",
                           str(stub)], capture_output=True, text=True, check=False)


def test_check_fails_on_a_keyword_the_stub_lacks(tmp_path):
    text = STUB.read_text()
    line = "        step_decay: float = ...,\n"
    assert line in text
    result = run_check(text.replace(line, "", 1), tmp_path)  # from Settings.__init__ only
    assert result.returncode == 1
    assert result.stdout.splitlines() == [
        f"{tmp_path / '_core.pyi'}: Settings.__init__: keyword step_decay= of the table is "
        "missing"
    ]
    assert run_check(text, tmp_path).returncode == 0


def test_check_fails_on_a_keyword_typed_apart_from_the_table():
    text = STUB.read_text()
    line = "\n    trim: float = ...,\n"  # register's, the one at the top level
    assert text.count(line) == 1
    text = text.replace(line, "\n    trim: int = ...,\n")
    assert tool("stub_signatures").differences(text, _core) == [
        "register: keyword trim= is typed int, the table makes it float"
    ]


def test_check_fails_on_keywords_out_of_the_table_order():
    # optimizer= before learning_rate=, the order in which they are applied.
    text = STUB.read_text()
    pair = "        optimizer: _OptimizerName = ...,\n        learning_rate: float = ...,\n"
    swapped = "        learning_rate: float = ...,\n        optimizer: _OptimizerName = ...,\n"
    assert tool("stub_signatures").differences(text.replace(pair, swapped, 1), _core) == [
        "Settings.__init__: the keywords' order, defaults or layout are not the table's"
    ]


class CoreWithANewSetting:
    """The module with one more setting in the SGD table, as after adding one to the C++ table."""

    def __getattr__(self, name: str) -> object:
        return getattr(_core, name)

    @staticmethod
    def _settings_keywords(solver: str) -> list[tuple[str, str, str | None, bool]]:
        extra = [("new_knob", "real", None, False)] if solver == "sgd" else []
        return _core._settings_keywords(solver) + extra


def test_a_new_setting_is_missing_from_the_stub_until_it_is_regenerated():
    signatures = tool("stub_signatures")
    core = CoreWithANewSetting()
    missing = signatures.differences(STUB.read_text(), core)
    assert missing == [f"{name}: keyword new_knob= of the table is missing" for name in (
        "Settings.__init__", "Settings.paper", "Settings.replace", "register",
        "ReferenceIndex.for_registration", "Odometry.__init__", "Localizer.__init__")]
    regenerated = signatures.written(STUB.read_text(), core)
    assert signatures.differences(regenerated, core) == []
    assert "        new_knob: float = ...,\n    ) -> Settings:" in regenerated


def test_odometry_keywords_are_its_table_and_the_registrations():
    # Its own table's (max_points_per_voxel= a count), the registration's (the SGD and batch
    # tables'), but not downsample_to=, which Odometry refuses (it thins on its own grid).
    text = STUB.read_text()
    header = text[text.index("class Odometry:"):]
    header = header[header.index("def __init__("):header.index(") -> None:")]
    assert "        max_points_per_voxel: int = ...,\n" in header
    assert "        max_range: float = ...,\n" in header
    assert "        batch_size: int = ...,\n" in header  # the SGD table's
    assert "        damping: float = ...,\n" in header  # the batch table's
    assert header.count("voxel_size:") == 1
    assert "downsample_to" not in header
    with pytest.raises(sgd_icp.InvalidSettingsError, match="downsample_to"):
        sgd_icp.Odometry(downsample_to=1000)


def test_setting_docstrings_come_from_the_library_table():
    # Each attribute of the settings table says its range and keyword (settings.hpp).
    assert "in [8, 100000]" in inspect.getdoc(sgd_icp.ConvergenceSettings.window)
    assert "Keyword window=." in inspect.getdoc(sgd_icp.ConvergenceSettings.window)
    assert "in [0.01, 1]" in inspect.getdoc(sgd_icp.BatchSettings.trim_ratio)


def test_everything_public_is_exported_and_documented():
    assert set(sgd_icp.__all__) == {n for n in dir(_core) if not n.startswith("_")} | {
        "__version__"
    }
    assert sgd_icp.__version__.count(".") == 2
    for name in sgd_icp.__all__:
        obj = getattr(sgd_icp, name)
        if name != "__version__":
            assert inspect.getdoc(obj), f"{name} has no docstring"
        if isinstance(obj, type) and not issubclass(obj, (enum.Enum, BaseException)):
            for member, value in vars(obj).items():
                if not member.startswith("_") and not isinstance(value, staticmethod):
                    assert inspect.getdoc(value), f"{name}.{member} has no docstring"
            assert obj.__module__ == "sgd_icp"


def test_register_docstring_lists_every_keyword_with_its_default():
    doc = inspect.getdoc(sgd_icp.register)
    for keyword in (
        "batch_size (160, [1, 10000000])",
        "optimizer (OptimizerType.adam)",
        "learning_rate (0.01",
        "max_distance (Distance.scaled(0.5))",
        "window (20, [8, 100000])",
        "max_distance_unit ('scaled'",
        "record_trace (False)",
    ):
        assert keyword in doc


def documented_defaults(doc: str) -> list[str]:
    """The literals of 'Default X.' in a docstring (X without spaces)."""
    return re.findall(r"Default (\S+?)\.(?:\s|$)", doc)


def test_documented_defaults_are_the_real_ones():
    # Every "Default X." in the docstrings of the module and of the stubs must be the value of a
    # fresh Settings() (BatchSettings()), so neither can drift from the C++ defaults.
    settings = sgd_icp.Settings()
    objects = {
        "Settings": settings,
        "OptimizerSettings": settings.optimizer,
        "ConvergenceSettings": settings.convergence,
        "RefinementSettings": settings.refinement,
        "NeighborhoodSettings": settings.neighborhood,
        "BatchSettings": sgd_icp.BatchSettings(),
    }
    stub_docs = {}
    for node in ast.parse(STUB.read_text()).body:
        if isinstance(node, ast.ClassDef) and node.name in objects:
            body = node.body
            for item, following in zip(body, body[1:] + [None]):
                name = (
                    item.target.id
                    if isinstance(item, ast.AnnAssign)
                    else (item.name if isinstance(item, ast.FunctionDef) else None)
                )
                doc = None
                if isinstance(item, ast.FunctionDef):
                    doc = ast.get_docstring(item)
                elif isinstance(following, ast.Expr) and isinstance(following.value, ast.Constant):
                    doc = following.value.value
                if name and doc:
                    stub_docs[(node.name, name)] = doc
    checked = 0
    namespace = vars(sgd_icp)
    for class_name, obj in objects.items():
        for member, descriptor in vars(type(obj)).items():
            if member.startswith("_") or not isinstance(descriptor, property):
                continue
            for doc in (inspect.getdoc(descriptor) or "", stub_docs.get((class_name, member), "")):
                for literal in documented_defaults(doc):
                    expected = eval(literal, namespace)
                    actual = getattr(obj, member)
                    assert actual == expected, f"{class_name}.{member}: documented {literal}"
                    checked += 1
    assert checked >= 70


def test_one_version_for_cmake_cli_and_package():
    from conftest import REPO_ROOT, find_cli

    cmake = (REPO_ROOT / "CMakeLists.txt").read_text()
    project_version = re.search(r"project\(sgdicp\s+VERSION\s+([0-9.]+)", cmake).group(1)
    assert sgd_icp.__version__ == project_version
    cli = find_cli()
    if cli is not None:
        out = subprocess.run([str(cli), "--version"], capture_output=True, text=True, check=True)
        assert out.stdout.strip() == f"sgdicp {project_version}"
