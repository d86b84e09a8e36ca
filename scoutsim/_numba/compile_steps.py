"""Numba's compiler steps that scoutsim replaces while it compiles its own core, and only
then (docs/model.md "Compile time"): four that repeat work, replaced by equivalent ones,

- the hash of the compiler flags on every overload lookup (:func:`_flags_hash`);
- the IR inliner's per-block deep copies (:func:`_inline_copy`, numba#8989, numba#9204)
  and its per-call-site re-translation of the callee (:func:`_inline_translation`);
- the full compilation of an always-inlined overload's implementation that is then thrown
  away (:func:`inline_only`, :func:`_inline_overloads`, numba#6856);

and one that is wrong: the alias analysis of the dead-code elimination Numba runs after
inlining, which lets it remove a write into an array taken from a tuple made in the
function (:func:`_alias_analysis`, numba#7135).

The first four change no compiled code: the results are bit for bit those without them
(``tests/_numba/test_compile_steps.py`` compiles the core both ways and compares). The
fifth keeps writes that Numba's analysis would remove; on the core as it is, that changes
no plain run's results either (the same test, and ``tools/check_identical.py``); it moved
the derivatives carried with a run by about 1e-8, where such a write had been lost.

**Only while the core compiles.** The replacements are class attributes of Numba's, so
they would change every Numba user of the process if they stayed in place. They are put
in place by :func:`applied`, a re-entrant context manager that :mod:`scoutsim._numba.jit`
enters around every compile of one of scoutsim's own functions (the compiles of its
callees nest inside it), and Numba's own attributes are put back when the outermost one
exits. While they are in place the context holds Numba's compiler lock, so no other
thread compiles meanwhile; outside it, Numba is exactly as it was imported. The memo of
re-translated callees (:func:`_inline_translation`) lives as long as the outermost context.

**Checked, not assumed.** Each replacement first checks that Numba's code is the one it
replaces (its source text or signature, on the Numba releases of the pin in
pyproject.toml) and otherwise leaves Numba's step as it is. What each check found is
recorded, not swallowed: :func:`status` says, for each replacement, ``"applied"`` or why
not (``tests/_numba/test_compile_steps.py`` fails on the pinned Numba unless all five are applied).
Only the errors a moved or changed Numba can give (a missing module or attribute, a source
that cannot be read, a signature that differs) count as "not the known code"; any other
error propagates.

``SCOUTSIM_NUMBA_AS_IS=1`` in the environment (read at import) leaves all five as Numba
has them (to compare: :data:`AS_IS`).
"""

from __future__ import annotations

import contextlib
import importlib
import inspect
import os
import textwrap
import threading
from collections.abc import Mapping

#: the environment variable that leaves Numba's compiler steps as Numba has them
AS_IS_VARIABLE = "SCOUTSIM_NUMBA_AS_IS"
#: True if :data:`AS_IS_VARIABLE` is set (non-empty): no replacement is put in place
AS_IS = bool(os.environ.get(AS_IS_VARIABLE))
#: :func:`status` of a replacement that is put in place while the core compiles
APPLIED = "applied"


class _NotTheKnownCode(Exception):
    """A replacement's check found other code than the one it replaces (the reason)."""


def _lookup(module: str, qualname: str = ""):
    """``module.qualname`` of Numba's (the module itself without ``qualname``), or
    :class:`_NotTheKnownCode` if it is not there."""
    try:
        obj = importlib.import_module(module)
    except ImportError as exc:
        raise _NotTheKnownCode(f"no module {module} ({exc})") from None
    for part in qualname.split(".") if qualname else ():
        try:
            obj = getattr(obj, part)
        except AttributeError:
            raise _NotTheKnownCode(f"no {module}.{qualname}") from None
    return obj


def _source(func, where: str) -> str:
    try:
        return textwrap.dedent(inspect.getsource(func))
    except (OSError, TypeError) as exc:
        raise _NotTheKnownCode(f"the source of {where} cannot be read ({exc})") from None


def _check_parameters(func, where: str, expected: tuple[str, ...]):
    try:
        names = tuple(inspect.signature(func).parameters)
    except (TypeError, ValueError) as exc:
        raise _NotTheKnownCode(f"{where} has no readable signature ({exc})") from None
    if names != expected:
        raise _NotTheKnownCode(f"{where} takes {names}, not {expected}")


def _flags_hash():
    """Numba's ``TargetConfig.__hash__`` is ``hash(tuple(sorted(self.values())))``:
    ``values()`` builds a dict of every option (a getattr each), and sorting a dict yields
    its keys, so the hash is that of the sorted option *names*, the same for every instance
    of a class. It is computed on every overload lookup (``templates._get_impl``: every
    array index and arithmetic operator typed). The same value, computed once per class
    (the same value: a dict keyed by flags finds its keys with either hash)."""
    cls = _lookup("numba.core.targetconfig", "TargetConfig")
    src = _source(cls.__hash__, "TargetConfig.__hash__")
    if "hash(tuple(sorted(self.values())))" not in src:
        raise _NotTheKnownCode("TargetConfig.__hash__ is not the hash of its sorted values")
    options = getattr(cls, "options", None)
    if not isinstance(options, Mapping):
        raise _NotTheKnownCode("TargetConfig has no mapping of options")
    probe = cls.__new__(cls)
    probe._values = {}
    try:
        same = cls.__hash__(probe) == hash(tuple(sorted(options)))
    except (AttributeError, TypeError) as exc:
        raise _NotTheKnownCode(
            f"TargetConfig.__hash__ fails on a default instance ({exc})"
        ) from None
    if not same:
        raise _NotTheKnownCode("TargetConfig.__hash__ is not the hash of its option names")
    hashes = {}

    def __hash__(self):
        t = type(self)
        h = hashes.get(t)
        if h is None:
            h = hashes[t] = hash(tuple(sorted(t.options)))
        return h

    return cls, "__hash__", __hash__


def _inline_copy():
    """Numba's IR inliner (``inline="always"``) deep-copies the callee's IR block by block,
    each block with its own ``copy.deepcopy``: the scope all blocks share (every variable
    of the function) is copied again for every block (numba#8989, numba#9204). One memo
    for all blocks copies it once (the blocks then share one scope, as in the original).
    The method is Numba's own source with these two lines edited, compiled in Numba's
    module."""
    icc = _lookup("numba.core.inline_closurecall")
    worker = _lookup("numba.core.inline_closurecall", "InlineWorker")
    src = _source(worker.inline_ir, "InlineWorker.inline_ir")
    old_a = "kernel_copy.blocks = {}\n"
    old_b = "copy.deepcopy(the_ir.blocks[block_label])"
    if src.count(old_a) != 1 or src.count(old_b) != 1:
        raise _NotTheKnownCode(
            "InlineWorker.inline_ir does not copy the blocks one by one as expected"
        )
    indent = src.split(old_a)[0].rsplit("\n", 1)[1]
    src = src.replace(old_a, old_a + indent + "_memo = {}\n")
    src = src.replace(old_b, "copy.deepcopy(the_ir.blocks[block_label], _memo)")
    ns = {}
    exec(compile(src, icc.__file__, "exec"), icc.__dict__, ns)
    return worker, "inline_ir", ns["inline_ir"]


#: the callees' IR translated by the untyped pipeline, by (function, code, flags): kept
#: while the outermost :func:`applied` context lasts, cleared when it exits
_TRANSLATED: dict[tuple, object] = {}


def _inline_translation():
    """Numba's IR inliner runs the untyped pipeline (bytecode to IR, and the inlining of
    the callee's own ``inline="always"`` callees) on the callee at every call site again
    (numba#9204); its result depends only on the function and the compiler flags. Kept
    per function and flags in :data:`_TRANSLATED` (``inline_ir`` copies it before
    changing anything) for the duration of one compile of the core."""
    worker = _lookup("numba.core.inline_closurecall", "InlineWorker")
    _check_parameters(
        worker.inline_function,
        "InlineWorker.inline_function",
        ("self", "caller_ir", "block", "i", "function", "arg_typs"),
    )
    src = _source(worker.inline_function, "InlineWorker.inline_function")
    if "callee_ir = self.run_untyped_passes(function)" not in src:
        raise _NotTheKnownCode(
            "InlineWorker.inline_function does not translate the callee with run_untyped_passes"
        )

    def inline_function(self, caller_ir, block, i, function, arg_typs=None):
        key = (function, function.__code__, repr(self.flags))
        callee_ir = _TRANSLATED.get(key)
        if callee_ir is None:
            callee_ir = _TRANSLATED[key] = self.run_untyped_passes(function)
        freevars = function.__code__.co_freevars
        return self.inline_ir(caller_ir, block, i, callee_ir, freevars, arg_typs=arg_typs)

    return worker, "inline_function", inline_function


def inline_only(impl):
    """Mark ``impl``, the implementation returned by an ``@overload(..., inline="always")``,
    as only ever inlined: typing a call of it then does not compile it. (Numba types an
    always-inlined overload by compiling its implementation in full, LLVM included, and
    throws the result away, numba#6856: 2.5 s for each variant of the ARK3 step's wrapper.)
    The implementation must not ask for literal arguments (``numba.literally``).
    Without the replacement in place (:data:`AS_IS`, another Numba) the mark does nothing."""
    impl._scoutsim_inline_only = True
    return impl


def _inline_overloads():
    """Typing a call of an :func:`inline_only` implementation folds its arguments without
    compiling it (the inliner types it from its IR, as it does for any inlined overload):
    Numba's ``Dispatcher.get_call_template`` with the dispatcher's ``_can_compile`` off."""
    disp = _lookup("numba.core.dispatcher", "Dispatcher")
    orig = disp.get_call_template
    _check_parameters(orig, "Dispatcher.get_call_template", ("self", "args", "kws"))
    src = _source(orig, "Dispatcher.get_call_template")
    if "if self._can_compile:" not in src:
        raise _NotTheKnownCode("Dispatcher.get_call_template does not ask _can_compile")

    def get_call_template(self, args, kws):
        if getattr(self.py_func, "_scoutsim_inline_only", False) and self._can_compile:
            self._can_compile = False
            try:
                return orig(self, args, kws)
            finally:
                self._can_compile = True
        return orig(self, args, kws)

    return disp, "get_call_template", get_call_template


def _alias_analysis():
    """Numba's dead-code elimination, run after every IR inlining, removes a write into an
    array (``x[i] = v``) unless the variable ``x``, or a variable its alias analysis
    (``ir_utils.find_potential_aliases``) links to it, is read later or aliases an
    argument. That analysis links ``a = b.c`` to ``b`` only when ``b`` already aliases an
    argument, and a tuple made in the function (``build_tuple``, a named tuple's
    constructor) to none of its items. So a write through an array taken from such a tuple,
    ``t.x[i] = v`` (typically in an inlined callee given ``t``), is removed when that
    variable is not read again, though the array is read later through another name:
    the write is silently lost (numba#7135; numba PR #7167, open, links tuples made from
    parts). Found here as carried derivatives that came out zero, or with an explicit
    integration step where the splitting matrix had been copied.

    The replacement runs Numba's analysis, then links every ``getattr`` result to its
    object and every tuple made in the function to its items, closes the links
    transitively, and counts every variable linked to an argument's alias as one. It can
    only keep writes Numba's removes: a store that is truly dead is left to LLVM's own
    dead-store elimination, which sees the memory."""
    iru = _lookup("numba.core.ir_utils")
    ir = _lookup("numba.core.ir")
    original = _lookup("numba.core.ir_utils", "find_potential_aliases")
    where = "ir_utils.find_potential_aliases"
    _check_parameters(
        original, where, ("blocks", "args", "typemap", "func_ir", "alias_map", "arg_aliases")
    )
    src = _source(original, where)
    if "expr.value.name in arg_aliases" not in src or "build_tuple" in src:
        raise _NotTheKnownCode(f"{where} is not the analysis whose gaps this fills")
    add_alias = _lookup("numba.core.ir_utils", "_add_alias")
    immutable = _lookup("numba.core.ir_utils", "is_immutable_type")
    get_definition = _lookup("numba.core.ir_utils", "get_definition")

    def tuple_class(func_ir, var) -> bool:
        try:
            d = get_definition(func_ir, var)
        except Exception:  # noqa: BLE001 - no single definition: not a known class
            return False
        value = getattr(d, "value", None) if isinstance(d, (ir.Global, ir.FreeVar)) else None
        return isinstance(value, type) and issubclass(value, tuple)

    def find_potential_aliases(blocks, args, typemap, func_ir, alias_map=None, arg_aliases=None):
        alias_map, arg_aliases = original(blocks, args, typemap, func_ir, alias_map, arg_aliases)
        linked = False
        for block in blocks.values():
            for instr in block.body:
                if not isinstance(instr, ir.Assign) or not isinstance(instr.value, ir.Expr):
                    continue
                lhs, expr = instr.target.name, instr.value
                if typemap is not None and immutable(lhs, typemap):
                    continue
                if expr.op == "getattr" and expr.attr != "shape":
                    parts = [expr.value.name]
                elif expr.op == "build_tuple":
                    parts = [v.name for v in expr.items]
                elif expr.op == "call" and tuple_class(func_ir, expr.func):
                    parts = [v.name for v in expr.args] + [v.name for _, v in expr.kws]
                else:
                    continue
                for part in parts:
                    add_alias(lhs, part, alias_map, arg_aliases)
                    add_alias(part, lhs, alias_map, arg_aliases)
                    linked = True
        if not linked:
            return alias_map, arg_aliases
        changed = True
        while changed:
            changed = False
            for v in list(alias_map):
                group = set(alias_map[v]) | {v}
                for w in list(group):
                    group |= alias_map.get(w, set())
                group.discard(v)
                if group != alias_map[v]:
                    alias_map[v] = group
                    changed = True
                if (v in arg_aliases or group & arg_aliases) and not group <= arg_aliases:
                    arg_aliases |= group | {v}
                    changed = True
        return alias_map, arg_aliases

    return iru, "find_potential_aliases", find_potential_aliases


#: the replacements, by the Numba attribute each replaces
STEPS = {
    "TargetConfig.__hash__": _flags_hash,
    "InlineWorker.inline_ir": _inline_copy,
    "InlineWorker.inline_function": _inline_translation,
    "Dispatcher.get_call_template": _inline_overloads,
    "ir_utils.find_potential_aliases": _alias_analysis,
}

_INHERITED = object()  # (an attribute the class inherits: put back by deleting ours)
_LOCK = threading.Lock()
_status: dict[str, str] = {}
#: the checked replacements: name -> (owner, attribute, Numba's own, the replacement)
_prepared: dict | None = None
_depth = 0
_installed: list = []


def _prepare() -> dict:
    """Check each replacement against the installed Numba (once per process; with
    :data:`_LOCK` held) and record the outcome in :data:`_status`."""
    global _prepared
    if _prepared is not None:
        return _prepared
    prepared = {}
    for name, make in STEPS.items():
        if AS_IS:
            _status[name] = f"off: {AS_IS_VARIABLE} is set"
            continue
        try:
            owner, attr, new = make()
        except _NotTheKnownCode as exc:
            _status[name] = f"not applied: {exc}"
            continue
        new._scoutsim = True
        prepared[name] = (owner, attr, owner.__dict__.get(attr, _INHERITED), new)
        _status[name] = APPLIED
    _prepared = prepared
    return prepared


def status() -> dict[str, str]:
    """For each replacement (:data:`STEPS`), ``"applied"`` (it is put in place while the
    core compiles) or why not: ``"off: ..."`` (:data:`AS_IS`) or ``"not applied: ..."``
    (the installed Numba's code is not the one it replaces; Numba's is used)."""
    with _LOCK:
        _prepare()
        return dict(_status)


def _install():
    for name, (owner, attr, original, new) in _prepare().items():
        if owner.__dict__.get(attr, _INHERITED) is not original:
            # someone else replaced Numba's step since it was checked: leave theirs
            _status[name] = f"not applied: {name} was replaced by other code"
            continue
        setattr(owner, attr, new)
        _installed.append((owner, attr, original, new))
        _status[name] = APPLIED


def _restore():
    while _installed:
        owner, attr, original, new = _installed.pop()
        if owner.__dict__.get(attr) is not new:
            continue  # replaced again by other code meanwhile: theirs stays
        if original is _INHERITED:
            delattr(owner, attr)
        else:
            setattr(owner, attr, original)
    _TRANSLATED.clear()


@contextlib.contextmanager
def applied():
    """Context manager: while it is open, the replacements are in place (those
    :func:`status` says are applied) and Numba's compiler lock is held. Re-entrant (a
    count of depth): the outermost one puts them in place and puts Numba's own back."""
    global _depth
    from numba.core.compiler_lock import global_compiler_lock

    with global_compiler_lock:
        with _LOCK:
            if _depth == 0:
                _install()
            _depth += 1
        try:
            yield
        finally:
            with _LOCK:
                _depth -= 1
                if _depth == 0:
                    _restore()


def in_place() -> bool:
    """True while an :func:`applied` context is open (in any thread)."""
    return _depth > 0
