"""Compilation options of the compiled core (Numba), in one place.

Every compiled function of the model, the integrators and the built-in controller is
declared with one of two decorators:

``kernel``
    Functions that only read and write arrays they are given (no allocation, no array
    returned). They are compiled without Numba's reference counting (``_nrt=False``): with
    it, every array argument, every view (``wk[a:b]``, ``K[0]``) and every tuple item is
    an atomic increment on entry and an atomic decrement on exit, and on the hot loop these
    were a third of the run time (measured with ``perf`` on 10 s of Model II: 17 % of all
    samples in ``NRT_incref`` / ``NRT_decref``; without them the run went from 45 to
    30 ms, bit-identical). Numba refuses to compile a kernel that allocates, so the
    property is checked, not assumed. Arrays a kernel receives stay owned by its caller,
    which holds them for the duration of the call.
``allocating``
    Functions that create arrays (``np.zeros``, ``.copy()``): reference counting on. It
    is set explicitly because Numba otherwise lets a callee inherit the setting of the
    function that first compiles it.

Both cache their machine code on disk, one directory per module of the core named by a
digest of what it depends on (:mod:`.disk_cache`), and use NumPy's error model (a division
by zero gives inf / nan, it does not raise).

Compile time (docs/model.md "Compile time"): four of Numba's compiler steps repeat work
and are replaced by equivalent ones, and one, an alias analysis that loses writes into
arrays of tuples, by a sound one (:mod:`.compile_steps`), only while scoutsim compiles
its own functions: each dispatcher :func:`kernel` and :func:`allocating` make compiles
inside :func:`compile_steps.applied` (:func:`_compiled_in_context`), and the compiles of
its callees nest in it; other Numba users of the process see Numba as it is. Calls from
compiled code to a core function compile one specialization per argument kind, not per
constant (:func:`_typed_by_kind`). Each of these checks that Numba's code is the one it
expects, else leaves Numba's as it is; :func:`status` records what was applied and why
not. To compare (the results are bit for bit the same either way), two switches in the
environment: ``SCOUTSIM_NUMBA_AS_IS=1`` leaves the five replacements out (Numba's steps as
they are), ``SCOUTSIM_NUMBA_SPECIALIZE_CONSTANTS=1`` leaves :func:`_typed_by_kind` out (one
specialization per constant argument, as Numba does by itself: about 45 % more CPU time for
the first compile, which is why it has its own switch and is not part of the first).
"""

from __future__ import annotations

import functools
import inspect
import os
import time

from numba import njit

from . import compile_steps, disk_cache

# (where the command line asks whether the core is compiled)
from .disk_cache import PACKAGE, cache_directory, core_is_compiled  # noqa: F401

#: what the guarded hooks of this module found on the installed Numba (:func:`status`)
_STATUS: dict[str, str] = {}
APPLIED = compile_steps.APPLIED

_why_not_cached = disk_cache.install_cache_locator()
_STATUS["cache_locator"] = APPLIED if _why_not_cached is None else f"not applied: {_why_not_cached}"

_COMMON = dict(cache=_why_not_cached is None, error_model="numpy")


#: What a simulation compiles on its first call, and about how long it takes (the first
#: call of ``loop.run``; measured on a 2-core machine, docs/model.md "Compile time").
FIRST_COMPILE_NOTICE = (
    "compiling the simulator core with Numba (first run after an "
    "install or an update; about 1 min on a 2-core machine, then cached)"
)


class compile_progress:
    """Context manager: while it is open, say on ``stream`` what the compiled core is
    compiling. On a terminal one line is rewritten as each function of the core is done
    (how many, the time so far, the last one); elsewhere (a log) one line is printed at the
    end. Nothing is printed if nothing of the core was compiled."""

    def __init__(self, stream, prefix: str = "  "):
        self.stream = stream
        self.prefix = prefix
        self.done = 0
        self.t0 = None
        try:
            self.tty = stream.isatty()
        except (AttributeError, ValueError):
            self.tty = False

    def __enter__(self):
        from numba.core import event

        progress = self

        class _Listener(event.Listener):
            def on_start(self, ev):
                pass

            def on_end(self, ev):
                try:
                    progress._compiled(ev.data["dispatcher"].py_func)
                except Exception:  # never let a message break a compile
                    pass

        self.t0 = time.perf_counter()
        self._listener = _Listener()
        event.register("numba:compile", self._listener)
        return self

    def _compiled(self, py_func):
        module = py_func.__module__ or ""
        if not module.startswith(PACKAGE.name + "."):
            return
        self.done += 1
        if self.tty:
            name = f"{module[len(PACKAGE.name) + 1 :]}.{py_func.__qualname__}"
            self.stream.write(
                f"\r\033[K{self.prefix}compiled {self.done} functions in "
                f"{time.perf_counter() - self.t0:.0f} s (last: {name})"
            )
            self.stream.flush()

    def __exit__(self, *exc):
        from numba.core import event

        event.unregister("numba:compile", self._listener)
        if self.done:
            end = "\r\033[K" if self.tty else ""
            self.stream.write(
                f"{end}{self.prefix}compiled {self.done} function"
                f"{'s' if self.done != 1 else ''} of the core in "
                f"{time.perf_counter() - self.t0:.1f} s (cached now)\n"
            )
            self.stream.flush()
        return False


#: parameters whose integer constants compile their own specializations (branch pruning)
SPECIALIZING_PARAMETERS = ("method",)
#: the environment variable that turns :func:`_typed_by_kind` off: calls from compiled
#: code to the core's functions then compile one specialization per constant, as Numba does
#: by itself (the same results, bit for bit; about 45 % more CPU time for the first
#: compile). Not part of ``SCOUTSIM_NUMBA_AS_IS``: the core compiled both ways would take
#: its test past its time budget.
SPECIALIZE_CONSTANTS_VARIABLE = "SCOUTSIM_NUMBA_SPECIALIZE_CONSTANTS"
#: whether calls to the core's functions compile one specialization per argument kind
#: (:func:`_typed_by_kind`); off with :data:`SPECIALIZE_CONSTANTS_VARIABLE` set
TYPED_BY_KIND = not os.environ.get(SPECIALIZE_CONSTANTS_VARIABLE)


def _has_method(dispatcher, name: str, parameters: tuple[str, ...]) -> str | None:
    """None if the class of ``dispatcher`` has the method ``name`` taking ``parameters``
    (and the instance does not override it), else why not."""
    method = getattr(type(dispatcher), name, None)
    if method is None:
        return f"{type(dispatcher).__name__} has no {name}"
    if name in vars(dispatcher):
        return f"{name} is already replaced on the dispatcher"
    try:
        found = tuple(inspect.signature(method).parameters)
    except (TypeError, ValueError) as exc:
        return f"{type(dispatcher).__name__}.{name} has no readable signature ({exc})"
    if found != parameters:
        return f"{type(dispatcher).__name__}.{name} takes {found}, not {parameters}"
    return None


def _typed_by_kind(dispatcher):
    """Make calls from compiled code to ``dispatcher`` compile one specialization per
    argument *kind*, not one per constant value.

    Numba types a constant argument of a call (``evaluate_ws(..., True)``, a leg index
    ``0``) as a literal (``Literal[bool](True)``) and compiles the callee again for each
    literal it meets. The right-hand side was compiled five times that way (20-40 s each,
    two thirds of the first run's compilation). Here the argument types are widened to
    their non-literal kind before the callee is compiled or looked up; the caller then
    converts its constants to that kind. It changes which specializations are compiled,
    not what they compute.

    The one exception is a parameter named ``method`` (:data:`SPECIALIZING_PARAMETERS`):
    the integration method stays a literal, so each method compiles its own specialization
    of the integrator with the other methods' branches pruned, and a run compiles only the
    method it uses (:func:`scoutsim._core.loop.run_entry`).

    The dispatcher's ``get_call_template`` (Numba's, called by the typing of a call) is
    replaced on this dispatcher only, after a check that it is the method this expects
    (``get_call_template(self, args, kws)``); else the dispatcher is left as it is and
    :func:`status` says why. Off with :data:`TYPED_BY_KIND` false."""
    if not TYPED_BY_KIND:
        _STATUS["typed_by_kind"] = f"off: {SPECIALIZE_CONSTANTS_VARIABLE} is set"
        return dispatcher
    why_not = _has_method(dispatcher, "get_call_template", ("self", "args", "kws"))
    if why_not is not None:
        _STATUS["typed_by_kind"] = f"not applied: {why_not}"
        return dispatcher
    _STATUS.setdefault("typed_by_kind", APPLIED)
    from numba.core import types

    cls = type(dispatcher)
    code = dispatcher.py_func.__code__
    names = code.co_varnames[: code.co_argcount]
    keep = {i for i, n in enumerate(names) if n in SPECIALIZING_PARAMETERS}

    def widen(a, literal_ok):
        return a if literal_ok and isinstance(a, types.IntegerLiteral) else types.unliteral(a)

    def get_call_template(args, kws):
        # (the class's method, looked up at the call: Numba's, or compile_steps's
        # replacement while the core compiles)
        return cls.get_call_template(
            dispatcher,
            tuple(widen(a, i in keep) for i, a in enumerate(args)),
            {k: widen(v, k in SPECIALIZING_PARAMETERS) for k, v in kws.items()},
        )

    dispatcher.get_call_template = get_call_template
    return dispatcher


def _compiled_in_context(dispatcher):
    """Make every compile of ``dispatcher`` (a first call, a call from compiled code that
    types it, ``dispatcher.compile``) run inside :func:`compile_steps.applied`, so
    Numba's replaced compiler steps are in place for it and its callees and for nothing
    else; the first one in a process also cleans the cache
    (:func:`~scoutsim._numba.disk_cache.clean_cache`). Numba's ``compile(self, sig)`` is
    wrapped on this dispatcher only, after a check that it is
    the method this expects; else the dispatcher is left as it is (compiled with Numba's
    steps) and :func:`status` says why."""
    why_not = _has_method(dispatcher, "compile", ("self", "sig"))
    if why_not is not None:
        _STATUS["compile_context"] = f"not applied: {why_not}"
        return dispatcher
    _STATUS.setdefault("compile_context", APPLIED)
    compile_numba = dispatcher.compile

    @functools.wraps(compile_numba)
    def compile(sig):
        with compile_steps.applied():
            disk_cache.clean_once()
            return compile_numba(sig)

    dispatcher.compile = compile
    return dispatcher


def status() -> dict[str, str]:
    """What each of the guarded uses of Numba's internals found on the installed Numba:
    ``"applied"``, or ``"off: ..."`` / ``"not applied: ..."`` and why (then Numba's own
    code is used). The five compiler steps (:func:`compile_steps.status`), the compile
    context of the core's dispatchers (``compile_context``), the per-kind typing of calls
    (``typed_by_kind``) and the cache locator (``cache_locator``)."""
    return {**compile_steps.status(), **_STATUS}


def _own(dispatcher, inline: str):
    """A dispatcher of the core: compiled inside the compile context, and typed by kind
    unless it is inlined at the IR level (then there is no callee to specialize)."""
    if inline == "never":
        _typed_by_kind(dispatcher)
    return _compiled_in_context(dispatcher)


def _compile(func, nrt: bool, inline: str):
    # _nrt: Numba's own switch of reference counting, not in its published signature
    deco = njit(**_COMMON, _nrt=nrt, inline=inline)  # type: ignore[call-overload]
    if func is None:
        return lambda f: _own(deco(f), inline)
    return _own(deco(func), inline)


def kernel(func=None, *, inline: str = "never"):
    """Compile ``func`` as a non-allocating kernel (no reference counting);
    ``inline="always"`` inlines it into its callers at the Numba IR level."""
    return _compile(func, False, inline)


def c_function(signature, func):
    """Compile ``func`` now as a C function of ``signature`` (cached on disk), for calls
    by address from compiled code (its ``.address``): code a compiled caller runs without
    linking it. With reference counting (Numba's ``carray``, which makes arrays of the
    addresses it is given, needs it); its callees are kernels as they are declared."""
    from numba import cfunc

    with compile_steps.applied():
        disk_cache.clean_once()
        return cfunc(signature, **_COMMON, _nrt=True)(func)


def allocating(func=None, *, inline: str = "never"):
    """Compile ``func`` with reference counting (it allocates arrays)."""
    return _compile(func, True, inline)
