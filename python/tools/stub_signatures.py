"""Writes the keyword parameters of the stub's settings signatures from the module's table.

Settings(**overrides), Settings.paper, Settings.replace, BatchSettings(**overrides) and its
constructors, register() and ReferenceIndex.for_registration() take the flat keyword settings of
the library's settings table (include/sgdicp/registration/settings.hpp), the last two also those
of the global registration's table (include/sgdicp/global/global_registration.hpp, the global_*
keywords of init="global"); Odometry() takes the odometry's table's
(include/sgdicp/odometry/odometry.hpp) and the registration's. The stub spells each one
out, so that type checkers and IDEs know them; this module writes those parameters from
_core._settings_keywords(), the table as the module reads it: one `keyword: type = ...` per
setting, in table order, typed by its kind (count int, real float, flag bool, distance
_DistanceValue, choice the stub's alias that names the choice's enum, e.g. _CostName, else
`Enum | str`). A function's own parameters (those the module names, e.g. paper's optimizer or
for_registration's method) stay as the stub writes them.

sync_stub.py runs it together with the docstrings:

    python python/tools/sync_stub.py            # rewrites python/sgd_icp/_core.pyi
    python python/tools/sync_stub.py --check    # exit 1 listing every difference
"""

from __future__ import annotations

import ast
import re
from types import ModuleType

# The functions whose **overrides are the flat setting keywords, and the tables they take:
# register() and for_registration() take either solver's, as the method says, and the global
# registration's (init="global"; for_registration checks and ignores them).
SIGNATURES: dict[str, tuple[str, ...]] = {
    "Settings.__init__": ("sgd",),
    "Settings.paper": ("sgd",),
    "Settings.replace": ("sgd",),
    "BatchSettings.__init__": ("batch",),
    "BatchSettings.icp": ("batch",),
    "BatchSettings.icp_plane": ("batch",),
    "BatchSettings.gicp": ("batch",),
    "BatchSettings.replace": ("batch",),
    "register": ("sgd", "batch", "global"),
    "ReferenceIndex.for_registration": ("sgd", "batch", "global"),
    "Odometry.__init__": ("odometry", "sgd", "batch"),
    "Localizer.__init__": ("odometry", "sgd", "batch"),
}
# Keywords of those tables a function refuses: the odometry thins on its own grid (voxel_size=,
# its own table's) and make_odometry raises for downsample_to=.
REFUSED: dict[str, frozenset[str]] = {
    "Odometry.__init__": frozenset({"downsample_to"}),
    "Localizer.__init__": frozenset({"downsample_to"}),
}
KIND_TYPES = {"count": "int", "real": "float", "flag": "bool", "distance": "_DistanceValue"}


def enum_aliases(tree: ast.Module) -> dict[str, str]:
    """The stub's alias for the values of each enum: `_CostName = Union["CostType", str]` makes
    CostType's _CostName (the first alias whose Union starts with the enum)."""
    aliases: dict[str, str] = {}
    for node in tree.body:
        if not (isinstance(node, ast.Assign) and isinstance(node.targets[0], ast.Name)
                and isinstance(node.value, ast.Subscript)
                and getattr(node.value.value, "id", None) == "Union"
                and isinstance(node.value.slice, ast.Tuple)):
            continue
        first = node.value.slice.elts[0]
        named = first.value if isinstance(first, ast.Constant) else getattr(first, "id", None)
        if isinstance(named, str):
            aliases.setdefault(named, node.targets[0].id)
    return aliases


def keyword_types(module: ModuleType, solvers: tuple[str, ...],
                  aliases: dict[str, str]) -> dict[str, str]:
    """Each keyword of the solvers' tables with its stub type: the common ones first (those a user
    sets, as help() lists them), then the others, each in table order."""
    types: dict[str, str] = {}
    common: list[str] = []
    for solver in solvers:
        for keyword, kind, enum_name, is_common in module._settings_keywords(solver):
            if is_common and keyword not in common:
                common.append(keyword)
            if kind == "choice":
                annotation = aliases.get(enum_name, f"{enum_name} | str")
            else:
                annotation = KIND_TYPES[kind]
            if types.get(keyword, annotation) != annotation:  # typed apart by the two tables
                annotation = f"{types[keyword]} | {annotation}"
            types[keyword] = annotation
    return {**{k: types[k] for k in common}, **types}


def own_parameters(module: ModuleType, qualified: str) -> set[str]:
    """The parameters the module's function names itself, from pybind11's signature line."""
    obj = module
    for part in qualified.split("."):
        obj = getattr(obj, part)
    line = (obj.__doc__ or "").split("\n")[0]
    if "**kwargs" not in line:
        raise ValueError(f"{qualified} takes no **kwargs: {line!r}")
    return set(re.findall(r"[(,]\s*(\w+)\s*[:=,)]", line[line.index("("):]))


def _functions(tree: ast.Module) -> dict[str, ast.FunctionDef]:
    """The stub's functions by qualified name (Class.method)."""
    found: dict[str, ast.FunctionDef] = {}
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            found[node.name] = node
        elif isinstance(node, ast.ClassDef):
            for item in node.body:
                if isinstance(item, ast.FunctionDef):
                    found[f"{node.name}.{item.name}"] = item
    return found


def _offset(lines: list[str], line: int, column: int) -> int:
    """The offset in the text of `lines` of a 1-based line's column."""
    return sum(len(text) + 1 for text in lines[: line - 1]) + column


class _Signature:
    """One settings signature of the stub: its `def ...:` header and the one the table makes."""

    def __init__(self, text: str, fn: ast.FunctionDef, keywords: dict[str, str], own: set[str],
                 qualified: str):
        if fn.returns is None or fn.returns.end_lineno is None:
            raise ValueError(f"the stub's {fn.name} has no return type")
        self.text, self.fn, self.returns, self.own = text, fn, fn.returns, own
        self.keywords = {k: v for k, v in keywords.items()
                         if k not in own and k not in REFUSED.get(qualified, frozenset())}
        lines = text.split("\n")
        self.start = _offset(lines, fn.lineno, fn.col_offset)
        returns_end = _offset(lines, fn.returns.end_lineno, fn.returns.end_col_offset or 0)
        self.end = text.index(":", returns_end) + 1  # the header's colon

    def _source(self, node: ast.AST) -> str:
        return ast.get_source_segment(self.text, node) or ""

    def _parameter(self, arg: ast.arg, default: ast.expr | None) -> str:
        return self._source(arg) + ("" if default is None else f" = {self._source(default)}")

    def written(self) -> str:
        """The header with the table's keywords after the function's own parameters."""
        args = self.fn.args
        positional = args.posonlyargs + args.args
        defaults = [None] * (len(positional) - len(args.defaults)) + list(args.defaults)
        params = [self._parameter(a, d) for a, d in zip(positional, defaults)] + ["*"]
        params += [self._parameter(a, d) for a, d in zip(args.kwonlyargs, args.kw_defaults)
                   if a.arg in self.own]
        params += [f"{keyword}: {annotation} = ..." for keyword, annotation in
                   self.keywords.items()]
        pad = " " * self.fn.col_offset
        body = "".join(f"{pad}    {p},\n" for p in params)
        return f"def {self.fn.name}(\n{body}{pad}) -> {self._source(self.returns)}:"

    def differences(self, name: str) -> list[str]:
        """What the stub's header of `name` says that the table does not."""
        if self.fn.args.kwarg:
            return [f"{name}: takes **{self.fn.args.kwarg.arg}, not the table's keywords"]
        stub = {a.arg: self._source(a.annotation) if a.annotation else "(no type)"
                for a in self.fn.args.kwonlyargs if a.arg not in self.own}
        found = [f"{name}: keyword {k}= of the table is missing" for k in self.keywords
                 if k not in stub]
        found += [f"{name}: keyword {k}= is not in the table" for k in stub
                  if k not in self.keywords]
        found += [f"{name}: keyword {k}= is typed {stub[k]}, the table makes it {t}"
                  for k, t in self.keywords.items() if k in stub and stub[k] != t]
        if not found and self.text[self.start:self.end] != self.written():
            found.append(f"{name}: the keywords' order, defaults or layout are not the table's")
        return found


def _signatures(text: str, module: ModuleType) -> dict[str, _Signature]:
    tree = ast.parse(text)
    aliases = enum_aliases(tree)
    functions = _functions(tree)
    missing = [name for name in SIGNATURES if name not in functions]
    if missing:
        raise ValueError(f"the stub has no {', '.join(missing)}")
    return {name: _Signature(text, functions[name], keyword_types(module, solvers, aliases),
                             own_parameters(module, name), name)
            for name, solvers in SIGNATURES.items()}


def differences(text: str, module: ModuleType) -> list[str]:
    """Every keyword parameter of the stub's settings signatures that the table disagrees with."""
    return [d for name, s in _signatures(text, module).items() for d in s.differences(name)]


def written(text: str, module: ModuleType) -> str:
    """The stub with the keyword parameters of every settings signature written from the table."""
    for signature in sorted(_signatures(text, module).values(), key=lambda s: -s.start):
        text = text[: signature.start] + signature.written() + text[signature.end:]
    return text
