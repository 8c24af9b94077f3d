#!/usr/bin/env python3
"""Checks the library's layout (docs/design.md, "Where things are"); exits 1 on a violation.

- Parts are layered: a file of part P (src/P/, include/sgdicp/P/) includes only headers of P and
  of the parts before P in the order given (the top-level CMakeLists.txt's SGDICP_PARTS), so no
  two parts include each other.
- Public headers (include/sgdicp/) include no private header of src/.
- No source file over MAX_LINES lines in the folders listed in SIZE_CHECKED.

Usage: scripts/check_layout.py [--root DIR] PART...   (ctest runs it with SGDICP_PARTS)
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

MAX_LINES = 700
SIZE_CHECKED = ("src", "include", "apps", "python", "tests", "bench", "eval", "fuzz", "scripts")
SOURCE_SUFFIXES = {".cpp", ".hpp", ".h", ".py", ".sh"}
INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]([^>"]+)[>"]', re.MULTILINE)


def part_of_include(path: str, parts: list[str]) -> str | None:
    """The part an include names: "sgdicp/P/x.hpp" (public) or "P/x.hpp" (private)."""
    pieces = path.split("/")
    if pieces[0] == "sgdicp":
        pieces = pieces[1:]
    return pieces[0] if len(pieces) > 1 and pieces[0] in parts else None


def layering_errors(root: Path, parts: list[str]) -> list[str]:
    errors = []
    rank = {p: i for i, p in enumerate(parts)}
    for base in (root / "src", root / "include" / "sgdicp"):
        for folder in sorted(p for p in base.iterdir() if p.is_dir()):
            if folder.name not in rank:
                errors.append(f"{folder.relative_to(root)}: not a part of SGDICP_PARTS {parts}")
                continue
            for file in sorted(folder.rglob("*")):
                if file.suffix not in SOURCE_SUFFIXES:
                    continue
                for target in INCLUDE.findall(file.read_text(encoding="utf-8")):
                    other = part_of_include(target, parts)
                    where = file.relative_to(root)
                    if other is not None and rank[other] > rank[folder.name]:
                        errors.append(f"{where}: includes {target}: part '{folder.name}' may "
                                      f"include only {parts[: rank[folder.name] + 1]}")
                    if base.name == "sgdicp" and not target.startswith("sgdicp/") and other:
                        errors.append(f"{where}: a public header includes the private {target}")
    return errors


def size_errors(root: Path) -> list[str]:
    errors = []
    for folder in SIZE_CHECKED:
        for file in sorted((root / folder).rglob("*")):
            if file.suffix in SOURCE_SUFFIXES and file.is_file():
                lines = file.read_text(encoding="utf-8").count("\n")
                if lines > MAX_LINES:
                    errors.append(f"{file.relative_to(root)}: {lines} lines, more than "
                                  f"{MAX_LINES}: split it by concern")
    return errors


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", type=Path, default=Path(__file__).resolve().parent.parent)
    parser.add_argument("parts", nargs="+", help="the parts, lowest layer first")
    args = parser.parse_args()
    errors = layering_errors(args.root, args.parts) + size_errors(args.root)
    for e in errors:
        print(f"check_layout: {e}", file=sys.stderr)
    if not errors:
        print(f"check_layout: {len(args.parts)} parts layered, no file over {MAX_LINES} lines")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
