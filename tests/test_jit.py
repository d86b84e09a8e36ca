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
    assert pathlib.Path(jit.config.CACHE_DIR).name == f"numba-{d0}" or \
        "NUMBA_CACHE_DIR" in __import__("os").environ
