"""The package's shape: no module over 600 lines, no function over 12 parameters (kernel
arguments travel in named bundles, public entry points take bundles and their fields as
keywords), and the integrators and the run loop free of the model variants (they reach
the hip unit through scoutsim._core.model.hip_unit). Read from the source, no import."""

import ast
import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parents[1] / "scoutsim"
CORE = ROOT / "_core"
MAX_LINES = 600
MAX_PARAMETERS = 12
#: functions allowed more than MAX_PARAMETERS parameters ("path relative to the package:name"),
#: and why; matched exactly, so an entry that no longer names a wide function fails too
WIDE_BY_DESIGN = {
    "simulation/simulator.py:simulate": "the public entry point spells out every keyword "
    "for IDEs, inspect.signature and type checkers",
}


def _sources():
    return sorted(p for p in ROOT.rglob("*.py") if "__pycache__" not in p.parts)


def test_no_module_over_600_lines():
    long = {
        str(p.relative_to(ROOT)): n
        for p in _sources()
        if (n := len(p.read_text().splitlines())) > MAX_LINES
    }
    assert not long, long


def test_no_function_over_12_parameters():
    """No function takes more than 12 parameters but those of :data:`WIDE_BY_DESIGN`, and
    each of those does."""
    wide, excepted = [], set()
    for p in _sources():
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                a = node.args
                n = (
                    len(a.posonlyargs)
                    + len(a.args)
                    + len(a.kwonlyargs)
                    + (a.vararg is not None)
                    + (a.kwarg is not None)
                )
                if a.args and a.args[0].arg in ("self", "cls"):
                    n -= 1
                if n > MAX_PARAMETERS:
                    key = f"{p.relative_to(ROOT).as_posix()}:{node.name}"
                    if key in WIDE_BY_DESIGN:
                        excepted.add(key)
                    else:
                        wide.append(f"{p.relative_to(ROOT)}:{node.lineno} {node.name} ({n})")
    assert not wide, wide
    stale = set(WIDE_BY_DESIGN) - excepted
    assert not stale, f"listed as wide by design but not wide (or gone): {sorted(stale)}"


def test_integrators_and_run_loop_know_no_model_variant():
    found = [
        f"{p.relative_to(ROOT)}:{i}"
        for p in [*sorted((CORE / "numerics").glob("*.py")), CORE / "loop.py"]
        for i, line in enumerate(p.read_text().splitlines(), 1)
        if re.search(r"\bMODEL_(II|I|IDEAL|PASSIVE)\b|\bP_MODEL\b", line)
    ]
    assert not found, found


def test_hip_units_are_reached_only_through_their_registry():
    """Every hip-unit module (a module of scoutsim/model that declares ``GEARED``) is
    imported by model/hip_unit.py alone: the rest of the package reaches a unit through the
    registry's hooks, so adding a unit is its module and its entry in the registry."""
    model = CORE / "model"
    units = sorted(
        p.stem for p in model.glob("*.py") if re.search(r"^GEARED\s*=", p.read_text(), re.M)
    )
    assert {"rigid_hip", "belt", "backlash"} <= set(units), units
    registry = (model / "hip_unit.py").read_text()
    for unit in units:
        assert re.search(rf"^from \. import .*\b{unit}\b", registry, re.M), unit
    pattern = re.compile(
        rf"^\s*(from\s+\S*\b({'|'.join(units)})\b\s+import|from\s+\.+\S*\s+"
        rf"import\s+.*\b({'|'.join(units)})\b|import\s+\S*\.({'|'.join(units)})\b)",
        re.M,
    )
    found = [
        str(p.relative_to(ROOT))
        for p in _sources()
        if p != model / "hip_unit.py" and pattern.search(p.read_text())
    ]
    assert not found, found


#: forms of the compiled core's arrays read by number where layout.py has a name:
#: (what, pattern, files relative to the package)
MAGIC_FORMS = (
    (
        "a leg or gear angle indexed by number (layout IPHB / IALB + leg)",
        re.compile(r"(?<![\w.])[35]\s*\+\s*leg\b"),
        ("**/*.py",),
    ),
    (
        "a huge number standing for an infinite friction coefficient (P_NO_SLIP)",
        re.compile(r"\b1e30[0-9]\b"),
        ("**/*.py",),
    ),
    (
        "a flag slot compared with one half by hand (model/flags.py is_set)",
        re.compile(r"\b(P|meta|hwork|aux|C|geom)\[(-1,\s*)?(L\.)?[A-Z_]+\]\s*[<>]=?\s*0\.5\b"),
        ("**/*.py",),
    ),
    (
        "a controller transition bit by its value (layout TR_*)",
        re.compile(r"(&|\|=)\s*[124]\b"),
        ("_core/loop.py", "control/bounding.py"),
    ),
    (
        "contact-event slot arithmetic by hand (numerics/events.py contact_event, event_leg, "
        "event_slot)",
        re.compile(r"(//|%)\s*NEV_CONTACT\b|NEV_CONTACT\s*\+\s*[0-9]"),
        (
            "_core/loop.py",
            "_core/numerics/hybrid.py",
            "_core/numerics/event_location.py",
            "_core/numerics/transitions.py",
        ),
    ),
    (
        "an impact output by number (layout IMP_*)",
        re.compile(r"\b(imp|out)\[\s*([0-9]|3\s*\*)"),
        ("_core/model/impact.py", "_core/numerics/transitions.py"),
    ),
)


def test_core_arrays_are_read_by_their_names():
    """The slots of the compiled core's arrays are read through the names of
    scoutsim/_core/model/layout.py and the helpers beside it, not by number (comments aside)."""
    found = []
    for what, pattern, globs in MAGIC_FORMS:
        files = sorted({p for g in globs for p in ROOT.glob(g) if "__pycache__" not in p.parts})
        assert files, globs
        for p in files:
            for i, line in enumerate(p.read_text().splitlines(), 1):
                if pattern.search(line.split("#", 1)[0]):
                    found.append(f"{p.relative_to(ROOT)}:{i}: {what}: {line.strip()}")
    assert not found, "\n".join(found)


#: at most this many modules at the package root besides ``__init__``, ``__main__`` and
#: ``_version``: the rest of the package lives in sub-packages named for what they hold
MAX_ROOT_MODULES = 8
#: packages whose modules may share a base name with a module elsewhere, and why
SHARED_BASE_NAMES = {
    "cli": "each module of the command line is named after its command (scoutsim basin, "
    "sweep, tune), which runs the study of the same name in scoutsim.analysis",
    "_core/model/derivative": "each module of the right-hand side's derivative is named "
    "after the module of scoutsim._core.model whose functions it differentiates",
}


def test_the_package_root_holds_few_modules():
    root = sorted(
        p.stem for p in ROOT.glob("*.py") if p.stem not in ("__init__", "__main__", "_version")
    )
    assert len(root) <= MAX_ROOT_MODULES, root


def test_no_two_modules_share_a_base_name():
    """A module's base name says what it holds, once: ``sensors.py`` in two packages would
    make a reader (and a traceback) ask which. The command line's modules are the reasoned
    exception (:data:`SHARED_BASE_NAMES`)."""
    where = {}
    for p in _sources():
        rel = p.relative_to(ROOT)
        folder = rel.parent.as_posix()
        if p.stem == "__init__" or (
            (rel.parts[0] in SHARED_BASE_NAMES and len(rel.parts) > 1)
            or folder in SHARED_BASE_NAMES
        ):
            continue
        where.setdefault(p.stem, []).append(str(rel))
    shared = {k: v for k, v in where.items() if len(v) > 1}
    assert not shared, shared


def test_tests_mirror_the_package():
    """Every directory of tests/ is named after the package it tests (tests/_core/model for
    scoutsim/_core/model, ...), so a module's tests are found where the module is."""
    tests = ROOT.parent / "tests"
    dirs = sorted(
        p.relative_to(tests)
        for p in tests.rglob("*")
        if p.is_dir() and "__pycache__" not in p.parts and not p.name.startswith(".")
    )
    assert dirs
    stray = [str(d) for d in dirs if not (ROOT / d).is_dir()]
    assert not stray, stray


def test_no_module_imports_another_modules_private_names():
    """What a module shares with the rest of the package has a public name: an import of a
    ``_name`` from another module of the package (a helper used across files under a name
    that says "only here") fails, naming the file, the line and the name."""
    found = []
    for p in _sources():
        pkg = ".".join(p.relative_to(ROOT.parent).with_suffix("").parts[:-1])
        for node in ast.walk(ast.parse(p.read_text())):
            if not isinstance(node, ast.ImportFrom):
                continue
            inside = node.level > 0 or (node.module or "").split(".")[0] == ROOT.name
            if not inside or node.module == "__future__":
                continue
            found += [
                f"{p.relative_to(ROOT)}:{node.lineno} {a.name} (from {'.' * node.level}"
                f"{node.module or ''}; in {pkg})"
                for a in node.names
                if a.name.startswith("_") and not a.name.startswith("__")
            ]
    assert not found, found


def test_the_layout_page_names_every_module():
    """docs/layout.md says what every module of the package holds: a module added, moved or
    renamed without its row there fails (a row may name a whole directory, as `cli/`)."""
    page = (ROOT.parent / "docs" / "layout.md").read_text()
    missing = []
    for p in _sources():
        rel = p.relative_to(ROOT).as_posix()
        if p.name in ("__init__.py", "__main__.py", "_version.py"):
            continue
        folder = rel.rpartition("/")[0]
        if f"`{rel}`" not in page and not (folder and f"`{folder}/`" in page):
            missing.append(rel)
    assert not missing, missing
