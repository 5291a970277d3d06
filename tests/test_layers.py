"""The package's layers (issues 10, 19): no module imports a module of a higher layer, no
import cycle, no module takes another package's private names, and ``import deformclosure``
loads no heavy optional machinery.

Layers, low to high (a module may import its own layer and the layers below):

====  ======================================================================
L0    foundation: errors, choices, geometry, units, jsonfile, outputs, log,
      limits (the resource-limit constants and the size checks on plain numbers)
L1    inputs: part, drawing, mesh
L2    elasticity
L3    mechanics: contact, landscape (issue 19; the release searches, their compiled
      kernels landscape.kernels, the noise-floor and elastic-limit rules)
L4    models: grasp, dspace, pads, fields, and the per-model limit estimators beside
      their models (grasp.size_limits, pads.size_limits); grasp, dspace and pads import
      none of each other
L5    planners, pictures: planning, plotting
L6    reports, batch
L7    cli, __main__
====  ======================================================================

The static checks read the sources with ``ast`` and count **every** import statement
(:func:`scan_imports`): at module level, inside functions (they run when the function
does, and still make the module depend on the one imported), in class bodies, ``try``
and ``if`` blocks. Only imports under ``if TYPE_CHECKING`` (annotations, never run) are
exempt from the cycle check; they must still respect the layers. The runtime checks
import each name in a fresh interpreter (a forked child of a clean interpreter that has
loaded the third-party libraries only, so no module of the package is loaded before the
one under test). Dynamic imports (``importlib.import_module``: the top level's lazy
names, ``reports.run``) are not statements and are not counted; they only go downwards
from the package root and from ``reports``.
"""

from __future__ import annotations

import ast
import importlib.util
import json
import subprocess
import sys
import textwrap
from dataclasses import dataclass
from pathlib import Path

import pytest

SRC = Path(importlib.util.find_spec("deformclosure").origin).resolve().parent
PKG = "deformclosure"

#: Layer of each entry; a module belongs to the entry that is its longest prefix. An entry
#: whose module does not exist (yet) is skipped by the runtime test and stays registered.
LAYERS: dict[str, int] = {
    "errors": 0, "choices": 0, "geometry": 0, "units": 0, "jsonfile": 0, "outputs": 0, "log": 0,
    "limits": 0,
    "part": 1, "drawing": 1, "mesh": 1,
    "elasticity": 2,
    "contact": 3, "landscape": 3,
    "grasp": 4, "dspace": 4, "pads": 4, "fields": 4,
    "planning": 5, "plotting": 5,
    "reports": 6, "batch": 6,
    "cli": 7, "__main__": 7,
}

#: Model packages that import none of each other: dspace is the general model, pads the
#: special one on a grasp axis, grasp the paper's; what they share lives below them.
MODELS_APART = ("grasp", "dspace", "pads")

#: Imports that break the rules only in files being rewritten for issue 19 (the
#: ``contact/`` and ``landscape/`` refactor; not to be edited meanwhile): ``(importer,
#: imported)`` without the ``deformclosure.`` prefix, as the failure messages print them.
#: The refactor removes them and then this constant; nothing may be added to it.
PENDING_CONTACT_REFACTOR: set[tuple[str, str]] = set()

#: What ``import deformclosure`` alone must not load (issue 10): storage, process pools,
#: clusters, plotting, the command line and the JIT compiler are loaded when used.
HEAVY = ("sqlite3", "multiprocessing", "dask", "distributed", "matplotlib", "click", "numba")


def layer_of(module: str, table: dict[str, int] | None = None) -> int | None:
    """Layer of ``deformclosure.<...>`` in ``table`` (default :data:`LAYERS`; ``None`` for
    the package root or an unknown name)."""
    table = LAYERS if table is None else table
    parts = module.split(".")[1:]
    for n in range(len(parts), 0, -1):
        key = ".".join(parts[:n])
        if key in table:
            return table[key]
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


#: When an import statement runs: with the module (``"import"``: module level, inside
#: ``if``/``try``/``with``/``for`` blocks and class bodies), when a function runs
#: (``"function"``), or never (``"type"``: under ``if TYPE_CHECKING``, for annotations).
WHEN = ("import", "function", "type")
RUNS_AT_IMPORT = ("import",)


def _import_nodes(body, when: str = "import"):
    """Every import statement of ``body`` with when it runs (:data:`WHEN`)."""
    for node in body:
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node, when
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            yield from _import_nodes(node.body, "type" if when == "type" else "function")
        elif isinstance(node, ast.If):
            yield from _import_nodes(node.body, "type" if _is_type_checking(node.test) else when)
            yield from _import_nodes(node.orelse, when)
        elif isinstance(node, ast.ClassDef):
            yield from _import_nodes(node.body, when)
        elif isinstance(node, (ast.Try, getattr(ast, "TryStar", ast.Try))):
            yield from _import_nodes(node.body, when)
            for h in node.handlers:
                yield from _import_nodes(h.body, when)
            yield from _import_nodes(node.orelse, when)
            yield from _import_nodes(node.finalbody, when)
        elif isinstance(node, (ast.With, ast.AsyncWith, ast.For, ast.AsyncFor, ast.While)):
            yield from _import_nodes(node.body, when)
            yield from _import_nodes(getattr(node, "orelse", []), when)
        elif hasattr(ast, "Match") and isinstance(node, ast.Match):
            for case in node.cases:
                yield from _import_nodes(case.body, when)


def _ancestors(module: str) -> list[str]:
    parts = module.split(".")
    return [".".join(parts[:n]) for n in range(1, len(parts))]


@dataclass(frozen=True)
class Import:
    """One imported module (or name) of one import statement.

    ``target`` is the module that the statement loads (``from .a import b`` loads ``a.b``
    when that is a module, else ``a``); ``name`` the name taken from it (``b``; ``None``
    for ``import x`` and for a submodule), ``line`` where, ``when`` see :data:`WHEN`;
    ``alias`` the local name it binds, and what it binds is ``target`` (``name`` None)
    or ``target.name`` (for ``import a.b`` without ``as``: ``a``, bound to ``a``).
    """

    importer: str
    target: str
    name: str | None
    line: int
    when: str
    alias: str = ""


def scan_imports_of(mod: str, tree: ast.Module, mods, pkg: str = PKG) -> list[Import]:
    """Every import statement of the module ``mod`` (its parsed ``tree``)."""
    package = mod if mods[mod].name == "__init__.py" else mod.rpartition(".")[0]
    out = []
    for node, when in _import_nodes(tree.body):
        if isinstance(node, ast.Import):
            for a in node.names:
                out.append(Import(mod, a.name, None, node.lineno, when, a.asname or a.name))
                if a.asname is None and "." in a.name:       # ``import a.b`` binds ``a``
                    out.append(Import(mod, a.name.split(".")[0], None, node.lineno, when,
                                      a.name.split(".")[0]))
            continue
        if node.level:
            base = package.split(".")
            base = base[:len(base) - (node.level - 1)]
            stem = ".".join(base + ([node.module] if node.module else []))
        else:
            stem = node.module
        for alias in node.names:
            sub = f"{stem}.{alias.name}"
            bind = alias.asname or alias.name
            if sub in mods:           # ``from . import x``: the submodule ``x``
                out.append(Import(mod, sub, None, node.lineno, when, bind))
            elif stem.split(".")[0] != pkg:
                out.append(Import(mod, sub, None, node.lineno, when, bind))
            else:
                out.append(Import(mod, stem, alias.name, node.lineno, when, bind))
    return out


def scan_imports(src: Path = SRC, pkg: str = PKG) -> list[Import]:
    """Every import statement anywhere in every module of the package (module level,
    functions, classes, ``if TYPE_CHECKING``), relative imports resolved."""
    mods = source_modules(src, pkg)
    out = []
    for mod, path in mods.items():
        out += scan_imports_of(mod, ast.parse(path.read_text(encoding="utf-8"), str(path)),
                               mods, pkg)
    return out


def module_edges(imports: list[Import], mods, pkg: str = PKG,
                 when: tuple[str, ...] = RUNS_AT_IMPORT):
    """``(importer, module, import)`` for every module of the package that an import
    statement running ``when`` loads: its target, and the ``__init__`` of every package
    around the target that does not enclose the importer (those are already loading)."""
    for imp in imports:
        if imp.when not in when or imp.target.split(".")[0] != pkg or imp.target not in mods:
            continue
        enclosing = set(_ancestors(imp.importer)) | {imp.importer}
        for a in [*_ancestors(imp.target), imp.target]:
            if a not in enclosing and a in mods:      # a namespace package runs no code
                yield imp.importer, a, imp


def import_graph(src: Path = SRC, pkg: str = PKG, when: tuple[str, ...] = RUNS_AT_IMPORT
                 ) -> tuple[dict[str, set[str]], dict[str, set[str]]]:
    """Edges between modules of the package made by the import statements that run
    ``when`` (:data:`WHEN`; default: at import time), and for each module the other
    top-level modules (third-party and standard library) it imports then.

    An import of ``x.y.z`` also runs the ``__init__`` of ``x`` and ``x.y``, which are edges
    too unless they enclose the importer (then they are already being imported).
    """
    mods = source_modules(src, pkg)
    imports = scan_imports(src, pkg)
    graph: dict[str, set[str]] = {m: set() for m in mods}
    external: dict[str, set[str]] = {m: set() for m in mods}
    for imp in imports:
        if imp.when in when and imp.target.split(".")[0] != pkg:
            external[imp.importer].add(imp.target)   # dotted; ``from a import b``: ``a.b``
    for a, b, _ in module_edges(imports, mods, pkg, when):
        graph[a].add(b)
    return graph, external


#: What the static layer and cycle checks count: every import that can run, at import
#: time or inside a function. Imports under ``if TYPE_CHECKING`` never run (annotations
#: only), so they are exempt from the cycle check; they still may not reach upwards.
RUNS = ("import", "function")


def full_graph(src: Path = SRC, pkg: str = PKG) -> dict[str, set[str]]:
    """The module graph of every import statement that can run (:data:`RUNS`)."""
    return import_graph(src, pkg, RUNS)[0]


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
        members, covered = set(comp), set()
        for start in comp:            # one shortest cycle through each member not yet shown
            if start in covered:
                continue
            cycle = _shortest_cycle(graph, members, start)
            covered.update(cycle)
            cycles.append(cycle)
    return cycles


def _shortest_cycle(graph: dict[str, set[str]], members: set[str], start: str) -> list[str]:
    """A shortest way from ``start`` back to itself inside ``members`` (breadth-first)."""
    prev, frontier, found = {start: None}, [start], None
    while frontier and found is None:
        nxt = []
        for v in frontier:
            for w in sorted(graph.get(v, set()) & members):
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
    return path[::-1] + [start]


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


def _short(module: str, pkg: str = PKG) -> str:
    return module[len(pkg) + 1:] if module.startswith(pkg + ".") else module


def _top(module: str) -> str:
    """The top-level subpackage (or module) of the package a module belongs to."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def _is_private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


@dataclass(frozen=True)
class Violation:
    """An import that breaks a rule: ``importer`` (line ``line``) loads ``imported``."""

    importer: str
    imported: str
    line: int
    rule: str

    def __str__(self) -> str:
        return f"  {self.importer}:{self.line} imports {self.imported} ({self.rule})"


def layer_violations(src: Path = SRC, pkg: str = PKG, layer=layer_of,
                     apart: tuple[str, ...] = MODELS_APART,
                     allowed: set[tuple[str, str]] = frozenset()) -> list[Violation]:
    """Every import statement (anywhere, also ``TYPE_CHECKING``) that loads a module of a
    higher layer, or a model package of :data:`MODELS_APART` from another one; the first
    line of each ``(importer, imported)`` pair. ``allowed`` pairs (short names) are skipped."""
    mods = source_modules(src, pkg)
    seen: dict[tuple[str, str], Violation] = {}
    for a, b, imp in module_edges(scan_imports(src, pkg), mods, pkg, WHEN):
        if a == pkg or b == pkg or (a, b) in seen or (_short(a, pkg), _short(b, pkg)) in allowed:
            continue
        la, lb = layer(a), layer(b)
        if lb is not None and (la is None or lb > la):
            seen[a, b] = Violation(_short(a, pkg), _short(b, pkg), imp.line,
                                   f"L{la} imports L{lb}")
        elif _top(a) != _top(b) and _top(a) in apart and _top(b) in apart:
            seen[a, b] = Violation(_short(a, pkg), _short(b, pkg), imp.line,
                                   f"model {_top(a)} imports model {_top(b)}")
    return sorted(seen.values(), key=lambda v: (v.importer, v.imported))


def private_violations(src: Path = SRC, pkg: str = PKG,
                       allowed: set[tuple[str, str]] = frozenset()) -> list[Violation]:
    """Every import of a private module (a ``_name`` in its dotted path, e.g.
    ``grasp._kernels``) or private name (``from grasp.pieces import _helper``) of another
    top-level subpackage; inside one subpackage (its own ``_kernels``) they are its own."""
    out = []
    for imp in scan_imports(src, pkg):
        t = imp.target
        if t.split(".")[0] != pkg or _top(t) == _top(imp.importer):
            continue
        private = [p for p in t.split(".")[1:] if _is_private(p)]
        if imp.name is not None and _is_private(imp.name):
            private.append(imp.name)
        if private:
            what = t if imp.name is None else f"{t}.{imp.name}"
            out.append(Violation(_short(imp.importer, pkg), _short(what, pkg), imp.line,
                                 f"private {', '.join(private)} of {_top(t)}"))
    out += _private_attributes(src, pkg)
    return [v for v in out if (v.importer, v.imported) not in allowed]


def _private_attributes(src: Path, pkg: str) -> list[Violation]:
    """``mod._name`` where ``mod`` is bound by an import to a module (or name) of another
    top-level subpackage: the same reach into private names, through an attribute."""
    mods = source_modules(src, pkg)
    out = []
    for mod, path in mods.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        bound: dict[str, str] = {}
        for imp in scan_imports_of(mod, tree, mods, pkg):
            if imp.target.split(".")[0] == pkg:
                bound[imp.alias] = imp.target if imp.name is None else f"{imp.target}.{imp.name}"

        def resolve(node) -> str | None:
            if isinstance(node, ast.Name):
                return bound.get(node.id)
            if isinstance(node, ast.Attribute):
                base = resolve(node.value)
                return None if base is None else f"{base}.{node.attr}"
            return None

        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute) and _is_private(node.attr):
                base = resolve(node.value)
                if base is not None and _top(base) != _top(mod):
                    out.append(Violation(_short(mod, pkg), _short(f"{base}.{node.attr}", pkg),
                                         node.lineno, f"private {node.attr} of {_top(base)}"))
    return out


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


def _fail(title: str, items) -> None:
    items = list(items)
    if items:
        pytest.fail(f"{len(items)} {title}:\n" + "\n".join(map(str, items)), pytrace=False)


def test_static_imports_respect_the_layers():
    """On the sources, every import statement — module level or inside a function —
    loads only modules of its own layer or below, and no model package another one (this
    sees imports the runtime test does not reach: those inside functions, of submodules
    that are not imported by their package). :data:`PENDING_CONTACT_REFACTOR` lists the
    imports left in files being rewritten."""
    _fail("import(s) of a higher layer or of another model package",
          layer_violations(allowed=PENDING_CONTACT_REFACTOR))


def test_the_pending_list_holds_only_real_violations():
    """Every entry of :data:`PENDING_CONTACT_REFACTOR` is still a violation (delete it when
    it is not), and it names only the files being rewritten for issue 19."""
    found = {(v.importer, v.imported) for v in [*layer_violations(), *private_violations()]}
    stale = sorted(PENDING_CONTACT_REFACTOR - found)
    assert not stale, f"no longer violations, remove them from PENDING_CONTACT_REFACTOR: {stale}"
    rewritten = {"dspace.escape", "dspace.fingers", "dspace.placement_energy",
                 "dspace.equilibrium", "pads.contact", "pads.landscape", "pads.noise",
                 "pads.homotopy"}
    assert {a for a, _ in PENDING_CONTACT_REFACTOR} <= rewritten


def test_no_import_cycles():
    """No cycle among the modules at any level: an import inside a function counts (it
    runs when the function does, and ties the two modules together all the same). Only
    ``if TYPE_CHECKING`` imports are exempt (they never run)."""
    cycles = find_cycles(full_graph())
    _fail("import cycle(s) (function-level imports included); each cycle's modules",
          ("  " + " -> ".join(_short(m) for m in c) for c in cycles))


def test_no_module_imports_another_packages_private_names():
    """``_name`` modules and names belong to their top-level subpackage (``grasp._kernels``
    is grasp's); another subpackage imports only public names."""
    _fail("import(s) of another package's private names",
          private_violations(allowed=PENDING_CONTACT_REFACTOR))


def _plant(root: Path, files: dict[str, str]) -> Path:
    src = root / "pk"
    for name, text in files.items():
        (src / name).parent.mkdir(parents=True, exist_ok=True)
        (src / name).write_text(textwrap.dedent(text))
    return src


def test_the_checks_fail_on_a_planted_cycle_and_upward_import(tmp_path):
    """A throw-away package with a cycle hidden in a function-level import (low → mid at
    module level, mid → low inside a function, through ``from . import``), an upward
    import inside a method, a model reaching another's private kernel (by import and by
    attribute) and a cycle that exists only under ``TYPE_CHECKING``: the same functions
    the tests above use find exactly the planted faults."""
    src = _plant(tmp_path, {
        "__init__.py": "",
        "low.py": "from .mid import helper\n",
        "mid.py": """\
            def helper():
                from . import low        # the hidden half of the cycle
                return low
            """,
        "base.py": """\
            class Thing:
                def report(self):
                    from .top.run import main   # upward, inside a method
                    return main
            """,
        "top/__init__.py": "",
        "top/run.py": "from ..low import helper as main\n",
        "models/__init__.py": "",
        "models/a.py": "def f():\n    from ..other._kernels import k\n",
        "models/b.py": "import pk.other.own\nx = pk.other.own._hidden\n",
        "other/__init__.py": "",
        "other/_kernels.py": "k = 1\n",
        "other/own.py": "from ._kernels import k\n",           # its own kernels: fine
        "typed.py": """\
            from typing import TYPE_CHECKING
            if TYPE_CHECKING:
                from .typed2 import T
            """,
        "typed2.py": "from .typed import TYPE_CHECKING\nT = int\n",
    })
    graph = full_graph(src, "pk")
    assert find_cycles(graph) == [["pk.low", "pk.mid", "pk.low"]]
    # import-time imports alone do not see it: the cycle is hidden in a function
    assert find_cycles(import_graph(src, "pk")[0]) == []
    table = {"low": 0, "mid": 0, "typed": 0, "typed2": 0, "base": 1, "models": 2,
             "other": 2, "top": 3}
    bad = layer_violations(src, "pk", layer=lambda m: layer_of(m, table), apart=())
    assert [(v.importer, v.imported, v.line) for v in bad] == [
        ("base", "top", 3), ("base", "top.run", 3)]
    assert "L1 imports L3" in str(bad[0]) and "base:3" in str(bad[0])
    priv = private_violations(src, "pk")
    assert [(v.importer, v.imported, v.line) for v in priv] == [
        ("models.a", "other._kernels.k", 2), ("models.b", "other.own._hidden", 2)]
    # models apart: a model package importing another at all is refused
    bad = layer_violations(src, "pk", layer=lambda m: layer_of(m, table),
                           apart=("models", "other"))
    assert ("models.a", "other._kernels") in {(v.importer, v.imported) for v in bad}
    assert layer_violations(src, "pk", layer=lambda m: layer_of(m, table), apart=(),
                            allowed={("base", "top"), ("base", "top.run")}) == []


def test_the_import_graph_counts_only_import_time_imports(tmp_path):
    """On a made-up package: module level, ``try`` and class bodies count; functions and
    ``if TYPE_CHECKING`` do not; relative imports resolve; a package's ``__init__`` is
    an edge of every import through it. The full graph adds the function-level imports."""
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
    full = full_graph(src, "pk")
    assert full["pk.b"] == {"pk.a"} and full["pk.d"] == graph["pk.d"]
    assert sorted(map(tuple, find_cycles(full))) == [("pk.a", "pk.b", "pk.a"),
                                                     ("pk.d", "pk.e", "pk.d"),
                                                     ("pk.sub", "pk.sub.c", "pk.b", "pk.a",
                                                      "pk.sub")]


def test_layer_table():
    assert layer_of("deformclosure.errors") == layer_of("deformclosure.limits") == 0
    assert layer_of("deformclosure.part") == layer_of("deformclosure.drawing") == 1
    assert layer_of("deformclosure.contact.bodies") == layer_of("deformclosure.landscape") == 3
    assert layer_of("deformclosure.pads.size_limits") == layer_of("deformclosure.dspace") == 4
    assert layer_of("deformclosure.planning._kernels") == 5
    assert layer_of("deformclosure.batch.store") == 6
    assert layer_of("deformclosure.cli.main") == 7
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
