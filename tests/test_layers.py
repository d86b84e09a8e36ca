"""The package's import graph: no cycles, and imports go one way through the layers
(README "Layout"): presentation -> analysis / validation / identification -> simulation ->
numerics / control -> model -> parameters.

The graph is read from the source (module-level and deferred imports alike, by AST), so
the test needs no import of the package. The only imports against the layers are the
convenience accessors of ``CONVENIENCE_ACCESSORS`` (a method of a result that hands it to
the layer above, e.g. ``result.plot()``); they must be deferred (inside the method, so
importing the lower module never loads the upper one) and the list must match exactly, so
a new violation fails, and so does a removed one that is still listed.
"""

import ast
import pathlib

ROOT = pathlib.Path(__file__).resolve().parents[1] / "scoutsim"

#: layer of each module, by prefix (longest prefix wins); higher imports lower only
LAYERS = {
    "scoutsim._version": 0, "scoutsim.jit": 0, "scoutsim.parameters": 0, "scoutsim.tables": 0, "scoutsim.run_directory": 0,
    "scoutsim.model": 1,
    "scoutsim.numerics": 2, "scoutsim.control": 2,
    "scoutsim.state": 3, "scoutsim.loop": 3, "scoutsim.simulation": 3, "scoutsim.result": 3,
    "scoutsim.failure": 3, "scoutsim.streaming": 3,
    "scoutsim.analysis": 4, "scoutsim.validation": 4, "scoutsim.identification": 4,
    "scoutsim.presentation": 5, "scoutsim.cli": 5,
    # the package root re-exports the public API: nothing inside imports it
    "scoutsim": 6, "scoutsim.__main__": 6,
}

#: (importer, imported) pairs against the layers: convenience accessors, deferred imports
CONVENIENCE_ACCESSORS = {
    ("scoutsim.result", "scoutsim.analysis.gait"),                     # result.gait()
    ("scoutsim.result", "scoutsim.presentation.plots"),                # result.plot()
    ("scoutsim.analysis.sweep", "scoutsim.presentation.plots"),        # sweep.plot_map()
    ("scoutsim.identification.fit",
     "scoutsim.presentation.identification_plots"),                    # fit result .plot()
}


def _modules():
    mods = {}
    for p in ROOT.rglob("*.py"):
        parts = p.relative_to(ROOT.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        mods[name] = p
    return mods


def _graph(module_level_only=False):
    """importer -> set of imported package modules (only the imports at module level, i.e.
    run when the importer is imported, if ``module_level_only``)."""
    mods = _modules()
    edges = {m: set() for m in mods}
    for name, path in mods.items():
        pkg = name if path.name == "__init__.py" else name.rpartition(".")[0]
        tree = ast.parse(path.read_text())
        nodes = _module_level(tree) if module_level_only else ast.walk(tree)
        for node in nodes:
            targets = []
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = pkg.split(".")[:len(pkg.split(".")) - node.level + 1]
                    mod = ".".join(base + ([node.module] if node.module else []))
                else:
                    mod = node.module or ""
                targets = [f"{mod}.{a.name}" for a in node.names if f"{mod}.{a.name}" in mods]
                if not targets and mod in mods:
                    targets = [mod]
            elif isinstance(node, ast.Import):
                targets = [a.name for a in node.names if a.name in mods]
            edges[name].update(t for t in targets if t != name)
    return edges


def _module_level(tree):
    """Nodes executed on import: everything outside function bodies."""
    stack = list(tree.body)
    while stack:
        node = stack.pop()
        yield node
        if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            stack.extend(ast.iter_child_nodes(node))


def _layer(module):
    best = max((p for p in LAYERS if module == p or module.startswith(p + ".")), key=len)
    return LAYERS[best]


def test_every_module_has_a_layer():
    for m in _modules():
        assert any(m == p or m.startswith(p + ".") for p in LAYERS), m


def test_no_import_cycles():
    edges = _graph()
    state = {}

    def visit(m, stack):
        state[m] = 1
        stack.append(m)
        for t in sorted(edges[m]):
            if state.get(t) == 1:
                raise AssertionError("import cycle: " + " -> ".join(stack[stack.index(t):] + [t]))
            if t not in state:
                visit(t, stack)
        stack.pop()
        state[m] = 2

    for m in sorted(edges):
        if m not in state:
            visit(m, [])


def test_imports_go_down_the_layers():
    edges = _graph()
    against = {(a, b) for a, ts in edges.items() for b in ts
               if _layer(b) > _layer(a) or (_layer(b) == _layer(a) and _peer_forbidden(a, b))}
    assert against == CONVENIENCE_ACCESSORS


def test_convenience_accessors_import_the_upper_layer_only_when_called():
    eager = _graph(module_level_only=True)
    assert not {(a, b) for a, b in CONVENIENCE_ACCESSORS if b in eager[a]}


def _peer_forbidden(a, b):
    """Within one layer: numerics and control do not import each other (the run loop that
    composes them is in the layer above)."""
    top = {p.split(".")[1] if p.count(".") else p for p in (a, b)}
    return top == {"numerics", "control"}
