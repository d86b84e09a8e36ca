"""The compiled core's declarations (scoutsim/jit.py): every compiled function says whether
it runs with reference counting, and the non-allocating kernels really run without it."""

import numpy as np
import pytest
from numba import njit
from numba.core.caching import NullCache
from numba.core.errors import TypingError
from numba.core.registry import CPUDispatcher

from scoutsim import jit, loop
from scoutsim.control import bounding
from scoutsim.model import (
    actuator, contact, evaluate, impact, kinematics, kkt, leg, rigid_body, transmission, workspace,
)
from scoutsim.numerics import ark, dopri5, events, hybrid, transitions

MODULES = (kinematics, rigid_body, leg, actuator, transmission, contact, kkt, workspace,
           impact, evaluate, ark, dopri5, events, transitions, hybrid, loop, bounding)


def dispatchers(module):
    return {name: obj for name, obj in vars(module).items()
            if isinstance(obj, CPUDispatcher) and obj.py_func.__module__ == module.__name__}


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
    for f in (evaluate.evaluate_ws, evaluate.evaluate_command_change, kinematics.project_state,
              ark.step3, hybrid.advance, transitions.settle_ws, events.event_values,
              bounding.bounding_step):
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


def test_the_compiled_cache_is_keyed_by_every_core_source(tmp_path):
    """An edit of any compiled-core module (not only of a function's own file, which is
    all Numba checks) gives a new cache directory; other modules do not."""
    import pathlib
    import shutil
    pkg = pathlib.Path(jit.__file__).parent
    copy = tmp_path / "scoutsim"
    shutil.copytree(pkg, copy, ignore=shutil.ignore_patterns("__pycache__"))
    d0 = jit.core_digest(copy)
    assert d0 == jit.core_digest(pkg)
    with open(copy / "analysis" / "gait.py", "a") as f:
        f.write("\n# not part of the compiled core\n")
    assert jit.core_digest(copy) == d0
    with open(copy / "model" / "layout.py", "a") as f:
        f.write("\n# an edit of a module that compiled functions import\n")
    assert jit.core_digest(copy) != d0
    used = pathlib.Path(jit.config.CACHE_DIR).name
    assert used in (f"numba-{d0}", f"{jit.USER_CACHE_PREFIX}{d0}")


#: run in a new process with NUMBA_CACHE_DIR set: import the package's jit module only (no
#: compilation) and report where Numba will cache and the digest of the core's sources
_REPORT_CACHE_DIR = """
import json, numba, scoutsim.jit as jit
print(json.dumps({"cache_dir": numba.config.CACHE_DIR, "digest": jit.core_digest()}))
"""


def test_a_user_numba_cache_dir_is_keyed_by_the_core_digest_too(tmp_path):
    """With NUMBA_CACHE_DIR set, the compiled core is cached in a directory of it named by
    the digest of every core source (an edit of an inlined callee in another file must not
    be served from a stale caller), a different digest names a different directory, and
    only this package's directories of other digests that nothing wrote to for a day are
    removed there: a recent one of ours and everything not ours stay."""
    import json
    import os
    import pathlib
    import subprocess
    import sys
    import time
    user = tmp_path / "user-cache"
    ours_stale = user / f"{jit.USER_CACHE_PREFIX}{'0' * 16}"
    ours_recent = user / f"{jit.USER_CACHE_PREFIX}{'1' * 16}"
    not_ours = [user / "numba-0000000000000000", user / "scoutsim-numba-notadigest",
                user / "another_program_abc123"]
    for d in (ours_stale, ours_recent, *not_ours):
        (d / "sub").mkdir(parents=True)
        (d / "sub" / "f.nbi").write_bytes(b"x")
    (user / "a-file.txt").write_text("the user's\n")
    old = time.time() - 2 * jit.STALE_USER_CACHE_S
    for d in (ours_stale, *not_ours):
        for path in (d / "sub" / "f.nbi", d / "sub", d):
            os.utime(path, (old, old))
    env = dict(os.environ, NUMBA_CACHE_DIR=str(user),
               PYTHONPATH=os.pathsep.join([str(pathlib.Path(jit.__file__).parents[1]),
                                           os.environ.get("PYTHONPATH", "")]))
    out = subprocess.run([sys.executable, "-c", _REPORT_CACHE_DIR], env=env, cwd=tmp_path,
                         capture_output=True, text=True, timeout=300, check=True)
    report = json.loads(out.stdout.strip().splitlines()[-1])
    digest = report["digest"]
    assert digest == jit.core_digest()
    cache_dir = pathlib.Path(report["cache_dir"])
    assert cache_dir.parent == user and digest in cache_dir.name
    assert cache_dir == jit.user_cache_dir(user, digest)
    other = "f" * 16 if digest != "f" * 16 else "e" * 16
    assert jit.user_cache_dir(user, other) != jit.user_cache_dir(user, digest)
    assert jit.user_cache_dir(user, other).parent == user
    assert not ours_stale.exists()
    assert (ours_recent / "sub" / "f.nbi").exists()
    assert all((d / "sub" / "f.nbi").exists() for d in not_ours)
    assert (user / "a-file.txt").read_text() == "the user's\n"
