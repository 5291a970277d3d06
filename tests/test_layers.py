"""The package's layers (issue 10): importing a module loads nothing of a higher layer,
``import deformclosure`` loads no heavy optional machinery, and there is no import cycle.

Only import-time imports count: an import inside a function runs when the function does.
Layers, low to high (a module may import its own layer and the layers below):

====  ======================================================================
L0    errors, choices, geometry, units, jsonfile, outputs, log
L1    part, drawing, mesh
L2    elasticity
L3    grasp, dspace, pads, fields, limits
L4    planning (planning.plan, planning._kernels), plotting
L5    reports, batch (planning.batch until it moves to batch)
L6    cli, __main__
====  ======================================================================

The runtime checks import each name in a fresh interpreter (a forked child of a clean
interpreter that has loaded the third-party libraries only, so no module of the package
is loaded before the one under test); the static check reads the sources with ``ast``.
"""

from __future__ import annotations

import ast
import importlib.util
import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

SRC = Path(importlib.util.find_spec("deformclosure").origin).resolve().parent
PKG = "deformclosure"

#: Layer of each entry; a module belongs to the entry that is its longest prefix.
LAYERS: dict[str, int] = {
    "errors": 0, "choices": 0, "geometry": 0, "units": 0, "jsonfile": 0, "outputs": 0, "log": 0,
    "part": 1, "drawing": 1, "mesh": 1,
    "elasticity": 2,
    "contact": 3, "landscape": 3,
    "grasp": 3, "dspace": 3, "pads": 3, "fields": 3, "limits": 3,
    "planning": 4, "planning.plan": 4, "planning._kernels": 4, "plotting": 4,
    "reports": 5, "batch": 5, "planning.batch": 5,
    "cli": 6, "__main__": 6,
}

#: What ``import deformclosure`` alone must not load (issue 10): storage, process pools,
#: clusters, plotting, the command line and the JIT compiler are loaded when used.
HEAVY = ("sqlite3", "multiprocessing", "dask", "distributed", "matplotlib", "click", "numba")


def layer_of(module: str) -> int | None:
    """Layer of ``deformclosure.<...>`` (``None`` for the package root or an unknown name)."""
    parts = module.split(".")[1:]
    for n in range(len(parts), 0, -1):
        key = ".".join(parts[:n])
        if key in LAYERS:
            return LAYERS[key]
    return None


# --------------------------------------------------------------------------- static graph
def source_modules(src: Path = SRC, pkg: str = PKG) -> dict[str, Path]:
    """Every module of the package by dotted name, from the source tree."""
    out = {}
    for path in sorted(src.rglob("*.py")):
        rel = path.relative_to(src).with_suffix("")
        parts = [pkg, *rel.parts]
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _is_type_checking(test: ast.expr) -> bool:
    return ((isinstance(test, ast.Name) and test.id == "TYPE_CHECKING")
            or (isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"))


def _import_time_nodes(body):
    """Import statements executed when the module is imported: module level, inside
    ``if``/``try``/``with``/``for`` blocks and class bodies; not in functions, not under
    ``if TYPE_CHECKING``."""
    for node in body:
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        elif isinstance(node, ast.If):
            if not _is_type_checking(node.test):
                yield from _import_time_nodes(node.body)
            yield from _import_time_nodes(node.orelse)
        elif isinstance(node, ast.ClassDef):
            yield from _import_time_nodes(node.body)
        elif isinstance(node, (ast.Try, getattr(ast, "TryStar", ast.Try))):
            yield from _import_time_nodes(node.body)
            for h in node.handlers:
                yield from _import_time_nodes(h.body)
            yield from _import_time_nodes(node.orelse)
            yield from _import_time_nodes(node.finalbody)
        elif isinstance(node, (ast.With, ast.AsyncWith, ast.For, ast.AsyncFor, ast.While)):
            yield from _import_time_nodes(node.body)
            yield from _import_time_nodes(getattr(node, "orelse", []))


def _ancestors(module: str) -> list[str]:
    parts = module.split(".")
    return [".".join(parts[:n]) for n in range(1, len(parts))]


def import_graph(src: Path = SRC, pkg: str = PKG) -> tuple[dict[str, set[str]],
                                                           dict[str, set[str]]]:
    """Import-time edges between modules of the package, and for each module the other
    top-level modules (third-party and standard library) it imports at import time.

    ``from .a import b`` is an edge to ``a.b`` when that is a module, else to ``a``; an
    import of ``x.y.z`` also runs the ``__init__`` of ``x`` and ``x.y``, which are edges
    too unless they enclose the importer (then they are already being imported).
    """
    mods = source_modules(src, pkg)
    graph: dict[str, set[str]] = {m: set() for m in mods}
    external: dict[str, set[str]] = {m: set() for m in mods}
    for mod, path in mods.items():
        is_pkg = path.name == "__init__.py"
        package = mod if is_pkg else mod.rpartition(".")[0]
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        targets = []
        for node in _import_time_nodes(tree.body):
            if isinstance(node, ast.Import):
                targets += [a.name for a in node.names]
                continue
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                stem = ".".join(base + ([node.module] if node.module else []))
            else:
                stem = node.module
            for alias in node.names:
                sub = f"{stem}.{alias.name}"
                targets.append(sub if sub in mods or stem.split(".")[0] != pkg else stem)
        for t in targets:
            if t.split(".")[0] != pkg:
                external[mod].add(t)      # dotted; ``from a import b`` gives ``a.b``
                continue
            if t not in mods:
                continue
            enclosing = set(_ancestors(mod)) | {mod}
            for a in [*_ancestors(t), t]:
                if a not in enclosing:
                    graph[mod].add(a)
    return graph, external


def find_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """One cycle per strongly connected component of more than one module (or a
    self-import), found by depth-first search (Tarjan)."""
    index, low, stack, on, comps = {}, {}, [], set(), []
    counter = [0]

    def strong(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1 or v in graph.get(v, ()):
                comps.append(sorted(comp))

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 10 * len(graph) + 100))
    for v in sorted(graph):
        if v not in index:
            strong(v)

    cycles = []
    for comp in comps:
        members = set(comp)
        start = comp[0]
        # Shortest way back to ``start`` inside the component (breadth-first).
        prev, frontier, found = {start: None}, [start], None
        while frontier and found is None:
            nxt = []
            for v in frontier:
                for w in sorted(graph[v] & members):
                    if w == start:
                        found = v
                        break
                    if w not in prev:
                        prev[w] = v
                        nxt.append(w)
                if found is not None:
                    break
            frontier = nxt
        path = [found]
        while prev[path[-1]] is not None:
            path.append(prev[path[-1]])
        cycles.append(path[::-1] + [start])
    return cycles


def chain(graph: dict[str, set[str]], src: str, dst: str) -> list[str] | None:
    """A shortest import chain ``src → … → dst`` in the static graph."""
    prev, frontier = {src: None}, [src]
    while frontier:
        nxt = []
        for v in frontier:
            for w in sorted(graph.get(v, ())):
                if w not in prev:
                    prev[w] = v
                    if w == dst:
                        path = [w]
                        while prev[path[-1]] is not None:
                            path.append(prev[path[-1]])
                        return path[::-1]
                    nxt.append(w)
        frontier = nxt
    return None


# --------------------------------------------------------------------------- runtime
_PROBE = textwrap.dedent("""
    import importlib, json, os, sys
    names, preload = json.loads(sys.argv[1]), json.loads(sys.argv[2])
    for lib in preload:                 # third-party only: speeds up every child
        try:
            importlib.import_module(lib)
        except Exception:
            pass
    assert not [m for m in sys.modules if m == "deformclosure" or m.startswith("deformclosure.")]
    out = {}
    for name in names:
        if not hasattr(os, "fork"):
            break
        r, w = os.pipe()
        pid = os.fork()
        if pid == 0:
            os.close(r)
            try:
                importlib.import_module(name)
                res = {"modules": sorted(m for m in sys.modules
                                         if m == "deformclosure" or m.startswith("deformclosure."))}
            except BaseException as err:
                res = {"error": f"{type(err).__name__}: {err}"}
            with os.fdopen(w, "w") as fh:
                json.dump(res, fh)
            os._exit(0)
        os.close(w)
        with os.fdopen(r) as fh:
            text = fh.read()
        os.waitpid(pid, 0)
        out[name] = json.loads(text) if text else {"error": "the child died"}
    print(json.dumps(out))
""")


def _entries() -> list[str]:
    return [f"{PKG}.{k}" for k in LAYERS]


@pytest.fixture(scope="module")
def loaded() -> dict[str, dict]:
    """For each entry of :data:`LAYERS` that exists: the package modules that importing
    it alone loads (or the error)."""
    names = [n for n in _entries() if importlib.util.find_spec(n) is not None]
    _, external = import_graph()
    preload = sorted({e for ext in external.values() for e in ext} - set(sys.builtin_module_names))
    if not hasattr(__import__("os"), "fork"):   # pragma: no cover - Windows: one interpreter each
        out = {}
        for n in names:
            code = (f"import importlib, json, sys; importlib.import_module({n!r}); "
                    "print(json.dumps({'modules': sorted(m for m in sys.modules "
                    "if m.startswith('deformclosure'))}))")
            proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
            out[n] = (json.loads(proc.stdout) if proc.returncode == 0
                      else {"error": proc.stderr.strip().splitlines()[-1]})
        return out
    proc = subprocess.run([sys.executable, "-c", _PROBE, json.dumps(names), json.dumps(preload)],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def graph() -> dict[str, set[str]]:
    return import_graph()[0]


@pytest.mark.parametrize("entry", list(LAYERS))
def test_importing_loads_no_higher_layer(entry, loaded, graph):
    name = f"{PKG}.{entry}"
    if importlib.util.find_spec(name) is None:
        return      # not written yet (issue 10: reports, batch); stays in the table
    res = loaded[name]
    assert "error" not in res, f"import {name}: {res.get('error')}"
    own = LAYERS[entry]
    higher = [m for m in res["modules"] if (layer_of(m) or -1) > own]
    if higher:
        groups: dict[str, list[str]] = {}
        for m in higher:
            groups.setdefault(_entry_of(m), []).append(m)
        lines = [f"import {name} (L{own}) loads {len(higher)} module(s) of higher layers:"]
        for key, ms in sorted(groups.items(), key=lambda kv: (-LAYERS[kv[0]], kv[0])):
            via = None
            for start in [name, *reversed(_ancestors(name))]:
                via = chain(graph, start, ms[0])
                if via:
                    break
            lines.append(f"  L{LAYERS[key]} {key}: {len(ms)} module(s)"
                         + (f", e.g. {' -> '.join(via)}" if via else ""))
        pytest.fail("\n".join(lines), pytrace=False)


def _entry_of(module: str) -> str:
    parts = module.split(".")[1:]
    for n in range(len(parts), 0, -1):
        if ".".join(parts[:n]) in LAYERS:
            return ".".join(parts[:n])
    return module


def test_every_module_has_a_layer():
    unknown = [m for m in source_modules() if m != PKG and layer_of(m) is None]
    assert not unknown, f"add these to LAYERS in {__file__}: {unknown}"


def test_static_imports_respect_the_layers(graph):
    """The same rule on the sources: no module imports, at import time, a module of a
    higher layer (this sees imports the runtime test does not reach, e.g. of submodules
    that are not imported by their package)."""
    bad = sorted((layer_of(a), a, layer_of(b), b) for a, targets in graph.items()
                 for b in targets if a != PKG and b != PKG
                 and (layer_of(b) or -1) > (layer_of(a) if layer_of(a) is not None else 99))
    msg = "\n".join(f"  L{la} {a} imports L{lb} {b}" for la, a, lb, b in bad)
    if bad:
        pytest.fail(f"{len(bad)} import-time import(s) of a higher layer:\n{msg}", pytrace=False)


def test_no_import_cycles(graph):
    cycles = find_cycles(graph)
    msg = "\n".join("  " + " -> ".join(c) for c in cycles)
    if cycles:
        pytest.fail(f"{len(cycles)} import cycle(s) among modules at import time:\n{msg}",
                    pytrace=False)


def test_the_import_graph_counts_only_import_time_imports(tmp_path):
    """On a made-up package: module level, ``try`` and class bodies count; functions and
    ``if TYPE_CHECKING`` do not; relative imports resolve; a package's ``__init__`` is
    an edge of every import through it."""
    src = tmp_path / "pk"
    (src / "sub").mkdir(parents=True)
    files = {
        "__init__.py": "",
        "a.py": "from . import b\nfrom .sub.c import thing\nimport numpy as np\n",
        "b.py": "def f():\n    from . import a\n",
        "d.py": ("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .a import x\n"
                 "else:\n    from . import b\ntry:\n    from .e import y\nexcept ImportError:\n"
                 "    pass\nclass K:\n    from .sub import c\n"),
        "e.py": "from .d import K\n",
        "sub/__init__.py": "from .c import thing\n",
        "sub/c.py": "from ..b import f\nthing = 1\n",
    }
    for name, text in files.items():
        (src / name).write_text(text)
    graph, external = import_graph(src, "pk")
    assert graph["pk.a"] == {"pk.b", "pk.sub", "pk.sub.c"}
    assert graph["pk.b"] == set()
    assert graph["pk.d"] == {"pk.b", "pk.e", "pk.sub", "pk.sub.c"}
    assert graph["pk.sub"] == {"pk.sub.c"}
    assert graph["pk.sub.c"] == {"pk.b"}
    assert "numpy" in external["pk.a"]
    assert find_cycles(graph) == [["pk.d", "pk.e", "pk.d"]]
    assert chain(graph, "pk.a", "pk.b") == ["pk.a", "pk.b"]


def test_layer_table():
    assert layer_of("deformclosure.errors") == 0
    assert layer_of("deformclosure.grasp._kernels") == 3
    assert layer_of("deformclosure.planning._kernels") == 4
    assert layer_of("deformclosure.planning.batch") == 5
    assert layer_of("deformclosure.cli.main") == 6
    assert layer_of("deformclosure") is None


def test_the_cycle_finder_finds_cycles():
    g = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"d"}, "e": {"a"}}
    cycles = find_cycles(g)
    assert sorted(map(tuple, cycles)) == [("a", "b", "c", "a"), ("d", "d")]
    assert find_cycles({"a": {"b"}, "b": set()}) == []


def test_import_deformclosure_loads_no_heavy_machinery():
    code = ("import json, sys; import deformclosure; "
            "print(json.dumps(sorted(sys.modules)))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    mods = json.loads(proc.stdout.strip().splitlines()[-1])
    heavy = sorted({m.split(".")[0] for m in mods} & set(HEAVY))
    if heavy:
        ours = [m for m in mods if m == PKG or m.startswith(PKG + ".")]
        _, external = import_graph()
        lines = [f"import deformclosure loads {heavy}; it loads {len(ours)} of its own modules"]
        for h in heavy:
            by = [m for m in ours if any(e.split(".")[0] == h for e in external.get(m, ()))]
            lines.append(f"  {h}: imported at import time by "
                         + (", ".join(by) if by else "(no module of the package directly: "
                            "through a library)"))
        pytest.fail("\n".join(lines), pytrace=False)
