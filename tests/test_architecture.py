"""The layout's one rule, checked on the source: imports run downward only (docs/architecture.md).

Each top-level module or package of carom has a layer; a module may import from its own layer
and those below it, never from above. (Imports made only for type checking are included: a
type an engine needs from a higher layer is a sign it sits in the wrong place.)
"""

from __future__ import annotations

import ast
from pathlib import Path

import carom

ROOT = Path(carom.__file__).parent
LAYERS = [
    # the base: they import only each other
    {"errors", "limits", "_inputs", "_text", "_memory", "jit"},
    {"geometry", "laws"},  # world-free kernels and closed forms
    # the engine-neutral core
    {"shapes", "shapes3d", "meshes", "materials", "bodies", "body_input"},
    {"engines"},
    {"world", "scenery", "recording", "collision_log", "observables", "checkpoint"},
    {"scene", "reference", "studies"},
    {"io", "viz"},
    {"run", "compare", "sweeps"},
    {"cli", "__init__", "__main__"},
]
RANK = {name: rank for rank, names in enumerate(LAYERS) for name in names}


def _top(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return parts[0]


def test_every_module_has_a_layer() -> None:
    tops = {_top(p) for p in ROOT.rglob("*.py")} - {"scenarios"}
    assert tops <= set(RANK), sorted(tops - set(RANK))


def test_no_import_runs_upward() -> None:
    upward = []
    for path in ROOT.rglob("*.py"):
        here = _top(path)
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module]
            elif isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            else:
                continue
            for name in names:
                parts = name.split(".")
                if parts[0] != "carom" or len(parts) == 1:
                    continue  # ("from carom import __version__" reads the package's own data)
                there = parts[1]
                if RANK[there] > RANK[here]:
                    upward.append(f"{path.relative_to(ROOT)} imports {name}")
    assert upward == []
