"""The import rules of the package: arrows point down, never back up.

1. No import circle between fohw's modules. The graph is read statically with ``ast`` from
   every ``import`` and ``from … import`` in src/fohw, at module level and inside functions
   (a function-level import is still an arrow: it only moves the circle to run time).
2. ``import fohw`` loads neither the command line (``fohw.cli``), nor the paper studies
   (``fohw.paper``), nor ``argparse``.
3. No private name (``_name``) is imported from another fohw module. Private *modules*
   (``from . import _linalg``, ``from .._validation import check_array``) are fine.
4. CONTRIBUTING.md's module map has a line for every module, and only for modules.
5. Layers: no module imports from a higher layer (:data:`LAYERS`, the order CONTRIBUTING.md
   declares), and nothing calls upward through a runtime registry (a module-level assignment
   into a mapping imported from another fohw module).

Run alone with ``python -m pytest tests/test_architecture.py``; ``python tests/test_architecture.py``
prints the graph's circles and the private imports without pytest.
"""

import ast
import json
import os
import subprocess
import sys
from pathlib import Path

import fohw

PACKAGE = Path(fohw.__file__).resolve().parent  # the fohw the tests import (src/fohw)


def _module_name(path):
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _modules():
    """``{dotted name: path}`` of every module and package of fohw."""
    return {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _imports(modules):
    """Every import of a fohw module by a fohw module.

    Yields ``(importer, target, line, names)``: ``target`` is the module the statement loads
    (``from .x import y`` targets ``x.y`` when that is a module, else ``x``), ``names`` the
    names it takes from it (empty for ``import x``). The parent packages Python loads on the
    way (``fohw``, ``fohw.model`` for ``fohw.model.gl``) are not counted: they are loaded by
    every import of a submodule and would make every package a circle.
    """
    for importer, path in modules.items():
        is_package = path.name == "__init__.py"
        package = importer if is_package else importer.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name in modules:
                        yield importer, alias.name, node.lineno, ()
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")
                    base = base[:len(base) - (node.level - 1)]
                    source = ".".join(base + ([node.module] if node.module else []))
                else:
                    source = node.module or ""
                if source != "fohw" and not source.startswith("fohw."):
                    continue
                for alias in node.names:
                    sub = f"{source}.{alias.name}"
                    if sub in modules:
                        yield importer, sub, node.lineno, ()
                    else:
                        yield importer, source, node.lineno, (alias.name,)


def import_graph():
    """``{importer: {target: first line}}`` over fohw's modules."""
    modules = _modules()
    graph = {name: {} for name in modules}
    for importer, target, line, _ in _imports(modules):
        if target != importer:
            graph[importer].setdefault(target, line)
    return graph


def _strongly_connected(graph):
    """Tarjan's strongly connected components (iterative), each a sorted list."""
    index, low, on_stack, stack, out = {}, {}, set(), [], []
    counter = 0
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            for child in children:
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                    break
                if child in on_stack:
                    low[node] = min(low[node], index[child])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    component = []
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        component.append(member)
                        if member == node:
                            break
                    out.append(sorted(component))
    return out


def _shortest_cycle(graph, component):
    """One shortest circle through the first module of ``component``, as a list of modules."""
    start, members = component[0], set(component)
    previous, frontier = {start: None}, [start]
    while frontier:
        following = []
        for node in frontier:
            for child in sorted(graph[node]):
                if child == start:
                    path = [node]
                    while previous[path[-1]] is not None:
                        path.append(previous[path[-1]])
                    return path[::-1] + [start]
                if child in members and child not in previous:
                    previous[child] = node
                    following.append(child)
        frontier = following
    raise AssertionError(f"no circle through {start}")  # pragma: no cover


def import_cycles():
    """Each circle of the graph as ``"a (line) -> b (line) -> a"``, one per strongly connected set."""
    graph = import_graph()
    found = []
    for component in _strongly_connected(graph):
        if len(component) < 2:
            continue
        cycle = _shortest_cycle(graph, component)
        steps = [f"{a} (line {graph[a][b]})" for a, b in zip(cycle, cycle[1:])]
        extra = sorted(set(component) - set(cycle))
        found.append(" -> ".join(steps + [cycle[-1]])
                     + (f"  [same knot: {', '.join(extra)}]" if extra else ""))
    return found


def private_imports():
    """``"importer:line: from target import _name"`` for every private name crossing modules."""
    found = []
    for importer, target, line, names in _imports(_modules()):
        for name in names:
            if name.startswith("_") and not (name.startswith("__") and name.endswith("__")):
                found.append(f"{importer}:{line}: from {target} import {name}")
    return found


def test_no_import_cycles():
    cycles = import_cycles()
    assert not cycles, "import circles in fohw (module (line of the import) -> ...):\n" + "\n".join(cycles)


def test_graph_reads_relative_and_function_level_imports():
    # The reader itself: a package's relative import, a function-level import and a module import.
    graph = import_graph()
    assert "fohw.model.basis" in graph["fohw"]                 # from .model.basis import Basis
    assert "fohw.paper.table2" in graph["fohw.cli"]           # inside a function of the CLI
    assert "fohw.exceptions" in graph["fohw.cli"]              # from . import exceptions
    assert "fohw.paper" not in graph["fohw"]


_PROBE = """
import builtins, json, sys

stdlib = set(sys.stdlib_module_names) | {"_frozen_importlib", "_frozen_importlib_external"}
culprits = set()
real_import = builtins.__import__

def spy(name, globals=None, locals=None, fromlist=(), level=0):
    if name == "argparse" or name.startswith("argparse."):
        # The innermost module on the stack that is not the standard library decides who asked.
        frame = sys._getframe(1)
        while frame is not None:
            module = frame.f_globals.get("__name__", "?")
            if module.split(".")[0] not in stdlib:
                culprits.add(module)
                break
            frame = frame.f_back
    return real_import(name, globals, locals, fromlist, level)

builtins.__import__ = spy
import fohw
builtins.__import__ = real_import
print(json.dumps({
    "file": fohw.__file__,
    "argparse_by_fohw": sorted(m for m in culprits if m == "fohw" or m.startswith("fohw.")),
    "argparse_by": sorted(culprits),
    "applications": sorted(m for m in sys.modules if m == "fohw.cli" or m == "fohw.paper"
                           or m.startswith("fohw.paper.")),
}))
"""


def test_import_fohw_loads_no_application():
    # scipy itself loads argparse (scipy.linalg -> numpy.testing -> unittest -> argparse), so
    # "argparse in sys.modules" says nothing about fohw: the probe records, for every
    # `import argparse` statement run during `import fohw`, the innermost non-standard-library
    # module on the stack, and fohw must never be it.
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(PACKAGE.parent)] + [p for p in [os.environ.get("PYTHONPATH")] if p]))
    proc = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True, env=env,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr
    seen = json.loads(proc.stdout)
    assert Path(seen["file"]).resolve().parent == PACKAGE
    assert not seen["applications"], f"`import fohw` loads {seen['applications']}"
    assert not seen["argparse_by_fohw"], (f"`import fohw` imports argparse from "
                                          f"{seen['argparse_by_fohw']}")


def test_module_map_names_every_module():
    # CONTRIBUTING.md's module map: one line per module, the module in the first column. The
    # subpackages' __init__ files (re-exports only) need no line; fohw's own does.
    text = (Path(__file__).resolve().parents[1] / "CONTRIBUTING.md").read_text(encoding="utf-8")
    listed = {line.split("`")[1] for line in text.splitlines() if line.startswith("| `fohw")}
    modules = _modules()
    needed = {m for m, p in modules.items() if p.name != "__init__.py"} | {"fohw"}
    assert not sorted(needed - listed), f"not in CONTRIBUTING.md's module map: {sorted(needed - listed)}"
    assert not sorted(listed - set(modules)), f"not modules of fohw: {sorted(listed - set(modules))}"


#: The layers, lowest first; a module may import from its own layer and the ones below. The
#: foundation (private helpers, exceptions, the frequency plots every kind draws with) is
#: below everything; the model kinds; the results they make; the estimators; files and
#: data sets; the analyses (which fit, compare, test and select); the application.
LAYERS = (
    ("foundation", lambda top: top.startswith("_") or top in ("exceptions", "frequency_plots")),
    ("model", lambda top: top == "model"),
    ("results", lambda top: top in ("results", "fit_result", "result_checks", "presentation",
                                    "record", "lr_statistic")),
    ("estimators", lambda top: top == "estimators"),
    ("io", lambda top: top in ("io", "datasets")),
    ("analysis", lambda top: top == "analysis"),
    ("application", lambda top: top in ("cli", "paper", "__main__", "testing")),
)


def layer(module):
    """Index in :data:`LAYERS` of a fohw module (``fohw`` itself: above them all)."""
    if module == "fohw":
        return len(LAYERS)
    top = module.split(".")[1]
    for i, (_, member) in enumerate(LAYERS):
        if member(top):
            return i
    raise AssertionError(f"{module} is in no layer of LAYERS; add it")


def upward_imports():
    """``"importer (layer) line -> target (layer)"`` for every import of a higher layer."""
    names = [n for n, _ in LAYERS] + ["fohw"]
    found = []
    for importer, targets in sorted(import_graph().items()):
        for target, line in targets.items():
            if target == "fohw" and importer.split(".")[1] in ("cli", "paper"):
                continue                                  # the application uses the public API
            if importer == "fohw.__main__" and target == "fohw.cli":
                continue                                  # `python -m fohw` starts the CLI
            if layer(target) > layer(importer):
                found.append(f"{importer} ({names[layer(importer)]}) line {line} -> {target} "
                             f"({names[layer(target)]})")
    return found


def runtime_registries():
    """``"module:line"`` of module-level ``name[...] = ...`` into a name imported from fohw."""
    found = []
    for module, path in _modules().items():
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        imported = {alias.asname or alias.name for node in tree.body
                    if isinstance(node, ast.ImportFrom) and (node.level or (node.module or "")
                                                             .startswith("fohw"))
                    for alias in node.names}
        for node in tree.body:
            targets = node.targets if isinstance(node, ast.Assign) else []
            for t in targets:
                if isinstance(t, ast.Subscript) and isinstance(t.value, ast.Name) \
                        and t.value.id in imported:
                    found.append(f"{module}:{node.lineno}: {t.value.id}[...] = ...")
    return found


def test_every_module_is_in_a_layer_and_no_import_climbs():
    found = upward_imports()
    assert not found, "imports of a higher layer:\n" + "\n".join(found)


def test_nothing_calls_upward_through_a_runtime_registry():
    found = runtime_registries()
    assert not found, "module-level writes into another module's registry:\n" + "\n".join(found)


def test_the_layer_check_sees_a_climb():
    # The checker itself: a model module importing an analysis would be caught.
    assert layer("fohw.model.gl") < layer("fohw.analysis.crb")
    assert layer("fohw._validation") == 0 and layer("fohw.cli") == len(LAYERS) - 1


def test_no_private_names_cross_modules():
    found = private_imports()
    assert not found, "private names imported from another fohw module:\n" + "\n".join(found)


if __name__ == "__main__":
    print("import circles:", *import_cycles() or ["none"], sep="\n  ")
    print("private names imported across modules:", *private_imports() or ["none"], sep="\n  ")
    print("imports of a higher layer:", *upward_imports() or ["none"], sep="\n  ")
    print("runtime registries:", *runtime_registries() or ["none"], sep="\n  ")
