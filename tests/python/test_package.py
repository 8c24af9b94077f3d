"""The installed package: its public names, type stubs (py.typed, _core.pyi) and docstrings."""

from __future__ import annotations

import ast
import enum
import inspect
import sys
from pathlib import Path

import sgd_icp
from sgd_icp import _core

STUB = Path(_core.__file__).with_name("_core.pyi")


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
    """The strings of a `NAME = Literal[...]` alias of the stub."""
    for node in ast.parse(STUB.read_text()).body:
        if isinstance(node, ast.Assign) and node.targets[0].id == alias:
            elements = node.value.slice.elts
            return [e.value for e in elements]
    raise AssertionError(f"{alias} not in the stub")


def test_stub_literals_name_every_choice():
    # A name list kept by hand in the stub must follow the module's enum (svgd was missing).
    assert stub_literal("_UncertaintyName") == list(sgd_icp.UncertaintyType.__members__)


def test_stub_docstrings_are_the_modules():
    # The stub adds the types; its docstrings are copies of the module's, made by
    # python/tools/sync_stub.py (run it after changing a docstring in the bindings).
    tools = Path(__file__).resolve().parents[2] / "python" / "tools"
    sys.path.insert(0, str(tools))
    try:
        import sync_stub
    finally:
        sys.path.remove(str(tools))
    assert sync_stub.differences(STUB.read_text(), _core) == [], (
        "run python/tools/sync_stub.py to copy the module's docstrings into the stub"
    )


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
    import re

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
    import re
    import subprocess

    from conftest import REPO_ROOT, find_cli

    cmake = (REPO_ROOT / "CMakeLists.txt").read_text()
    project_version = re.search(r"project\(sgdicp\s+VERSION\s+([0-9.]+)", cmake).group(1)
    assert sgd_icp.__version__ == project_version
    cli = find_cli()
    if cli is not None:
        out = subprocess.run([str(cli), "--version"], capture_output=True, text=True, check=True)
        assert out.stdout.strip() == f"sgdicp {project_version}"
