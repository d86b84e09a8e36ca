"""The compiled core's declarations (scoutsim/_numba/jit.py) and its on-disk cache
(scoutsim/_numba/disk_cache.py): every compiled function says whether it runs with
reference counting, and the non-allocating kernels really run without it; each module is
cached under a digest of what it depends on, and only stale directories of ours are
removed."""

import numpy as np
import pytest
from numba import njit
from numba.core.caching import NullCache
from numba.core.errors import TypingError
from numba.core.registry import CPUDispatcher

from scoutsim._core import loop
from scoutsim._core.model import (
    actuator,
    contact,
    evaluate,
    impact,
    kinematics,
    kkt,
    leg,
    rigid_body,
    transmission,
    workspace,
)
from scoutsim._core.numerics import (
    ark,
    dopri5,
    event_location,
    events,
    hybrid,
    step_energy,
    stepper,
    transitions,
)
from scoutsim._numba import disk_cache, jit
from scoutsim.control import bounding

MODULES = (
    kinematics,
    rigid_body,
    leg,
    actuator,
    transmission,
    contact,
    kkt,
    workspace,
    impact,
    evaluate,
    ark,
    dopri5,
    events,
    transitions,
    stepper,
    event_location,
    step_energy,
    hybrid,
    loop,
    bounding,
)


def dispatchers(module):
    return {
        name: obj
        for name, obj in vars(module).items()
        if isinstance(obj, CPUDispatcher) and obj.py_func.__module__ == module.__name__
    }


@pytest.mark.parametrize("module", MODULES, ids=lambda m: m.__name__)
def test_every_compiled_function_declares_its_reference_counting(module):
    found = dispatchers(module)
    assert found, f"no compiled functions found in {module.__name__}"
    for name, d in found.items():
        opts = d.targetoptions
        assert "_nrt" in opts, f"{module.__name__}.{name}: not declared by jit.kernel/allocating"
        assert opts.get("error_model") == "numpy", name
        assert not isinstance(d._cache, NullCache), f"{name} is not cached on disk"


def test_the_hot_loop_runs_without_reference_counting():
    for f in (
        evaluate.evaluate_ws,
        evaluate.evaluate_command_change,
        kinematics.project_state,
        ark.step3,
        hybrid.advance,
        loop.run_periods,
        transitions.settle_ws,
        events.event_values,
        bounding.bounding_step,
    ):
        assert f.targetoptions["_nrt"] is False, f.py_func.__name__
    # the functions that allocate keep it
    for f in (loop.run, transitions.touchdown, impact.impact, evaluate.evaluate):
        assert f.targetoptions["_nrt"] is True, f.py_func.__name__


def test_a_kernel_cannot_allocate():
    # the property the kernels rely on is enforced by Numba, not by convention
    def make(n):
        return np.zeros(n)

    with pytest.raises(TypingError):
        njit(_nrt=False)(make)(3)
    np.testing.assert_array_equal(njit(_nrt=True)(make)(3), np.zeros(3))


def test_kernel_and_allocating_set_the_options():
    def f(x):
        return x + 1.0

    k = jit.kernel(f)
    a = jit.allocating(inline="always")(f)
    assert k.targetoptions["_nrt"] is False and k.targetoptions["inline"] == "never"
    assert a.targetoptions["_nrt"] is True and a.targetoptions["inline"] == "always"
    assert k.py_func is f and a.py_func is f


@pytest.mark.skipif(
    not jit.TYPED_BY_KIND,
    reason="SCOUTSIM_NUMBA_SPECIALIZE_CONSTANTS turns the per-kind typing off",
)
def test_a_callee_is_compiled_once_whatever_constants_its_callers_pass():
    """Constants passed from compiled code (True / False, leg index 0 / 1) do not give the
    callee one specialization each: the right-hand side used to be compiled five times."""

    def callee(x, flag, leg):
        return x + (1.0 if flag else 0.0) + leg

    c = jit.kernel(callee)
    k = njit(lambda x: c(x, True, 0) + c(x, False, 1) + c(x, x > 0.0, 1))
    assert k(1.0) == 2.0 + 2.0 + 3.0
    assert len(c.signatures) == 1
    assert "Literal" not in str(c.signatures[0])
    # the mechanism: an undecorated Numba function does specialize on each constant
    plain = njit(callee)
    njit(lambda x: plain(x, True, 0) + plain(x, False, 1))(1.0)
    assert len(plain.signatures) == 2


def test_each_module_is_cached_under_a_digest_of_what_it_imports(tmp_path):
    """An edit of a compiled-core module (not only of a function's own file, which is all
    Numba checks) gives new cache directories to that module and to every module that
    imports it, directly or through others; the other modules keep theirs, and modules
    outside the core change nothing."""
    import pathlib
    import shutil

    pkg = disk_cache.PACKAGE
    copy = tmp_path / "scoutsim"
    shutil.copytree(pkg, copy, ignore=shutil.ignore_patterns("__pycache__"))
    d0 = disk_cache.module_digests(copy)
    assert d0 == disk_cache.module_digests(pkg)
    assert set(d0) >= {
        "_core/loop.py",
        "_numba/jit.py",
        "_core/model/evaluate.py",
        "_core/numerics/hybrid.py",
    }

    def edit(rel):
        with open(copy / rel, "a") as f:
            f.write("\n# an edit\n")
        return disk_cache.module_digests(copy)

    d1 = edit("analysis/gait.py")  # not part of the compiled core
    assert d1 == d0
    d2 = edit("_core/loop.py")  # nothing imports the run loop
    assert {rel for rel in d0 if d2[rel] != d0[rel]} == {"_core/loop.py"}
    d3 = edit("_core/model/leg.py")  # inlined into the right-hand side, in another file
    changed = {rel for rel in d0 if d3[rel] != d2[rel]}
    assert {
        "_core/model/leg.py",
        "_core/model/contact.py",
        "_core/model/evaluate.py",
        "_core/numerics/ark.py",
        "_core/numerics/hybrid.py",
        "_core/loop.py",
    } <= changed
    assert not changed & {
        "_core/model/layout.py",
        "_core/model/kkt.py",
        "control/bounding.py",
        "_numba/jit.py",
    }
    d4 = edit("_numba/jit.py")  # the compilation options: every compiled module
    assert all(
        d4[rel] != d3[rel]
        for rel in (
            "_core/loop.py",
            "_core/model/evaluate.py",
            "_core/model/leg.py",
            "_core/numerics/ark.py",
            "control/bounding.py",
        )
    )
    assert d4["_core/model/layout.py"] == d3["_core/model/layout.py"]  # constants only
    # a module's directory is named by the module and its digest, under the cache's root
    here = disk_cache.module_digests()
    for rel, path in disk_cache._MODULE_DIRS.items():
        rel = pathlib.Path(rel).relative_to(pkg).as_posix()
        assert path == disk_cache.module_cache_dir(disk_cache.cache_directory(), rel, here[rel])
    assert (
        disk_cache._MODULE_DIRS[str(pkg / "_core" / "loop.py")].name
        == f"_core.loop-{here['_core/loop.py']}"
    )
    assert (
        disk_cache._MODULE_DIRS[str(pkg / "_core" / "model" / "evaluate.py")].name
        == f"_core.model.evaluate-{here['_core/model/evaluate.py']}"
    )


def test_a_function_is_cached_in_its_modules_directory():
    """Numba's cache of a core function is its module's directory (the locator jit.py
    installs), whatever Numba's own cache directory setting."""
    from numba.core.caching import FunctionCache

    cache = FunctionCache(evaluate.evaluate_ws.py_func)
    directory = disk_cache._MODULE_DIRS[str(pathlib_path(evaluate.__file__))]
    assert cache.cache_path == str(directory)
    assert (
        cache._impl.locator.get_source_stamp()
        == disk_cache._MODULE_DIRS[str(pathlib_path(evaluate.__file__))].name.rsplit("-", 1)[1]
    )


def pathlib_path(f):
    import pathlib

    return pathlib.Path(f).resolve()


#: run in a new process with NUMBA_CACHE_DIR set: import the package's jit module only (no
#: compilation), report where Numba will cache, the digest of the core's sources and which
#: of the paths given exist after the import; then clean the cache and report what it removed
_REPORT_CACHE_DIR = """
import json, os, sys, numba, scoutsim._numba.jit
from scoutsim._numba import disk_cache
report = {"numba_cache_dir": numba.config.CACHE_DIR, "root": str(disk_cache.cache_directory()),
          "loop": str(disk_cache._MODULE_DIRS[str(disk_cache.PACKAGE / "_core/loop.py")]),
          "digests": disk_cache.module_digests(),
          "after_import": [p for p in sys.argv[1:] if os.path.exists(p)]}
report["removed"] = [str(p) for p in disk_cache.clean_cache()]
print(json.dumps(report))
"""


def test_a_user_numba_cache_dir_holds_the_module_directories_too(tmp_path):
    """With NUMBA_CACHE_DIR set, the compiled core is cached in a directory of it
    (scoutsim-numba), one subdirectory per module named by its digest (an edit of an
    inlined callee in another file must not be served from a stale caller). Importing the
    package removes nothing; cleaning the cache (disk_cache.clean_cache, run when the core
    first compiles in a process, and by `scoutsim cache --clean`) removes only this package's
    directories of other digests (and the whole-core directories of older versions) that
    nothing wrote to for a day, and says which: a recent one of ours and everything not
    ours stay. Numba's own setting is left as the user set it."""
    import json
    import os
    import subprocess
    import sys
    import time

    user = tmp_path / "user-cache"
    root = disk_cache.user_cache_dir(user)
    assert root == user / disk_cache.USER_CACHE_NAME
    old_whole_stale = user / f"{disk_cache.USER_CACHE_PREFIX}{'0' * 16}"
    old_whole_recent = user / f"{disk_cache.USER_CACHE_PREFIX}{'1' * 16}"
    ours_stale = root / f"_core.loop-{'0' * 16}"
    ours_recent = root / f"_core.model.evaluate-{'1' * 16}"
    not_ours = [
        user / "numba-0000000000000000",
        user / "scoutsim-numba-notadigest",
        user / "another_program_abc123",
        root / f"notacoremodule-{'0' * 16}",
        root / "_core.loop-notadigest",
    ]
    every = (old_whole_stale, old_whole_recent, ours_stale, ours_recent, *not_ours)
    for d in every:
        (d / "sub").mkdir(parents=True)
        (d / "sub" / "f.nbi").write_bytes(b"x")
    (user / "a-file.txt").write_text("the user's\n")
    old = time.time() - 2 * disk_cache.STALE_USER_CACHE_S
    for d in (old_whole_stale, ours_stale, *not_ours):
        for path in (d / "sub" / "f.nbi", d / "sub", d):
            os.utime(path, (old, old))
    env = dict(
        os.environ,
        NUMBA_CACHE_DIR=str(user),
        PYTHONPATH=os.pathsep.join(
            [str(disk_cache.PACKAGE.parent), os.environ.get("PYTHONPATH", "")]
        ),
    )
    out = subprocess.run(
        [sys.executable, "-c", _REPORT_CACHE_DIR, *map(str, every)],
        env=env,
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    )
    report = json.loads(out.stdout.strip().splitlines()[-1])
    assert report["digests"] == disk_cache.module_digests()
    assert pathlib_path(report["numba_cache_dir"]) == user.resolve()
    assert pathlib_path(report["root"]) == root.resolve()
    loop_dir = pathlib_path(report["loop"])
    assert (
        loop_dir
        == disk_cache.module_cache_dir(
            root, "_core/loop.py", report["digests"]["_core/loop.py"]
        ).resolve()
    )
    assert loop_dir.parent == root.resolve()
    assert report["after_import"] == [str(d) for d in every]  # nothing removed at import
    assert sorted(report["removed"]) == sorted([str(ours_stale), str(old_whole_stale)])
    assert not ours_stale.exists() and not old_whole_stale.exists()
    assert (ours_recent / "sub" / "f.nbi").exists()
    assert (old_whole_recent / "sub" / "f.nbi").exists()
    assert all((d / "sub" / "f.nbi").exists() for d in not_ours)
    assert (user / "a-file.txt").read_text() == "the user's\n"


def test_compile_progress_says_what_was_compiled():
    """While the core compiles, the command line says so (one line at the end when the
    stream is not a terminal); nothing when nothing of the core compiled."""
    import io

    def g(x):
        return x * 3.0

    g.__module__ = "scoutsim._progress_probe"
    stream = io.StringIO()
    with jit.compile_progress(stream):
        assert njit(g)(2.0) == 6.0
    assert "compiled 1 function of the core in" in stream.getvalue()
    quiet = io.StringIO()
    with jit.compile_progress(quiet):
        njit(lambda x: x + 1.0)(1.0)  # not the core's
    assert quiet.getvalue() == ""


_SPECIALIZED = """
import json
from numba import njit
from scoutsim._numba import jit

def callee(x, flag, leg):
    return x + (1.0 if flag else 0.0) + leg

c = jit._typed_by_kind(njit(callee))
k = njit(lambda x: c(x, True, 0) + c(x, False, 1))
print(json.dumps({"value": k(1.0), "signatures": len(c.signatures),
                  "status": jit.status()["typed_by_kind"]}))
"""


def test_the_per_kind_typing_has_a_switch(tmp_path):
    """SCOUTSIM_NUMBA_SPECIALIZE_CONSTANTS=1 leaves calls to the core's functions as Numba
    types them (one specialization per constant), and the status says it is off; the
    values are the same."""
    import json
    import os
    import subprocess
    import sys

    env = dict(os.environ, SCOUTSIM_NUMBA_SPECIALIZE_CONSTANTS="1")
    p = subprocess.run(
        [sys.executable, "-c", _SPECIALIZED],
        env=env,
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert p.returncode == 0, p.stderr[-2000:]
    out = json.loads(p.stdout.strip().splitlines()[-1])
    assert out["value"] == (1.0 + 1.0 + 0) + (1.0 + 0.0 + 1)
    assert out["signatures"] == 2
    assert out["status"] == "off: SCOUTSIM_NUMBA_SPECIALIZE_CONSTANTS is set"


def test_the_cleaner_removes_directories_of_other_digests_and_of_modules_gone(tmp_path):
    """In the package's own cache, a module directory at another digest, or of a module the
    core no longer has (an older layout: ``numerics.hybrid-<digest>``), is removed; the
    current directories and anything that is not a module directory stay. In a user's
    shared directory only our modules' other digests go, once nothing has written to them
    for a while (a module this version lacks may be another version's, running now)."""
    import os
    import time

    digests = {"_core/loop.py": "0" * 16, "_core/numerics/hybrid.py": "1" * 16}

    def make(base):
        keep = [
            base / f"_core.loop-{'0' * 16}",
            base / f"_core.numerics.hybrid-{'1' * 16}",
            base / "imports.json",
            base / "not-a-module-dir",
        ]
        other = base / f"_core.loop-{'2' * 16}"
        gone = [base / f"numerics.hybrid-{'3' * 16}", base / f"loop-{'4' * 16}"]
        base.mkdir()
        for p in keep + [other] + gone:
            p.write_text("{}") if p.suffix == ".json" else p.mkdir()
        return keep, other, gone

    keep, other, gone = make(tmp_path / "own")
    removed = disk_cache._remove_other_digests(tmp_path / "own", digests, stale_after=None)
    assert sorted(removed) == sorted([other, *gone])
    assert all(p.exists() for p in keep)

    keep, other, gone = make(tmp_path / "shared")
    assert disk_cache._remove_other_digests(tmp_path / "shared", digests, 3600.0) == []
    old = time.time() - 7200.0
    for p in (other, *gone):
        os.utime(p, (old, old))
    assert disk_cache._remove_other_digests(tmp_path / "shared", digests, 3600.0) == [other]
    assert all(p.exists() for p in keep + gone)


def test_numba_can_name_the_source_of_a_core_function_it_cannot_cache():
    """Numba names a function's source file (its cache locator's ``_py_file``) when it
    warns that the function cannot be cached (dynamic globals, as with ``NUMBA_OPT=0``);
    the core's locator has it, so that warning is a warning, not an AttributeError."""
    from scoutsim._core.model import evaluate

    impl = evaluate.evaluate_ws._cache._impl
    assert type(impl.locator).__name__ == "_CoreCacheLocator"
    assert impl.locator._py_file == evaluate.__file__
    import types
    import warnings

    from numba.core.errors import NumbaWarning

    class Result:  # (what check_cachable reads of a compile result)
        library = types.SimpleNamespace(has_dynamic_globals=True)
        lifted = ()
        fndesc = types.SimpleNamespace(qualname="evaluate_ws")

    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        assert impl.check_cachable(Result()) is False
    assert any(issubclass(w.category, NumbaWarning) for w in seen)
