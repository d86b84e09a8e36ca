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
"""

from __future__ import annotations

from numba import njit

_COMMON = dict(cache=True, error_model="numpy")


def kernel(func=None, *, inline: str = "never"):
    """Compile ``func`` as a non-allocating kernel (no reference counting);
    ``inline="always"`` inlines it into its callers at the Numba IR level."""
    deco = njit(**_COMMON, _nrt=False, inline=inline)
    return deco if func is None else deco(func)


def allocating(func=None, *, inline: str = "never"):
    """Compile ``func`` with reference counting (it allocates arrays)."""
    deco = njit(**_COMMON, _nrt=True, inline=inline)
    return deco if func is None else deco(func)
