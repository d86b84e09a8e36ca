"""The package's import graph: no cycles, and imports go one way through the layers
(docs/layout.md, "Packages"): presentation, cli -> analysis / validation / identification / envs ->
simulation, result, state, the run loop -> numerics / control -> model, names ->
parameters, io, the Numba glue; and nothing from the analysis layer up imports the compiled
core (``scoutsim._core``) itself (``test_upper_layers_do_not_import_the_core``).

The graph is read from the source (module-level and deferred imports alike, by AST), so
the test needs no import of the package. An import of the package that names no module of
it fails the test (file, line and import named) rather than being left out of the graph. The only imports against the layers are the
convenience accessors of ``CONVENIENCE_ACCESSORS`` (a method of a result that hands it to
the layer above, e.g. ``result.plot()``); they must be deferred (inside the method, so
importing the lower module never loads the upper one) and the list must match exactly, so
a new violation fails, and so does a removed one that is still listed.
"""

import ast
import pathlib

ROOT = pathlib.Path(__file__).resolve().parents[1] / "scoutsim"

# fmt: off
#: layer of each package (or root module), by prefix (longest prefix wins); higher imports
#: lower only. Every module belongs to its package's layer: a new module needs no entry.
LAYERS = {
    "scoutsim._version": 0, "scoutsim._numba": 0, "scoutsim.parameters": 0, "scoutsim.io": 0,
    # the core's table of slots and codes imports nothing: scoutsim.names reads it
    "scoutsim._core.model.layout": 0, "scoutsim.names": 0,
    "scoutsim._core.model": 1,
    "scoutsim._core.numerics": 2, "scoutsim.control": 2,
    "scoutsim._core.loop": 3, "scoutsim.state": 3, "scoutsim.simulation": 3, "scoutsim.result": 3,
    "scoutsim.analysis": 4, "scoutsim.validation": 4, "scoutsim.identification": 4,
    "scoutsim.envs": 4,
    "scoutsim.presentation": 5, "scoutsim.cli": 5,
    # the package root re-exports the public API: nothing inside imports it
    "scoutsim": 6, "scoutsim.__main__": 6,
}

#: (importer, imported) pairs against the layers: convenience accessors, deferred imports
CONVENIENCE_ACCESSORS = {
    ("scoutsim.result.simulation_result", "scoutsim.analysis.gait"),                     # result.gait()
    ("scoutsim.result.energy_accounts", "scoutsim.analysis.energy"),   # result.energy_balance()
    ("scoutsim.result.simulation_result", "scoutsim.presentation.plots"),                # result.plot()
    ("scoutsim.analysis.sweep", "scoutsim.presentation.plots"),        # sweep.plot_map()
    ("scoutsim.analysis.tune_result", "scoutsim.presentation.plots"),  # tuning.plot_convergence()
    ("scoutsim.identification.fit_result",
     "scoutsim.presentation.identification_plots"),                    # fit result .plot()
    ("scoutsim.envs.bound", "scoutsim.presentation.frames"),           # BoundEnv.render()
}
# fmt: on


def _modules():
    mods = {}
    for p in ROOT.rglob("*.py"):
        parts = p.relative_to(ROOT.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        mods[name] = p
    return mods


def _graph(module_level_only=False):
    """importer -> set of imported package modules (only the imports at module level, i.e.
    run when the importer is imported, if ``module_level_only``). An import of the package
    (relative, or absolute under ``scoutsim``) that names no module of it fails here, naming
    the file, line and import: such an import raises when it runs, and a graph that dropped
    it would hide the edge."""
    mods = _modules()
    edges = {m: set() for m in mods}
    unresolved = []
    for name, path in mods.items():
        pkg = name if path.name == "__init__.py" else name.rpartition(".")[0]
        tree = ast.parse(path.read_text())
        nodes = _module_level(tree) if module_level_only else ast.walk(tree)
        for node in nodes:
            targets, missing = _resolve(node, pkg, mods)
            edges[name].update(t for t in targets if t != name)
            unresolved += [
                f"{path.relative_to(ROOT.parent)}:{node.lineno}: "
                f"`{ast.unparse(node)}` ({m} is not a module of the package)"
                for m in sorted(set(missing))
            ]
    assert not unresolved, "imports that resolve to no module of the package:\n" + "\n".join(
        unresolved
    )
    return edges


def _resolve(node, pkg, mods):
    """(package modules the import statement ``node`` loads, the names it asks for that
    are neither a module of the package nor a name taken from one). Imports from outside
    the package give ([], [])."""
    if isinstance(node, ast.Import):
        names = [a.name for a in node.names if a.name.split(".")[0] == ROOT.name]
        return [n for n in names if n in mods], [n for n in names if n not in mods]
    if not isinstance(node, ast.ImportFrom):
        return [], []
    if node.level:
        parts = pkg.split(".")
        if node.level > len(parts):  # above the package root
            return [], ["." * node.level + (node.module or "")]
        mod = ".".join(
            parts[: len(parts) - node.level + 1] + ([node.module] if node.module else [])
        )
    else:
        mod = node.module or ""
        if mod.split(".")[0] != ROOT.name:
            return [], []
    targets, missing = [], []
    for a in node.names:
        if f"{mod}.{a.name}" in mods:  # a submodule
            targets.append(f"{mod}.{a.name}")
        elif mod in mods:  # a name defined in the module (or a star import)
            targets.append(mod)
        else:
            missing.append(mod)
    return targets, missing


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


def test_every_package_import_resolves_to_a_module():
    """Every import of the package's own modules names one that exists (``_graph`` fails
    otherwise, naming file, line and import), so no edge of the graph is dropped."""
    assert _graph()


def test_an_import_of_a_missing_module_is_reported():
    """The resolver itself: a relative import one level too shallow (the module is a
    sibling of the package, not inside it) names no module; the right one does."""
    mods = _modules()
    wrong = ast.parse("from .parameters import RobotParameters").body[0]
    right = ast.parse("from ..parameters import RobotParameters").body[0]
    absolute = ast.parse("import scoutsim.no_such_module").body[0]
    assert _resolve(wrong, "scoutsim.presentation", mods) == (
        [],
        ["scoutsim.presentation.parameters"],
    )
    assert _resolve(right, "scoutsim.presentation", mods) == (["scoutsim.parameters"], [])
    assert _resolve(absolute, "scoutsim.presentation", mods) == ([], ["scoutsim.no_such_module"])


def test_no_import_cycles():
    edges = _graph()
    state = {}

    def visit(m, stack):
        state[m] = 1
        stack.append(m)
        for t in sorted(edges[m]):
            if state.get(t) == 1:
                raise AssertionError("import cycle: " + " -> ".join(stack[stack.index(t) :] + [t]))
            if t not in state:
                visit(t, stack)
        stack.pop()
        state[m] = 2

    for m in sorted(edges):
        if m not in state:
            visit(m, [])


def test_imports_go_down_the_layers():
    edges = _graph()
    against = {
        (a, b)
        for a, ts in edges.items()
        for b in ts
        if _layer(b) > _layer(a) or (_layer(b) == _layer(a) and _peer_forbidden(a, b))
    }
    assert against == CONVENIENCE_ACCESSORS


def test_convenience_accessors_import_the_upper_layer_only_when_called():
    eager = _graph(module_level_only=True)
    assert not {(a, b) for a, b in CONVENIENCE_ACCESSORS if b in eager[a]}


#: the first layer that reads the model only through the layers below it (the result's
#: accessors, ``scoutsim.state``, ``scoutsim.names``), never ``scoutsim._core.model`` itself
MODEL_FREE_LAYER = 4
#: importer -> reason, for a module of those layers that still imports scoutsim._core.model
#: (none: the list must match exactly, so a new import fails and so does a stale entry)
MODEL_IMPORT_EXCEPTIONS = {}


def test_upper_layers_do_not_import_the_core():
    """Analysis, validation, identification, the environments, presentation and the
    command line read a run through :class:`~scoutsim.result.simulation_result.SimulationResult`'s accessors,
    build states with :mod:`scoutsim.state` and compare codes with :mod:`scoutsim.names`:
    no module of theirs imports ``scoutsim._core`` (any submodule, deferred or not), so the
    compiled core's array layout can change under them."""
    edges = _graph()
    found = {
        a
        for a, ts in edges.items()
        if _layer(a) >= MODEL_FREE_LAYER
        for b in ts
        if b == "scoutsim._core" or b.startswith("scoutsim._core.")
    }
    assert found == set(MODEL_IMPORT_EXCEPTIONS), (
        "modules above the simulation layer that import scoutsim._core: "
        + ", ".join(sorted(found - set(MODEL_IMPORT_EXCEPTIONS)))
    )


def _peer_forbidden(a, b):
    """Within one layer: numerics and control do not import each other (the run loop that
    composes them is in the layer above)."""
    top = {p.split(".")[1] if p.count(".") else p for p in (a, b)}
    return top == {"numerics", "control"}
