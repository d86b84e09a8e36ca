"""Event location within one step: the events' zeros, found in continuous time.

A plant event is a sign change of an armed event function
(:mod:`scoutsim._core.numerics.events`) over a step of the integrator of one control period
(:mod:`scoutsim._core.numerics.hybrid`). Its zero is bracketed and found by the Illinois
method on the step's continuous extension (:func:`dense_event_values`) to EVENT_TIME_TOL;
the step redone to that instant is then checked on the event functions themselves and, if
it is not at their zero, the zero is located on redone steps (:func:`refine_event`).
Compiled with Numba.
"""

from __future__ import annotations

from ..._numba.jit import kernel
from ..model.evaluate import evaluate_ws, evaluated_state
from ..model.layout import NEV, NS
from ..model.roots import illinois_update
from .events import event_values_at
from .stepper import do_step, method_dense

#: an event's instant is located when its bracket is narrower than this [s]
EVENT_TIME_TOL = 1e-13
#: an event function counts as at its zero on a step that ends within this time of it [s]
#: (measured with the function's slope over the step; docs/specification.md section 7 asks for 1e-9 s)
EVENT_STATE_TOL = 1e-10


@kernel(inline="always")
def dense_event_values(method, s, h, th, P, mi, mf, cmd, work, evw):
    """Event functions (into evw.e_tmp) at the fraction ``th`` of the step of size ``h``
    from ``s`` to ``work.y_new``, on the method's continuous extension (one evaluation;
    ``work``: :class:`~scoutsim._core.numerics.work.StepWork`, ``evw``: its ``EventWork``)."""
    ybuf, aux_tmp, ew = evw.ybuf, evw.aux_tmp, work.ew
    method_dense(method, s, work.y_new, h, work.K, th, ybuf)
    evaluate_ws(ybuf, P, mi, mf, cmd, work.tmp, aux_tmp, ew, False, ew[3], True)
    sth, cth = evaluated_state(ew, ybuf)  # ybuf projected
    event_values_at(ybuf, aux_tmp, P, mi, evw.e_tmp, sth, cth)


@kernel(inline="always")
def smallest_armed_event_at_end(y_new, ybuf, P, mi, aux_new, ew, e_tmp, armed):
    """The smallest armed event function at the end ``y_new`` of a step that evaluated it
    (its end evaluation in ``ew`` and ``aux_new``, read, not made again; ``ybuf`` receives
    ``y_new`` as that evaluation projected it) and its slot: (value, slot)."""
    for i in range(NS):
        ybuf[i] = y_new[i]
    sth, cth = evaluated_state(ew, ybuf)  # ybuf projected
    event_values_at(ybuf, aux_new, P, mi, e_tmp, sth, cth)
    fc = 1.0
    k = -1
    for i in range(NEV):
        if armed[i] and e_tmp[i] < fc:
            fc = e_tmp[i]
            k = i
    return fc, k


@kernel
def refine_event(kmin, s, h, th0, e_full, method, P, mi, mf, cmd, work, evw):
    """Make the step from ``s`` end on the earliest zero of the armed event functions
    themselves (not of their continuous-extension interpolants).

    ``y_new`` holds the step of length th0 h located on the continuous extension for event
    ``kmin``; ``e_start`` / ``e_full`` are the event values at the step's start (armed ones
    > 0) and at its full length h. The step stands if, on it, the smallest armed event
    function g = min_i e_i has crossed (<= 0) by no more than EVENT_STATE_TOL of its slope;
    otherwise g's zero is located by Illinois iterations on redone steps. Using g, not
    e_kmin alone, keeps a refinement from stepping over another event. Returns
    (he, event slot, evaluations); y_new holds the step to he, and the step's end
    evaluation (``work.K[6]``, ``work.aux_new``, ``work.ew``) is that of y_new: the
    function values are read from it (the step to th0 h was evaluated at its end too).
    ``work``: the step's
    :class:`~scoutsim._core.numerics.work.StepWork`; ``evw``: its ``EventWork`` (the armed events,
    their values ``e_old`` at the step's start, the probe buffers)."""
    armed, e_start, ybuf, e_tmp = evw.armed, evw.e_old, evw.ybuf, evw.e_tmp
    y_new, ew = work.y_new, work.ew
    nf = 0
    a = 0.0
    fa = 1.0
    b = 1.0
    fb = -1.0
    for i in range(NEV):
        if armed[i] and e_start[i] < fa:
            fa = e_start[i]
        if armed[i] and e_full[i] < 0.0 and e_full[i] > fb:
            fb = e_full[i]
    th = th0
    side = 0
    k = kmin
    for _ in range(60):
        fc, kk = smallest_armed_event_at_end(y_new, ybuf, P, mi, work.aux_new, ew, e_tmp, armed)
        if kk >= 0:
            k = kk
        slope = abs(e_full[k] - e_start[k]) / h
        if fc <= 0.0 and fc >= -slope * EVENT_STATE_TOL:
            return th * h, k, nf
        a, fa, b, fb, side = illinois_update(th, fc, a, fa, b, fb, side)
        done = (b - a) * h < EVENT_TIME_TOL
        th = b if done else (a * fb - b * fa) / (fb - fa)
        err, ok, nfs = do_step(method, s, th * h, P, mi, mf, cmd, work, True, False)
        nf += nfs
        if done:
            break
    # bracket closed to EVENT_TIME_TOL: the step to b, where g <= 0
    fc, kk = smallest_armed_event_at_end(y_new, ybuf, P, mi, work.aux_new, ew, e_tmp, armed)
    if kk >= 0:
        k = kk
    return th * h, k, nf
