"""The compile-time replacements of Numba's compiler steps (scoutsim._numba.compile_steps): on
the Numba the package pins, each is applied (a Numba release that moved the replaced code
would silently cost compile time: this says so); they are in place only while scoutsim
compiles its own functions; and the core compiled without any of them runs bit for bit as
with them (they change no compiled code)."""

import importlib.metadata
from collections import namedtuple

import numpy as np
import pytest
from numba import njit
from numba.core import event
from numba.extending import overload

import scoutsim
from scoutsim._numba import compile_steps, jit

AS_IS = compile_steps.AS_IS


def _numba_steps():
    """The Numba attributes the replacements replace, as they are now."""
    from numba.core import dispatcher, inline_closurecall, ir_utils, targetconfig

    return {
        "TargetConfig.__hash__": targetconfig.TargetConfig.__hash__,
        "InlineWorker.inline_ir": inline_closurecall.InlineWorker.inline_ir,
        "InlineWorker.inline_function": inline_closurecall.InlineWorker.inline_function,
        "Dispatcher.get_call_template": dispatcher.Dispatcher.get_call_template,
        "ir_utils.find_potential_aliases": ir_utils.find_potential_aliases,
    }


#: a tuple of two views of an argument, made inside the function
_Pair = namedtuple("_Pair", ["a", "b"])


def _doubled(x):
    raise NotImplementedError


@overload(_doubled, inline="always")
def _doubled_impl(x):
    def impl(x):
        return 2.0 * x

    return impl


@njit(inline="always")
def _fill_first(t, v):
    for i in range(t.a.shape[0]):
        t.a[i] = v


def _sum_after_fill(buf):
    # (the overload inlined here makes Numba clean up the function after inlining it)
    t = _Pair(buf[0:3], buf[3:6])
    _fill_first(t, _doubled(3.5))
    x = t.a
    return x[0] + x[1] + x[2]


def test_the_installed_numba_is_in_the_pinned_range():
    """The replacements are checked against the Numba releases of the pin in
    pyproject.toml; the installed one must be one of them."""
    packaging = pytest.importorskip("packaging.requirements")
    import numba

    reqs = [packaging.Requirement(r) for r in importlib.metadata.requires("scoutsim") or []]
    pin = next(r for r in reqs if r.name == "numba" and r.marker is None)
    assert pin.specifier.contains(numba.__version__), (numba.__version__, str(pin))
    assert any(s.operator in ("<", "<=", "~=", "==") for s in pin.specifier), (
        f"numba has no upper bound in the pin {pin}"
    )


@pytest.mark.skipif(AS_IS, reason="SCOUTSIM_NUMBA_AS_IS leaves Numba's steps as they are")
def test_each_replacement_is_applied_on_the_pinned_numba():
    """Each replacement's check found the code it replaces (compile_steps.status), and so did
    the other guarded uses of Numba's internals (jit.status); one that found other code
    would leave Numba's alone, and say why here."""
    import numba

    found = jit.status()
    assert set(compile_steps.STEPS) <= set(found)
    assert {"compile_context", "typed_by_kind", "cache_locator"} <= set(found)
    if not jit.TYPED_BY_KIND:  # switched off in this process's environment
        assert found.pop("typed_by_kind").startswith("off:")
    not_applied = {k: v for k, v in found.items() if v != compile_steps.APPLIED}
    assert not not_applied, f"on numba {numba.__version__}: {not_applied}"


@pytest.mark.skipif(AS_IS, reason="SCOUTSIM_NUMBA_AS_IS leaves Numba's steps as they are")
def test_the_replacements_are_in_place_only_inside_the_compile_context():
    """Outside compile_steps.applied() Numba's own methods are in place (the very objects);
    inside, the replacements (marked ``_scoutsim``); a nested context's exit leaves them in
    place, the outermost one's puts Numba's back and empties the memo of translated
    callees; the context holds Numba's compiler lock."""
    from numba.core.compiler_lock import global_compiler_lock

    numba_own = _numba_steps()
    assert not any(getattr(f, "_scoutsim", False) for f in numba_own.values())
    assert not compile_steps.in_place()
    with compile_steps.applied():
        inside = _numba_steps()
        assert all(getattr(f, "_scoutsim", False) for f in inside.values()), inside
        assert global_compiler_lock.is_locked()
        with compile_steps.applied():
            assert _numba_steps() == inside
        assert _numba_steps() == inside and compile_steps.in_place()
        compile_steps._TRANSLATED["probe"] = object()
    after = _numba_steps()
    assert all(after[k] is numba_own[k] for k in numba_own)
    assert not compile_steps.in_place()
    assert compile_steps._TRANSLATED == {}


def test_a_core_function_compiles_inside_the_context_and_others_outside():
    """A compile of a function declared with jit.kernel / jit.allocating (a first call, or
    typing a call to it from other compiled code) runs inside the compile context; a plain
    Numba function's compile does not, and after either Numba's methods are its own."""
    numba_own = _numba_steps()
    seen = {}

    class Listener(event.Listener):
        def on_start(self, ev):
            seen[ev.data["dispatcher"].py_func.__name__] = (
                compile_steps.in_place(),
                all(getattr(f, "_scoutsim", False) for f in _numba_steps().values()),
            )

        def on_end(self, ev):
            pass

    def core_probe(x):
        return x * 2.0 + 1.0

    def foreign_probe(x):
        return core(x) - 1.0

    # (not cached on disk: a compile happens whatever ran before)
    core = jit._compiled_in_context(jit._typed_by_kind(njit(core_probe)))
    foreign = njit(foreign_probe)
    listener = Listener()
    event.register("numba:compile", listener)
    try:
        assert foreign(3.0) == 6.0
    finally:
        event.unregister("numba:compile", listener)
    assert seen["foreign_probe"] == (False, False)
    assert seen["core_probe"] == (True, not AS_IS)
    after = _numba_steps()
    assert all(after[k] is numba_own[k] for k in numba_own)
    # every dispatcher the decorators make compiles in the context
    from scoutsim._core.model import evaluate

    for d in (
        evaluate.evaluate_ws,
        evaluate.evaluate,
        jit.kernel(core_probe),
        jit.allocating(inline="always")(core_probe),
    ):
        assert d.compile.__wrapped__.__func__ is type(d).compile, d


def test_the_core_compiled_without_the_replacements_runs_bit_for_bit_the_same(as_is_run):
    """A process with SCOUTSIM_NUMBA_AS_IS=1 compiles the core afresh (its own, empty
    NUMBA_CACHE_DIR) with Numba's steps as they are; its Model II and Model I runs equal
    this process's in every recorded column, bit for bit. (The process starts when the
    tests are collected and this test runs last: tests/_numba/conftest.py.)"""
    rc, stderr, out = as_is_run.wait()
    assert rc == 0, stderr[-2000:]
    as_is = np.load(out)
    for model in as_is_run.models:
        r = scoutsim.simulate(duration=as_is_run.duration, model=model)
        columns = r.columns()
        assert {f"{model}/{k}" for k in columns} == {k for k in as_is if k.startswith(f"{model}/")}
        for k, v in columns.items():
            a, b = np.asarray(v), as_is[f"{model}/{k}"]
            assert a.shape == b.shape, (model, k)
            assert a.tobytes() == b.tobytes(), (model, k)


@pytest.mark.skipif(AS_IS, reason="SCOUTSIM_NUMBA_AS_IS leaves Numba's steps as they are")
def test_a_write_through_an_array_of_a_tuple_made_in_the_function_is_kept():
    """Law: a compiled function computes what its source says. An inlined callee writes
    7.0 into the first view of a named tuple made in the function; the sum read back
    through the tuple is 21. Numba's dead-code elimination, run after an inlining, loses
    that write (its alias analysis links neither the tuple to its views nor ``t.a`` to
    ``t``: numba#7135), and the function returns 0.0; compiled as scoutsim compiles its
    core (compile_steps._alias_analysis) it returns 21."""
    ours = jit._compiled_in_context(njit(_sum_after_fill))
    assert ours(np.zeros(6)) == 21.0
    if compile_steps.status()["ir_utils.find_potential_aliases"] == compile_steps.APPLIED:
        # the analysis it fills in is Numba's known one, which loses the write
        assert njit(_sum_after_fill)(np.zeros(6)) == 0.0
