"""Compile time: four of Numba's compiler steps that repeat work, replaced by equivalent
ones (docs/model.md "Compile time"). They change no compiled code (the results are bit for
bit those without them); each checks that Numba's code is the one it replaces and otherwise
leaves it alone. :mod:`scoutsim._numba.jit` applies them unless ``SCOUTSIM_NUMBA_AS_IS`` is set.

- the hash of the compiler flags on every overload lookup (:func:`_speed_up_flags_hash`);
- the IR inliner's per-block deep copies (:func:`_speed_up_inline_copy`, numba#8989,
  numba#9204) and its per-call-site re-translation of the callee
  (:func:`_speed_up_inline_translation`);
- the full compilation of an always-inlined overload's implementation that is then thrown
  away (:func:`inline_only`, :func:`_speed_up_inline_overloads`, numba#6856).
"""

from __future__ import annotations


def _speed_up_flags_hash():
    """Numba's ``TargetConfig.__hash__`` is ``hash(tuple(sorted(self.values())))``:
    ``values()`` builds a dict of every option (a getattr each), and sorting a dict yields
    its keys, so the hash is that of the sorted option *names*, the same for every instance
    of a class. It is computed on every overload lookup (``templates._get_impl``: every
    array index and arithmetic operator typed). The same value, computed once per class."""
    from numba.core import targetconfig
    cls = targetconfig.TargetConfig
    if getattr(cls.__hash__, "_scoutsim", False):
        return
    probe = cls.__new__(cls)
    probe._values = {}
    if cls.__hash__(probe) != hash(tuple(sorted(cls.options))):   # not the known code
        return
    hashes = {}

    def __hash__(self):
        t = type(self)
        h = hashes.get(t)
        if h is None:
            h = hashes[t] = hash(tuple(sorted(t.options)))
        return h

    __hash__._scoutsim = True
    cls.__hash__ = __hash__


def _speed_up_inline_copy():
    """Numba's IR inliner (``inline="always"``) deep-copies the callee's IR block by block,
    each block with its own ``copy.deepcopy``: the scope all blocks share (every variable
    of the function) is copied again for every block (numba#8989, numba#9204). One memo
    for all blocks copies it once (the blocks then share one scope, as in the original)."""
    import inspect
    import textwrap
    from numba.core import inline_closurecall as icc
    worker = icc.InlineWorker
    if getattr(worker.inline_ir, "_scoutsim", False):
        return
    try:
        src = textwrap.dedent(inspect.getsource(worker.inline_ir))
    except (OSError, TypeError):
        return
    old_a = "kernel_copy.blocks = {}\n"
    old_b = "copy.deepcopy(the_ir.blocks[block_label])"
    if src.count(old_a) != 1 or src.count(old_b) != 1:
        return
    indent = src.split(old_a)[0].rsplit("\n", 1)[1]
    src = src.replace(old_a, old_a + indent + "_memo = {}\n")
    src = src.replace(old_b, "copy.deepcopy(the_ir.blocks[block_label], _memo)")
    ns = {}
    exec(compile(src, icc.__file__, "exec"), icc.__dict__, ns)
    ns["inline_ir"]._scoutsim = True
    worker.inline_ir = ns["inline_ir"]


def _speed_up_inline_translation():
    """Numba's IR inliner runs the untyped pipeline (bytecode to IR, and the inlining of
    the callee's own ``inline="always"`` callees) on the callee at every call site again
    (numba#9204); its result depends only on the function and the compiler flags. Kept
    per function and flags (``inline_ir`` copies it before changing anything)."""
    import inspect
    from numba.core import inline_closurecall as icc
    worker = icc.InlineWorker
    if getattr(worker.inline_function, "_scoutsim", False):
        return
    try:
        src = inspect.getsource(worker.inline_function)
    except (OSError, TypeError):
        return
    if "callee_ir = self.run_untyped_passes(function)" not in src:
        return
    memo = {}

    def inline_function(self, caller_ir, block, i, function, arg_typs=None):
        key = (function, function.__code__, repr(self.flags))
        callee_ir = memo.get(key)
        if callee_ir is None:
            callee_ir = memo[key] = self.run_untyped_passes(function)
        freevars = function.__code__.co_freevars
        return self.inline_ir(caller_ir, block, i, callee_ir, freevars, arg_typs=arg_typs)

    inline_function._scoutsim = True
    worker.inline_function = inline_function


def inline_only(impl):
    """Mark ``impl``, the implementation returned by an ``@overload(..., inline="always")``,
    as only ever inlined: typing a call of it then does not compile it. (Numba types an
    always-inlined overload by compiling its implementation in full, LLVM included, and
    throws the result away, numba#6856: 2.5 s for each variant of the ARK3 step's wrapper.)
    The implementation must not ask for literal arguments (``numba.literally``)."""
    impl._scoutsim_inline_only = True
    return impl


def _speed_up_inline_overloads():
    """Typing a call of an :func:`inline_only` implementation folds its arguments without
    compiling it (the inliner types it from its IR, as it does for any inlined overload)."""
    from numba.core import dispatcher
    disp = dispatcher.Dispatcher
    if getattr(disp.get_call_template, "_scoutsim", False):
        return
    orig = disp.get_call_template

    def get_call_template(self, args, kws):
        if getattr(self.py_func, "_scoutsim_inline_only", False) and self._can_compile:
            self._can_compile = False
            try:
                return orig(self, args, kws)
            finally:
                self._can_compile = True
        return orig(self, args, kws)

    get_call_template._scoutsim = True
    disp.get_call_template = get_call_template


def speed_up_numba():
    """Replace each of the steps above, leaving any that is not the code it expects as
    Numba has it."""
    for speed_up in (_speed_up_flags_hash, _speed_up_inline_copy,
                     _speed_up_inline_translation, _speed_up_inline_overloads):
        try:
            speed_up()
        except Exception:    # another Numba: leave its code as it is
            pass
