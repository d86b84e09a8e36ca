"""Every use of Numba's internals in scoutsim._numba and the run loop is guarded: where
Numba's code is not the one expected (another release), it is left as Numba has it, the
reason is recorded (jit.status, compile_steps.status), and only the errors a changed Numba
can give are taken for that (any other error propagates); the replacements are put in
place and taken out only as the compile context says, and never over another's."""

import numpy as np
import pytest
from numba import njit

import scoutsim
from scoutsim._core import loop
from scoutsim._numba import compile_steps, disk_cache, jit


def _other_numba_dispatcher(py_func):
    """A dispatcher of another Numba: the methods scoutsim wraps take other arguments."""

    class OtherDispatcher:
        def __init__(self, f):
            self.py_func = f

        def get_call_template(self, args, kws, flags):
            raise AssertionError("not to be called here")

        def compile(self, sig, flags):
            raise AssertionError("not to be called here")

    return OtherDispatcher(py_func)


def test_a_dispatcher_of_another_numba_is_left_as_it_is(monkeypatch):
    """The per-kind typing and the compile context check the dispatcher's methods'
    signatures; a dispatcher whose methods differ is returned untouched (no method of its
    own replaced) and the reason is recorded."""
    monkeypatch.setattr(jit, "_STATUS", {})
    d = _other_numba_dispatcher(lambda x: x)
    assert jit._typed_by_kind(d) is d and jit._compiled_in_context(d) is d
    assert "get_call_template" not in vars(d) and "compile" not in vars(d)
    assert jit._STATUS["typed_by_kind"].startswith(
        "not applied: OtherDispatcher.get_call_template takes"
    )
    assert jit._STATUS["compile_context"].startswith("not applied: OtherDispatcher.compile takes")
    # Numba's own dispatcher passes the same checks
    monkeypatch.setattr(jit, "_STATUS", {})
    n = njit(lambda x: x + 1.0)
    jit._compiled_in_context(jit._typed_by_kind(n))
    assert jit._STATUS == {"typed_by_kind": jit.APPLIED, "compile_context": jit.APPLIED}
    assert "get_call_template" in vars(n) and "compile" in vars(n)
    assert n(1.0) == 2.0


def test_the_cache_locator_is_left_out_where_numba_has_no_list_of_them(monkeypatch):
    """Without Numba's list of cache locators (a tuple here, as another release might have)
    the locator is not installed and the reason is returned (jit then compiles the core
    without the on-disk cache, its staleness could not be checked, and its status says
    why); on the pinned Numba it is installed once and
    answers only for the core's own files."""
    from numba.core import caching

    classes = caching.CacheImpl._locator_classes
    ours = [c for c in classes if c.__name__ == "_CoreCacheLocator"]
    assert len(ours) == 1 and classes[0] is ours[0]
    monkeypatch.setattr(caching.CacheImpl, "_locator_classes", tuple(classes))
    assert "_locator_classes" in disk_cache.install_cache_locator()
    assert jit.status()["cache_locator"] == jit.APPLIED  # (installed at import)
    assert caching.CacheImpl._locator_classes == tuple(classes)
    monkeypatch.undo()
    # it answers for a core function's file, with the module's directory and digest
    from scoutsim._core.model import kinematics

    f = kinematics.project_state.py_func
    loc = ours[0].from_function(f, kinematics.__file__)
    directory = disk_cache._MODULE_DIRS[str(disk_cache.PACKAGE / "_core/model/kinematics.py")]
    assert loc.get_cache_path() == str(directory)
    # and for no other file: Numba's own locators are asked, as without scoutsim

    def foreign(x):
        return x

    assert ours[0].from_function(foreign, __file__) is None


def test_a_step_that_finds_other_code_is_not_applied_and_says_why(monkeypatch):
    """Each replacement checks Numba's code; changed code (a method with other source or
    arguments) is reported as not the known code, with the reason."""
    from numba.core import inline_closurecall
    from numba.core.dispatcher import Dispatcher

    def inline_ir(self, caller_ir, block, i, callee_ir, callee_freevars, arg_typs=None):
        return None  # copies nothing block by block

    def inline_function(self, caller_ir, block, i, function):
        return None

    monkeypatch.setattr(inline_closurecall.InlineWorker, "inline_ir", inline_ir)
    monkeypatch.setattr(inline_closurecall.InlineWorker, "inline_function", inline_function)
    monkeypatch.setattr(Dispatcher, "get_call_template", lambda self, args: None)
    with pytest.raises(compile_steps._NotTheKnownCode, match="block"):
        compile_steps._inline_copy()
    with pytest.raises(compile_steps._NotTheKnownCode, match="takes"):
        compile_steps._inline_translation()
    with pytest.raises(compile_steps._NotTheKnownCode, match="takes"):
        compile_steps._inline_overloads()


def test_the_outcome_of_every_check_is_recorded_and_other_errors_propagate(monkeypatch):
    """status() lists each replacement as applied or not with the reason its check gave;
    an error that is not "other code" (a bug) is not swallowed."""

    def fine():
        class Owner:
            def m(self):
                return "numba's"

        return Owner, "m", lambda self: "ours"

    def moved():
        raise compile_steps._NotTheKnownCode("no numba.core.somewhere.Thing")

    monkeypatch.setattr(compile_steps, "_prepared", None)
    monkeypatch.setattr(compile_steps, "_status", {})
    monkeypatch.setattr(compile_steps, "AS_IS", False)
    monkeypatch.setattr(compile_steps, "STEPS", {"Owner.m": fine, "Thing.x": moved})
    assert compile_steps.status() == {
        "Owner.m": compile_steps.APPLIED,
        "Thing.x": "not applied: no numba.core.somewhere.Thing",
    }

    def bug():
        raise RuntimeError("a bug, not another Numba")

    monkeypatch.setattr(compile_steps, "_prepared", None)
    monkeypatch.setattr(compile_steps, "STEPS", {"Bug.x": bug})
    with pytest.raises(RuntimeError, match="a bug"):
        compile_steps.status()


def test_the_context_puts_back_numbas_own_and_never_replaces_anothers(monkeypatch):
    """A replaced method defined on the class is put back as it was, an inherited one is
    inherited again (the class's own attribute removed); a method someone else replaced
    after the check is not replaced (the status says so), and one replaced again while
    the context is open keeps the other's replacement."""

    class Base:
        def inherited(self):
            return "numba's inherited"

    class Owner(Base):
        def own(self):
            return "numba's own"

    class Other:
        def m(self):
            return "numba's"

    def ours(self):
        return "ours"

    ours._scoutsim = True
    own, other_m = Owner.__dict__["own"], Other.__dict__["m"]
    monkeypatch.setattr(compile_steps, "_status", {})
    monkeypatch.setattr(
        compile_steps,
        "_prepared",
        {
            "Owner.own": (Owner, "own", own, ours),
            "Owner.inherited": (Owner, "inherited", compile_steps._INHERITED, ours),
            "Other.m": (Other, "m", other_m, ours),
        },
    )

    def theirs(self):
        return "theirs"

    Other.m = theirs  # replaced by other code after the check
    with compile_steps.applied():
        assert Owner().own() == Owner().inherited() == "ours"
        assert Other().m() == "theirs"
        Owner.own = theirs  # replaced again while the context is open
    assert Owner().own() == "theirs"
    assert Owner().inherited() == "numba's inherited" and "inherited" not in vars(Owner)
    assert Other().m() == "theirs"
    assert compile_steps._status["Other.m"].startswith("not applied:")
    Owner.own = own
    Other.m = other_m  # the other code's replacement taken back
    with compile_steps.applied():
        assert Owner().own() == Other().m() == "ours"
    assert Owner.__dict__["own"] is own and Other.__dict__["m"] is other_m
    assert compile_steps._status["Other.m"] == compile_steps.APPLIED


def test_the_run_loop_runs_the_same_without_numbas_fingerprint(monkeypatch):
    """Without Numba's private compute_fingerprint (another release) the run loop's entry is
    looked up by the typed arguments: the same run, bit for bit, and no fingerprint key."""
    scoutsim.simulate(duration=0.1)  # compiled (or loaded) with the fingerprints
    ref = scoutsim.simulate(duration=0.1)
    monkeypatch.setattr(loop, "_compute_fingerprint", None)
    monkeypatch.setattr(loop, "_ENTRIES", {})
    r = scoutsim.simulate(duration=0.1)
    for k, v in ref.columns().items():
        assert np.asarray(r.columns()[k]).tobytes() == np.asarray(v).tobytes(), k
    from numba.core import types

    assert loop._ENTRIES
    assert all(all(isinstance(t, types.Type) for t in key[1]) for key in loop._ENTRIES)
