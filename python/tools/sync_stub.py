#!/usr/bin/env python3
"""Keeps the docstrings and settings keywords of sgd_icp/_core.pyi equal to the module's own.

The stub is written by hand for what only it can say (the types of every parameter, attribute and
return value), but two parts of it are not: its docstrings are copied from the built module, which
holds the one text (most of it from the C++ library's tables), and the keyword parameters of the
functions that take the flat settings keywords (Settings(), Settings.paper, register(), ...) are
written from the module's settings table by stub_signatures.py. Run it with the package built and
installed, after changing a docstring in the bindings or a setting in the settings table:

    python python/tools/sync_stub.py            # rewrites python/sgd_icp/_core.pyi
    python python/tools/sync_stub.py --check    # exit 1 listing what differs

tests/python/test_package.py runs the check against the installed stub.
"""

from __future__ import annotations

import argparse
import ast
import enum
import inspect
import re
import sys
import textwrap
from pathlib import Path
from types import ModuleType

import stub_signatures

SOURCE_STUB = Path(__file__).resolve().parents[1] / "sgd_icp" / "_core.pyi"
WIDTH = 100


def _strip_signature(doc: str) -> str:
    """A pybind11 docstring without its leading 'name(args) -> type' line."""
    lines = doc.split("\n")
    if lines and re.match(r"^\w+\(.*\)( -> .*)?$", lines[0]):
        lines = lines[1:]
        while lines and not lines[0].strip():
            lines = lines[1:]
    return "\n".join(lines)


def _runtime_doc(obj: object) -> str | None:
    if isinstance(obj, staticmethod):
        obj = obj.__func__
    doc = inspect.getdoc(obj)
    return None if doc is None else _strip_signature(doc)


def _member_doc(cls: type, name: str) -> str | None:
    if issubclass(cls, enum.Enum):
        return cls[name].__doc__ if name in cls.__members__ else None
    if name not in vars(cls):
        return None
    return _runtime_doc(vars(cls)[name])


def _docstrings(tree: ast.Module, module: ModuleType) -> list[tuple[ast.Constant, str, str]]:
    """(the stub's docstring node, the module's docstring, a name) for every public name."""
    found = []

    def docstring_node(body: list[ast.stmt]) -> ast.Constant | None:
        if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
            return body[0].value if isinstance(body[0].value.value, str) else None
        return None

    for node in tree.body:
        if node.__class__ not in (ast.ClassDef, ast.FunctionDef) or node.name.startswith("_"):
            continue
        runtime = getattr(module, node.name, None)
        if runtime is None:
            continue
        own = docstring_node(node.body)
        doc = runtime.__doc__ if isinstance(runtime, type) else _runtime_doc(runtime)
        if own is not None and doc:
            found.append((own, inspect.cleandoc(doc), node.name))
        if not isinstance(node, ast.ClassDef):
            continue
        for item, following in zip(node.body, node.body[1:] + [None]):
            if isinstance(item, ast.FunctionDef):
                name, target = item.name, docstring_node(item.body)
            elif isinstance(item, (ast.AnnAssign, ast.Assign)) and isinstance(following, ast.Expr):
                target_node = item.target if isinstance(item, ast.AnnAssign) else item.targets[0]
                name = getattr(target_node, "id", "_")
                value = following.value
                target = value if isinstance(value, ast.Constant) and isinstance(value.value, str) else None
            else:
                continue
            if target is None or (name.startswith("_") and name != "__init__"):
                continue
            doc = _member_doc(runtime, name)
            if doc and "Overloaded function" not in doc:
                found.append((target, doc, f"{node.name}.{name}"))
    return found


def _literal(doc: str, indent: int) -> str:
    """doc as a triple-quoted literal for a line indented by `indent`, long lines wrapped."""
    pad = " " * indent
    lines = []
    for line in doc.replace("\\", "\\\\").replace('"""', '\\"\\"\\"').split("\n"):
        lead = line[: len(line) - len(line.lstrip())]
        if len(pad) + len(line) <= WIDTH or not line.strip():
            lines.append(line)
        else:
            lines.extend(textwrap.wrap(line, WIDTH - indent - 3, subsequent_indent=lead,
                                       break_on_hyphens=False))
    if len(lines) == 1 and indent + len(lines[0]) + 6 <= WIDTH:
        return f'"""{lines[0]}"""'
    body = "\n".join((pad + l) if l.strip() else "" for l in lines[1:])
    return f'"""{lines[0]}\n{body}\n{pad}"""' if len(lines) > 1 else f'"""{lines[0]}\n{pad}"""'


def _normal(text: str) -> str:
    return " ".join(text.split())


def differences(stub_text: str, module: ModuleType) -> list[str]:
    """The names whose stub docstring is not the module's (whitespace aside)."""
    tree = ast.parse(stub_text)
    return [name for node, doc, name in _docstrings(tree, module)
            if _normal(node.value) != _normal(doc)]


def synced(stub_text: str, module: ModuleType) -> str:
    """The stub with every docstring replaced by the module's."""
    tree = ast.parse(stub_text)
    lines = stub_text.split("\n")
    offsets = [0]
    for line in lines:
        offsets.append(offsets[-1] + len(line) + 1)
    edits = []
    for node, doc, _ in _docstrings(tree, module):
        start = offsets[node.lineno - 1] + node.col_offset
        end = offsets[node.end_lineno - 1] + node.end_col_offset
        edits.append((start, end, _literal(doc, node.col_offset)))
    for start, end, text in sorted(edits, reverse=True):
        stub_text = stub_text[:start] + text + stub_text[end:]
    return stub_text


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--check", action="store_true", help="only report differences")
    parser.add_argument("--stub", type=Path, default=SOURCE_STUB)
    args = parser.parse_args()
    from sgd_icp import _core

    text = args.stub.read_text()
    if args.check:
        found = [f"docstring of {name} differs from the module's"
                 for name in differences(text, _core)]
        found += stub_signatures.differences(text, _core)
        for difference in found:
            print(f"{args.stub}: {difference}")
        return 1 if found else 0
    args.stub.write_text(synced(stub_signatures.written(text, _core), _core))
    return 0


if __name__ == "__main__":
    sys.exit(main())
