"""The import graph of the package, read statically (``ast``: the Blender modules need no bpy):
no import circles, and every import goes the way docs/ARCHITECTURE.md Section 1 draws the layers.

Every ``import`` counts, wherever it is written: at the top, inside a function (an import "when
used" still ties the two modules together) or under ``TYPE_CHECKING``.
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "blender_turning"
PACKAGE = "blender_turning"

#: The packages a layer may import besides itself (docs/ARCHITECTURE.md Section 1).
LAYERS = {
    "core": set(),
    "mapping": {"core"},
    "crowd": {"core", "mapping"},
    "figures": {"core", "crowd"},
    "cli": {"core", "figures", "crowd"},
    "blender": {"core", "mapping", "crowd"},
}
#: Modules of Blender's own Python, importable only inside Blender (or the bpy wheel).
BLENDER_ONLY = {"bpy", "mathutils", "bpy_extras", "bl_ui", "bl_operators", "bl_math", "bmesh",
                "addon_utils", "gpu", "gpu_extras", "blf", "bgl", "aud", "idprop", "imbuf",
                "freestyle", "rna_prop_ui", "bl_ext"}


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def modules() -> dict:
    """``{dotted name: path}`` of every module of the package."""
    return {module_name(p): p for p in sorted(ROOT.rglob("*.py"))}


def imports(name: str, path: Path, known: dict) -> list:
    """``[(imported name, line)]``: the package's own modules ``name`` imports (resolved to a
    module where ``from pkg import mod`` names one) and every outside top-level name."""
    is_pkg = path.name == "__init__.py"
    here = name.split(".") if is_pkg else name.split(".")[:-1]
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            out += [(a.name, node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = here[:len(here) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module
            for a in node.names:
                sub = f"{target}.{a.name}"
                out.append((sub if sub in known else target, node.lineno))
    return out


def graph() -> tuple:
    """``(edges, outside)``: ``edges[m] = {n: line}`` between the package's modules, and
    ``outside[m] = {top-level name: line}``."""
    known = modules()
    edges, outside = {}, {}
    for name, path in known.items():
        edges[name], outside[name] = {}, {}
        for target, line in imports(name, path, known):
            if target == PACKAGE or target.startswith(PACKAGE + "."):
                while target not in known:              # ``from .x import y`` of a non-module
                    target = target.rsplit(".", 1)[0]
                if target != name:
                    edges[name].setdefault(target, line)
            else:
                outside[name].setdefault(target.split(".")[0], line)
    return edges, outside


def layer(name: str) -> str:
    parts = name.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in LAYERS else ""


def cycles(edges: dict) -> list:
    """One chain ``[a, b, ..., a]`` for every strongly connected part with a circle (Tarjan)."""
    index, low, stack, on, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in edges[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            part = set()
            while True:
                w = stack.pop()
                on.discard(w)
                part.add(w)
                if w == v:
                    break
            if len(part) > 1:
                found.append(chain(edges, part))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return found


def chain(edges: dict, part: set) -> list:
    """A shortest circle through the first module of ``part`` (breadth first inside it)."""
    start = min(part)
    prev, todo = {start: None}, [start]
    while todo:
        v = todo.pop(0)
        for w in sorted(edges[v]):
            if w == start:
                path = [v]
                while prev[path[-1]] is not None:
                    path.append(prev[path[-1]])
                return path[::-1] + [start]
            if w in part and w not in prev:
                prev[w] = v
                todo.append(w)
    raise AssertionError(part)


def show(edges: dict, path: list) -> str:
    return " -> ".join(f"{a} (line {edges[a][b]})" for a, b in zip(path, path[1:])) + \
        f" -> {path[-1]}"


def test_the_walk_sees_every_layer():
    """An empty or partial walk cannot pass: each layer has its modules, Blender's included."""
    counts = {k: sum(layer(m) == k for m in modules()) for k in LAYERS}
    least = {"core": 40, "mapping": 15, "crowd": 5, "figures": 4, "cli": 8, "blender": 25}
    assert all(counts[k] >= least[k] for k in LAYERS), counts
    edges, outside = graph()
    assert "bpy" in outside["blender_turning.blender.anim.bake"]          # the parser sees imports
    assert "blender_turning.core.planner.problem" in edges["blender_turning.core.planner.search"]


def test_no_import_circles():
    edges, _ = graph()
    found = cycles(edges)
    assert not found, "import circles:\n" + "\n".join(show(edges, c) for c in found)


def test_imports_follow_the_layers():
    edges, _ = graph()
    bad = []
    for name, targets in sorted(edges.items()):
        mine = layer(name)
        for target, line in sorted(targets.items()):
            theirs = layer(target)
            if not mine or not theirs or theirs == mine:
                continue
            if theirs not in LAYERS[mine]:
                bad.append(f"{name} (line {line}) imports {target}: {mine} may import "
                           f"{sorted(LAYERS[mine]) or 'nothing else'}")
    assert not bad, "\n".join(bad)


def test_only_the_blender_layer_imports_blender():
    _, outside = graph()
    bad = [f"{name} (line {line}) imports {top}"
           for name, tops in sorted(outside.items()) if layer(name) != "blender"
           for top, line in sorted(tops.items()) if top in BLENDER_ONLY]
    assert not bad, "\n".join(bad)


def script_imports() -> dict:
    """``{script: {imported name: line}}`` of the scripts (``scripts/``), which use the package
    by its absolute names; ``from pkg import mod`` counts as ``pkg.mod``."""
    out = {}
    for path in sorted((ROOT.parent / "scripts").rglob("*.py")):
        found = out[path.relative_to(ROOT.parent).as_posix()] = {}
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            if isinstance(node, ast.Import):
                found.update((a.name, node.lineno) for a in node.names)
            elif isinstance(node, ast.ImportFrom) and not node.level:
                found.update((f"{node.module}.{a.name}", node.lineno) for a in node.names)
    return out


def test_operators_are_leaves():
    """Nothing imports an operator module (``blender/ops/``), not even a script: what operators
    share lives in a module of its own (a job, a scene reader).  Only the Blender layer's
    ``register()`` loads them, by name."""
    edges, _ = graph()
    ops = f"{PACKAGE}.blender.ops"
    found = dict(edges, **script_imports())
    assert len(found) > len(edges) and "bpy" in found["scripts/bench_bake.py"]
    bad = [f"{name} (line {line}) imports {target}"
           for name, targets in sorted(found.items())
           for target, line in sorted(targets.items())
           if target == ops or target.startswith(ops + ".")]
    assert not bad, "\n".join(bad)


#: The most modules one folder of ``blender/``, ``core/`` or ``mapping/`` holds
#: (docs/ARCHITECTURE.md Section 1).
FOLDER_MODULES = 12


@pytest.mark.parametrize("part, least_folders, least_modules", [
    ("blender", 7, 30), ("core", 6, 40), ("mapping", 3, 20),
])
def test_folders_hold_a_dozen_modules_at_most(part, least_folders, least_modules):
    """Each folder of ``blender/``, ``core/`` and ``mapping/`` holds the modules of one part, at
    most a dozen (``__init__`` not counted): a new module goes into the folder of its part, a
    part that outgrows it splits."""
    folders = {p.parent for p in (ROOT / part).rglob("*.py")}
    counts = {f.relative_to(ROOT.parent).as_posix():
              sum(p.name != "__init__.py" for p in f.glob("*.py")) for f in folders}
    assert len(counts) >= least_folders and sum(counts.values()) >= least_modules, counts
    big = {f: n for f, n in sorted(counts.items()) if n > FOLDER_MODULES}
    assert not big, f"more than {FOLDER_MODULES} modules in a folder: {big}"


@pytest.mark.parametrize("edges, circle", [
    ({"a": {"b": 1}, "b": {"c": 2}, "c": {"a": 3}, "d": {"a": 4}}, ["a", "b", "c", "a"]),
    ({"a": {"b": 1}, "b": {"a": 2}}, ["a", "b", "a"]),
])
def test_a_circle_is_found_and_shown(edges, circle):
    assert cycles(edges) == [circle]
    assert show(edges, circle).startswith("a (line 1) -> b")


def test_no_circle_in_a_tree():
    assert cycles({"a": {"b": 1, "c": 1}, "b": {"c": 2}, "c": {}}) == []
