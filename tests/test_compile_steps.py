"""The compile-time replacements of Numba's compiler steps (scoutsim._numba.compile_steps): on the
Numba the package pins, each is applied (a Numba release that moved the replaced code
would silently cost compile time: this says so), and the core compiled without any of them
runs bit for bit as with them (they change no compiled code)."""

import importlib.metadata
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import scoutsim
import scoutsim._numba.jit  # noqa: F401 - applies the replacements (unless SCOUTSIM_NUMBA_AS_IS)

AS_IS = bool(os.environ.get("SCOUTSIM_NUMBA_AS_IS"))


def test_the_installed_numba_is_in_the_pinned_range():
    """The replacements are checked against the Numba releases of the pin in
    pyproject.toml; the installed one must be one of them."""
    packaging = pytest.importorskip("packaging.requirements")
    import numba
    reqs = [packaging.Requirement(r) for r in importlib.metadata.requires("scoutsim") or []]
    pin = next(r for r in reqs if r.name == "numba" and r.marker is None)
    assert pin.specifier.contains(numba.__version__), (numba.__version__, str(pin))
    assert any(s.operator in ("<", "<=", "~=", "==") for s in pin.specifier), \
        f"numba has no upper bound in the pin {pin}"


@pytest.mark.skipif(AS_IS, reason="SCOUTSIM_NUMBA_AS_IS leaves Numba's steps as they are")
def test_each_replacement_is_applied_on_the_pinned_numba():
    """Each replacement found the code it replaces and was applied (a replaced step is
    marked ``_scoutsim``); one that found other code would leave Numba's step alone."""
    from numba.core import dispatcher, inline_closurecall, targetconfig
    steps = {
        "TargetConfig.__hash__": targetconfig.TargetConfig.__hash__,
        "InlineWorker.inline_ir": inline_closurecall.InlineWorker.inline_ir,
        "InlineWorker.inline_function": inline_closurecall.InlineWorker.inline_function,
        "Dispatcher.get_call_template": dispatcher.Dispatcher.get_call_template,
    }
    missing = [name for name, f in steps.items() if not getattr(f, "_scoutsim", False)]
    assert not missing, f"not applied on numba {__import__('numba').__version__}: {missing}"


_RUN = textwrap.dedent("""
    import sys
    import numpy as np
    import scoutsim
    from numba.core import targetconfig
    # the replacements are off in this process
    assert not getattr(targetconfig.TargetConfig.__hash__, "_scoutsim", False)
    out = {}
    for model in ("II", "I"):
        r = scoutsim.simulate(duration=0.3, model=model)
        out.update({f"{model}/{k}": np.asarray(v) for k, v in r.columns().items()})
    np.savez(sys.argv[1], **out)
""")


def test_the_core_compiled_without_the_replacements_runs_bit_for_bit_the_same(tmp_path):
    """A process with SCOUTSIM_NUMBA_AS_IS=1 compiles the core afresh (its own, empty
    NUMBA_CACHE_DIR) with Numba's steps as they are; its Model II and Model I runs equal
    this process's in every recorded column, bit for bit."""
    env = dict(os.environ, SCOUTSIM_NUMBA_AS_IS="1", NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    out = tmp_path / "as_is.npz"
    p = subprocess.run([sys.executable, "-c", _RUN, str(out)], env=env, capture_output=True,
                       text=True, timeout=900)
    assert p.returncode == 0, p.stderr[-2000:]
    as_is = np.load(out)
    for model in ("II", "I"):
        r = scoutsim.simulate(duration=0.3, model=model)
        for k, v in r.columns().items():
            a, b = np.asarray(v), as_is[f"{model}/{k}"]
            assert a.shape == b.shape, (model, k)
            assert a.tobytes() == b.tobytes(), (model, k)
