"""The layout's rules, checked on the source (docs/architecture.md).

1. Each top-level module or package of carom has a rank; a module imports only from ranks
   below its own (modules of one rank are independent of each other).
2. Inside ``carom.engines`` the same holds between its packages: the protocol first, the
   engines beside each other, the table of engines on top.
3. No module imports, however indirectly, a module that imports it: no cycles, counting every
   import (at the top, inside a function, or for type checking only).

Imports made only for type checking count everywhere: a type a module needs from above it is
a sign it sits in the wrong place; it takes a Protocol of what it reads instead.
"""

from __future__ import annotations

import ast
from pathlib import Path

import carom

ROOT = Path(carom.__file__).parent
LAYERS = [
    # the base
    {"errors", "_text", "_memory", "jit"},
    {"limits"},
    {"_inputs"},
    # world-free kernels and closed forms
    {"geometry"},
    {"laws"},
    # the engine-neutral core
    {"shape_base"},
    {"shapes", "shapes3d", "materials"},
    {"meshes"},
    {"bodies"},
    {"body_input"},
    {"engines"},
    # the facade and what it is made of
    {"scenery", "recording", "collision_log", "checkpoint", "gameloop", "queries", "joints"},
    {"sensing", "kinds"},
    {"observables"},
    {"world"},
    # the edges
    {"scene", "reference"},
    {"studies"},
    {"io"},
    {"viz"},
    {"play"},
    {"compare", "sweeps"},
    {"run"},
    {"cli", "__init__"},
    {"__main__"},
]
#: the packages of carom.engines, ranked the same way: the rigid engines of the two
#: dimensions side by side on their shared core, neither importing the other
ENGINE_LAYERS = [{"base"}, {"stepped"}, {"edmd", "rigid", "rigid3d"}, {"registry"}]


def _rank(layers: list[set[str]]) -> dict[str, int]:
    return {name: rank for rank, names in enumerate(layers) for name in names}


RANK = _rank(LAYERS)
ENGINE_RANK = _rank(ENGINE_LAYERS)


def _module(path: Path) -> str:
    parts = ["carom", *path.relative_to(ROOT).with_suffix("").parts]
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_module(p): p for p in ROOT.rglob("*.py")}


def _imports(path: Path) -> set[str]:
    """The carom modules ``path`` imports, anywhere in it (``from package import module``
    names the module; a name from a package, its ``__init__``)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [f"{node.module}.{alias.name}" for alias in node.names]
        elif isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        else:
            continue
        for name in names:
            while name and name not in MODULES:
                name = name.rpartition(".")[0]
            if name.startswith("carom.") and name != "carom":
                found.add(name)
    return found


GRAPH = {name: _imports(path) - {name} for name, path in MODULES.items()}


def _top(name: str, depth: int = 1) -> str:
    parts = name.split(".")
    return parts[depth] if len(parts) > depth else "__init__"


def test_every_module_has_a_rank() -> None:
    tops = {_top(name) for name in MODULES} - {"scenarios"}
    assert tops <= set(RANK), sorted(tops - set(RANK))
    engines = {_top(n, 2) for n in MODULES if n.startswith("carom.engines.")}
    assert engines == set(ENGINE_RANK), sorted(engines ^ set(ENGINE_RANK))


def test_imports_run_downward_between_ranks() -> None:
    upward = [
        f"{name} imports {there}"
        for name, targets in GRAPH.items()
        for there in targets
        if _top(there) != _top(name) and RANK[_top(there)] >= RANK[_top(name)]
    ]
    assert upward == []


def test_imports_run_downward_between_the_engines_packages() -> None:
    inside = {n: t for n, t in GRAPH.items() if n.startswith("carom.engines.")}
    upward = [
        f"{name} imports {there}"
        for name, targets in inside.items()
        for there in targets
        if there.startswith("carom.engines.")
        and _top(there, 2) != _top(name, 2)
        and ENGINE_RANK[_top(there, 2)] >= ENGINE_RANK[_top(name, 2)]
    ]
    assert upward == []


def test_no_module_imports_itself_through_others() -> None:
    # Tarjan's strongly connected components: any of more than one module is a cycle
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    cycles: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in GRAPH[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for v in sorted(GRAPH):
        if v not in index:
            visit(v)
    assert cycles == []


def test_the_rules_see_a_cycle_and_an_upward_import() -> None:
    # the checks above are not vacuous: the graph holds the imports they judge
    assert "carom.engines.base" in GRAPH["carom.engines.edmd.driver"]
    assert "carom.engines.registry" in GRAPH["carom.world"]
    assert "carom.checkpoint" in GRAPH["carom.world"]  # (inside World.save and load)
    assert "carom.world" not in GRAPH["carom.checkpoint"]


def test_the_world_stays_a_facade() -> None:
    # issue 42: world.py at most 600 lines; what it grows goes to the modules it is made of
    # (scenery, recording, collision_log, checkpoint) or to the engines
    import carom.world

    lines = Path(carom.world.__file__).read_text(encoding="utf-8").splitlines()
    assert len(lines) <= 600, len(lines)
