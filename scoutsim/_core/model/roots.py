"""Root bracketing shared by the compiled model and integrators: one step of the Illinois
method (regula falsi with the stale end's value halved). Event location
(:mod:`scoutsim._core.numerics.hybrid`) and the battery voltage (:mod:`scoutsim._core.model.actuator`)
use it."""

from __future__ import annotations

from ..._numba.jit import kernel


@kernel(inline="always")
def illinois_update(th, fc, a, fa, b, fb, side):
    """One bracket update of the Illinois method on a bracket [a, b] with fa > 0 >= fb:
    the new point ``th`` with value ``fc`` replaces the end of its sign, and the value at
    an end kept twice in a row is halved. Returns (a, fa, b, fb, side)."""
    if fc > 0.0:
        if side == -1:
            fb *= 0.5
        return th, fc, b, fb, -1
    if side == 1:
        fa *= 0.5
    return a, fa, th, fc, 1
