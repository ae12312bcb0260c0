#!/usr/bin/env python3
"""Function sizes per package, from the source at a git revision: functions (and methods,
nested ones included), those longer than ``--limit`` lines (default 60, a screen), and the
longest, per package.

    python scripts/code_metrics.py [--rev HEAD] [--limit 60] [--repo .]

A function's length is its ``def`` line to its last line (docstring and comments included),
as :mod:`ast` gives them; nothing is imported or run.
"""

from __future__ import annotations

import argparse
import ast
import subprocess
import sys
from pathlib import Path

from _tables import markdown_table

#: package label -> folder in the repository
PACKAGES = {"pantocosim.core": "fmus/core", "pantocosim.catenary": "fmus/catenary",
            "pantocosim.pantograph": "fmus/pantograph", "pantocosim.multibody": "fmus/multibody",
            "pantocosim.fmi": "fmus/fmi", "pantocosim.master": "master", "scripts": "scripts",
            "tests": "tests"}


def git(repo: Path, *args: str) -> str:
    return subprocess.run(["git", "-C", str(repo), *args], capture_output=True, text=True,
                          check=True).stdout


def sources(repo: Path, rev: str, folder: str) -> dict[str, str]:
    """{path: text} of the Python files under ``folder`` at ``rev``."""
    names = git(repo, "ls-tree", "-r", "--name-only", rev, "--", folder).split()
    return {n: git(repo, "show", f"{rev}:{n}") for n in names if n.endswith(".py")}


def functions(path: str, text: str) -> list[tuple[int, str]]:
    """(lines, qualified name) of every function in a module."""
    out = []

    def visit(node, prefix):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                name = f"{prefix}{child.name}"
                out.append((child.end_lineno - child.lineno + 1, f"{path}::{name}"))
                visit(child, name + ".")
            elif isinstance(child, ast.ClassDef):
                visit(child, f"{prefix}{child.name}.")
            else:
                visit(child, prefix)

    visit(ast.parse(text, path), "")
    return out


def metrics(repo: Path, rev: str, limit: int) -> list[dict]:
    rows = []
    for label, folder in PACKAGES.items():
        files = sources(repo, rev, folder)
        if label == "pantocosim.master":   # its subpackages are in the label; nothing else
            files = {k: v for k, v in files.items() if k.startswith("master/")}
        fns = [f for path, text in files.items() for f in functions(path, text)]
        longest = max(fns, default=(0, "-"))
        rows.append({"package": label, "files": len(files), "functions": len(fns),
                     "over_limit": sum(1 for n, _ in fns if n > limit),
                     "longest_lines": longest[0], "longest": longest[1]})
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rev", default="HEAD")
    ap.add_argument("--limit", type=int, default=60)
    ap.add_argument("--repo", type=Path, default=Path(__file__).resolve().parents[1])
    a = ap.parse_args(argv)
    rows = metrics(a.repo, a.rev, a.limit)
    total = {"functions": sum(r["functions"] for r in rows),
             "over_limit": sum(r["over_limit"] for r in rows)}
    print(f"## Function sizes at {a.rev} (limit {a.limit} lines)\n")
    print(markdown_table(
        ("package", "files", "functions", f"> {a.limit} lines", "longest [lines]", "longest"),
        [(r["package"], r["files"], r["functions"], r["over_limit"], r["longest_lines"],
          f"`{r['longest']}`") for r in rows]
        + [("all", "", total["functions"], total["over_limit"], "", "")]), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
