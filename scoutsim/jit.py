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

Both cache their machine code on disk and use NumPy's error model (a division by zero
gives inf / nan, it does not raise).

The on-disk cache lives in a directory named by a digest of every compiled-core source
(``model/``, ``numerics/``, ``control/``, ``loop.py``, this file): Numba by itself checks
only the timestamp of a function's own file, so a cached function that inlines a callee
from another module would keep the old callee after that module is edited (a stale
result, silently). With the digest, any edit of the core compiles it afresh; directories
of other digests are removed. The directory is ``scoutsim/__pycache__/numba-<digest>``,
or, where the package is not writable, ``~/.cache/scoutsim/numba-<digest>``.

A ``NUMBA_CACHE_DIR`` set by the user is where the cache goes, keyed by the digest all the
same: ``$NUMBA_CACHE_DIR/scoutsim-numba-<digest>`` (:func:`user_cache_dir`). Such a
directory may be shared (by other programs, or by checkouts of other scoutsim versions
running at the same time), so only directories of ours (``scoutsim-numba-`` and a digest)
are ever removed there, and only those of other digests that nothing has written to for a
day (:data:`STALE_USER_CACHE_S`); everything else in it is left alone. The environment
variable itself is not changed, so processes started from this one key their cache the
same way.
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import time
from pathlib import Path

from numba import config, njit

_PACKAGE = Path(__file__).resolve().parent
#: the sources of the compiled core (a change in any of them invalidates the cache)
CORE_SOURCES = ("model/*.py", "numerics/*.py", "control/*.py", "loop.py", "jit.py")


def core_digest(package: Path = _PACKAGE) -> str:
    """Digest of the compiled core's sources (names and contents) under ``package``."""
    h = hashlib.sha256()
    files = sorted({f for pattern in CORE_SOURCES for f in package.glob(pattern)})
    for f in files:
        h.update(f.relative_to(package).as_posix().encode())
        h.update(f.read_bytes())
    return h.hexdigest()[:16]


#: name of this package's cache directory inside a ``NUMBA_CACHE_DIR`` set by the user,
#: followed by the digest
USER_CACHE_PREFIX = "scoutsim-numba-"
_USER_CACHE_NAME = re.compile(re.escape(USER_CACHE_PREFIX) + r"[0-9a-f]{16}")
#: another digest's directory in the user's ``NUMBA_CACHE_DIR`` is removed once nothing in
#: it has been written for this long [s] (a process of another version may be using it)
STALE_USER_CACHE_S = 86400.0


def user_cache_dir(base, digest: str) -> Path:
    """This package's cache directory for the compiled core of ``digest`` inside ``base``,
    a ``NUMBA_CACHE_DIR`` set by the user."""
    return Path(base) / f"{USER_CACHE_PREFIX}{digest}"


def _last_written(directory: Path) -> float:
    """Newest modification time [s since the epoch] of ``directory`` and everything in it."""
    newest = directory.stat().st_mtime
    for root, dirs, files in os.walk(directory):
        for name in dirs + files:
            try:
                newest = max(newest, os.lstat(os.path.join(root, name)).st_mtime)
            except OSError:
                pass
    return newest


def _user_cache_dir(base: Path) -> Path:
    """The cache directory inside the user's ``NUMBA_CACHE_DIR`` ``base``; removes the
    directories of ours of other digests there that nothing has written to for
    :data:`STALE_USER_CACHE_S`, and nothing else."""
    own = user_cache_dir(base, core_digest())
    try:
        entries = list(base.iterdir())
    except OSError:
        entries = []
    now = time.time()
    for old in entries:
        if old.name == own.name or not _USER_CACHE_NAME.fullmatch(old.name):
            continue
        try:
            if old.is_symlink() or not old.is_dir() or \
                    now - _last_written(old) < STALE_USER_CACHE_S:
                continue
        except OSError:
            continue
        shutil.rmtree(old, ignore_errors=True)
    return own


def _cache_dir() -> Path:
    digest = core_digest()
    for base in (_PACKAGE / "__pycache__", Path.home() / ".cache" / "scoutsim"):
        try:
            base.mkdir(parents=True, exist_ok=True)
            probe = base / f".write-test-{os.getpid()}"
            probe.touch()
            probe.unlink()
        except OSError:
            continue
        for old in base.glob("numba-*"):
            if old.name != f"numba-{digest}":
                shutil.rmtree(old, ignore_errors=True)
        return base / f"numba-{digest}"
    return _PACKAGE / "__pycache__" / f"numba-{digest}"


if os.environ.get("NUMBA_CACHE_DIR"):
    config.CACHE_DIR = str(_user_cache_dir(Path(os.environ["NUMBA_CACHE_DIR"])))
else:
    config.CACHE_DIR = str(_cache_dir())

_COMMON = dict(cache=True, error_model="numpy")


def cache_directory() -> Path:
    """Directory of the on-disk cache of the compiled core (this digest's)."""
    return Path(config.CACHE_DIR)


def core_is_compiled() -> bool:
    """True if the compiled run loop (and with it the whole core it calls) is in the cache,
    i.e. a simulation will not have to compile first (this process may still load it)."""
    d = cache_directory()
    return d.is_dir() and any(d.rglob("loop.run-*.nbi"))


#: What a simulation compiles on its first call, and about how long it takes (the first
#: call of ``loop.run``; measured on a 2-core machine, docs/model.md "Compile time").
FIRST_COMPILE_NOTICE = ("compiling the simulator core with Numba (first run after an "
                        "install or an update; about 1 min on a 2-core machine, then cached)")


#: parameters whose integer constants compile their own specializations (branch pruning)
SPECIALIZING_PARAMETERS = ("method",)


def _typed_by_kind(dispatcher):
    """Make calls from compiled code to ``dispatcher`` compile one specialization per
    argument *kind*, not one per constant value.

    Numba types a constant argument of a call (``evaluate_ws(..., True)``, a leg index
    ``0``) as a literal (``Literal[bool](True)``) and compiles the callee again for each
    literal it meets. The right-hand side was compiled five times that way (20-40 s each,
    two thirds of the first run's compilation). Here the argument types are widened to
    their non-literal kind before the callee is compiled or looked up; the caller then
    converts its constants to that kind.

    The one exception is a parameter named ``method`` (:data:`SPECIALIZING_PARAMETERS`):
    the integration method stays a literal, so each method compiles its own specialization
    of the integrator with the other methods' branches pruned, and a run compiles only the
    method it uses (:func:`scoutsim.loop.run_entry`)."""
    from numba.core import types

    resolve = dispatcher.get_call_template
    code = dispatcher.py_func.__code__
    names = code.co_varnames[:code.co_argcount]
    keep = {i for i, n in enumerate(names) if n in SPECIALIZING_PARAMETERS}

    def widen(a, literal_ok):
        return a if literal_ok and isinstance(a, types.IntegerLiteral) else types.unliteral(a)

    def get_call_template(args, kws):
        return resolve(tuple(widen(a, i in keep) for i, a in enumerate(args)),
                       {k: widen(v, k in SPECIALIZING_PARAMETERS) for k, v in kws.items()})

    dispatcher.get_call_template = get_call_template
    return dispatcher


def _compile(func, nrt: bool, inline: str):
    deco = njit(**_COMMON, _nrt=nrt, inline=inline)
    if inline != "never":   # inlined at the IR level: there is no callee to specialize
        return deco if func is None else deco(func)
    if func is None:
        return lambda f: _typed_by_kind(deco(f))
    return _typed_by_kind(deco(func))


def kernel(func=None, *, inline: str = "never"):
    """Compile ``func`` as a non-allocating kernel (no reference counting);
    ``inline="always"`` inlines it into its callers at the Numba IR level."""
    return _compile(func, False, inline)


def allocating(func=None, *, inline: str = "never"):
    """Compile ``func`` with reference counting (it allocates arrays)."""
    return _compile(func, True, inline)
