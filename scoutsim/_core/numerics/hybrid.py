"""Hybrid integration of one control period: adaptive steps and located events.

The event functions are in :mod:`scoutsim._core.numerics.events`, the mode transitions in
:mod:`scoutsim._core.numerics.transitions`, the run over control periods in :mod:`scoutsim._core.loop`.
Everything here is compiled with Numba. The run is a sequence of control periods; inside
each the commanded torques are held (sample-and-hold) and the plant is integrated with the
Dormand-Prince 5(4) pair under error control, forced to land on the next sample time.
Plant events (touchdown, lift-off, slide start/stop, strut, stiction stick/slip, fall) are
sign changes of event functions; each is located on the step's continuous extension by the
Illinois method to 1e-13 s and the step is then redone exactly to the event time, so
events are located in continuous time, not snapped to a step or to the control grid. The
controller sees the consequences at its next sample.

An event function is armed only after it has been seen positive, so a function that is
zero or negative right after a transition (a toe placed below ground by a massless leg, a
motor that has just broken away) does not re-trigger at once.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np
from numba.extending import overload

from ..._numba.compile_steps import inline_only
from ..._numba.jit import kernel
from ..model.evaluate import evaluate_ws
from ..model.flags import is_set
from ..model.kinematics import project_state
from ..model.layout import (
    A_ENERGY,
    A_KKT_OK,
    EV_FALL_HEIGHT,
    EV_FALL_PITCH,
    EV_MOTOR_B,
    EVC_CONE,
    EVC_GROUND,
    FLIGHT,
    MI_CONTACT_B,
    MI_MOTOR_B,
    NAUX,
    NEV,
    NMI,
    NS,
    P_MASSLESS,
    SLIDE,
    ST_FELL,
    ST_NUMERICAL_FAILURE,
    ST_RUNNING,
    STICK,
    V_SINGULAR,
)
from ..model.power_flows import power_flows
from ..model.roots import illinois_update
from . import ark
from .dopri5 import dense, step
from .events import (
    contact_event,
    event_leg,
    event_slot,
    event_values,
    is_contact_event,
    mode_violations,
    record_step,
    stamp_transition,
)
from .stats import S_HMAX, S_HMIN, S_NEVENT, S_NFEV, S_NREJECT, S_NSTEP
from .transitions import apply_event, record_friction, settle_ws

# integration methods (``run(..., method)``)
# (the user-level choice, e.g. ARK3 for Model II at the default tolerance, is made by
# ``simulation.IntegratorSettings.resolve``; run() itself maps AUTO to DOPRI5)
METHOD_AUTO = -1      # DOPRI5
METHOD_DOPRI5 = 0     # explicit Dormand-Prince 5(4): the reference
METHOD_ARK4 = 1       # additive RK 4(3), belt spring-dampers implicit (ark.py; Model II)
METHOD_ARK3 = 2       # additive RK 3(2) (ark.py, ARK3(2)4L[2]SA), same splitting

# slots of run()'s hwork array, carried between calls
HW_STEP = 0           # step-size guess [s]
HW_STIFF_VALID = 1    # 1: the ARK stiff factors sfwork are valid
HW_EVAL_KEPT = 2      # 1: the evaluation workspace holds the last evaluation of the state
NHW = 3

EVENT_TIME_TOL = 1e-13
#: an event function counts as at its zero on a step that ends within this time of it [s]
#: (measured with the function's slope over the step; docs/specification.md section 7 asks for 1e-9 s)
EVENT_STATE_TOL = 1e-10
#: a pending event counts as reached at another event's instant when its (normalised)
#: function is below this: toe height 3e-13 m, a force of 2.4e-10 N on Scout II
SIMULTANEOUS_EVENT_TOL = 1e-12
#: a stick -> slip function (normalised by body weight) this close below zero right after
#: a transition is armed: the stick rule of settle() accepts |F_t| <= mu F_n (1 + 1e-9) +
#: 1e-9 W, i.e. values down to about -2e-9
CONE_ARM_TOL = 1e-8
MAX_EVENTS_PER_PERIOD = 2000     # chattering guard: more events in one control period
MAX_STEPS_PER_PERIOD = 200000    # stall guard: more steps in one control period
#: free rows a step-record buffer must have at the start of a control period: the most
#: steps one period can record (accepted steps and steps cut at events, within the guards)
STEP_HEADROOM = MAX_STEPS_PER_PERIOD + MAX_EVENTS_PER_PERIOD + 2
# A control period starts with one step over the whole period when the carried step-size
# guess is at least this fraction of it (the command has just changed, so the guess is
# only a guess; measured on 10 s of Model II at the default tolerance: 8 % fewer
# evaluations than starting from the guess, gait metrics within 2e-5 of the reference)
WHOLE_PERIOD_FRACTION = 0.5


# --- the method, chosen when the integrator is compiled ---------------------------------
# ``method`` reaches the integrator as a compile-time constant (jit.SPECIALIZING_PARAMETERS,
# loop.run_entry). The two functions below are resolved from it while the caller is being
# compiled, so a run compiles only its own method's stepper and continuous extension
# (a Model II run at the default tolerance neither DOPRI5 nor ARK4: 10 % of the first run's
# compilation, docs/model.md "Compile time").


def method_step(method, s, h, P, mi, mf, cmd, work, eval_end, want_sf):
    """One step of ``method`` (a constant) on the step's ``work``
    (:class:`~scoutsim._core.numerics.work.StepWork`); compiled code only (:func:`_method_step`)."""
    raise NotImplementedError("method_step is resolved when a kernel is compiled")


@overload(method_step, prefer_literal=True, inline="always")
def _method_step(method, s, h, P, mi, mf, cmd, work, eval_end, want_sf):
    m = getattr(method, "literal_value", None)
    if m == METHOD_ARK4:
        def impl(method, s, h, P, mi, mf, cmd, work, eval_end, want_sf):
            return ark.step(s, h, P, mi, mf, cmd, work, eval_end, want_sf)
        return inline_only(impl)
    if m == METHOD_ARK3:
        def impl(method, s, h, P, mi, mf, cmd, work, eval_end, want_sf):
            return ark.step3(s, h, P, mi, mf, cmd, work, eval_end, want_sf)
        return inline_only(impl)
    if m == METHOD_DOPRI5:
        def impl(method, s, h, P, mi, mf, cmd, work, eval_end, want_sf):
            err, ok = step(s, h, P, mi, mf, cmd, work)
            return err, ok, 6
        return inline_only(impl)
    return None   # not a method constant: no implementation (a typing error names it)


def method_dense(method, s, y_new, h, K, th, out):
    """The continuous extension of ``method``'s last step (a constant) at the fraction
    ``th`` into ``out``; compiled code only (:func:`_method_dense`)."""
    raise NotImplementedError("method_dense is resolved when a kernel is compiled")


@overload(method_dense, prefer_literal=True, inline="always")
def _method_dense(method, s, y_new, h, K, th, out):
    m = getattr(method, "literal_value", None)
    if m == METHOD_ARK4 or m == METHOD_ARK3:
        def impl(method, s, y_new, h, K, th, out):
            ark.dense(s, y_new, h, K, th, out)
        return inline_only(impl)
    if m == METHOD_DOPRI5:
        def impl(method, s, y_new, h, K, th, out):
            dense(s, h, K, th, out)
        return inline_only(impl)
    return None


@kernel(inline="always")
def arm_jams(mi, e_now, armed):
    """Arm the jam event of every sliding toe whose slide is already at or beyond its jam
    level (``e_now``: the event values now; a slide started by a transition or a new
    command in a jammed direction, moving): it fires at once and the toe is stopped by the
    jam's impact. (Every other event is armed only once seen positive; this one cannot
    wait: beyond its jam level the slide's normal force is unbounded.)"""
    for leg in range(2):
        kj = contact_event(leg, EVC_CONE)
        if mi[MI_CONTACT_B + leg] == SLIDE and e_now[kj] <= 0.0:
            armed[kj] = True


@kernel(inline="always")
def do_step(method, s, h, P, mi, mf, cmd, work, eval_end, want_sf=True):
    """One step of the selected method (a constant, :func:`method_step`) on the step's
    ``work`` (:class:`~scoutsim._core.numerics.work.StepWork`); returns (error_norm, ok,
    evaluations). ``want_sf``: the ARK methods also refresh the stiff factors at the
    step's end (SF1)."""
    return method_step(method, s, h, P, mi, mf, cmd, work, eval_end, want_sf)


@kernel(inline="always")
def eval_k0(method, s, P, mi, mf, cmd, K0, aux, ew, SF0):
    """f(s) into K0 (and, for the ARK method, the stiff factors into SF0)."""
    return evaluate_ws(s, P, mi, mf, cmd, K0, aux, ew,
                       method >= METHOD_ARK4, SF0, True)


@kernel(inline="always")
def dense_event_values(method, s, h, th, P, mi, mf, cmd, work, evw):
    """Event functions (into evw.e_tmp) at the fraction ``th`` of the step of size ``h``
    from ``s`` to ``work.y_new``, on the method's continuous extension (one evaluation;
    ``work``: :class:`~scoutsim._core.numerics.work.StepWork`, ``evw``: its ``EventWork``)."""
    ybuf, aux_tmp, ew = evw.ybuf, evw.aux_tmp, work.ew
    method_dense(method, s, work.y_new, h, work.K, th, ybuf)
    evaluate_ws(ybuf, P, mi, mf, cmd, work.tmp, aux_tmp, ew, False, ew[3],
                True)
    project_state(ybuf, P, mi, mf)
    event_values(ybuf, aux_tmp, P, mi, evw.e_tmp)


@kernel(inline="always")
def smallest_armed_event(y, ybuf, P, mi, mf, cmd, tmp, aux_tmp, ew, e_tmp, armed):
    """The smallest armed event function at state ``y`` (evaluated on a projected copy)
    and its slot: (value, slot)."""
    for i in range(NS):
        ybuf[i] = y[i]
    project_state(ybuf, P, mi, mf)
    evaluate_ws(ybuf, P, mi, mf, cmd, tmp, aux_tmp, ew, False, ew[3], True)
    event_values(ybuf, aux_tmp, P, mi, e_tmp)
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
    (he, event slot, evaluations); y_new holds the step to he. ``work``: the step's
    :class:`~scoutsim._core.numerics.work.StepWork`; ``evw``: its ``EventWork`` (the armed events,
    their values ``e_old`` at the step's start, the probe buffers)."""
    armed, e_start, ybuf, aux_tmp, e_tmp = evw.armed, evw.e_old, evw.ybuf, evw.aux_tmp, \
        evw.e_tmp
    y_new, tmp, ew = work.y_new, work.tmp, work.ew
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
        fc, kk = smallest_armed_event(y_new, ybuf, P, mi, mf, cmd, tmp, aux_tmp, ew, e_tmp,
                                      armed)
        nf += 1
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
    fc, kk = smallest_armed_event(y_new, ybuf, P, mi, mf, cmd, tmp, aux_tmp, ew, e_tmp, armed)
    nf += 1
    if kk >= 0:
        k = kk
    return th * h, k, nf


#: advance()'s scratch arrays (``imp``: the impulses of a touchdown), and the step recording (``steps``, ``stepc``:
#: :func:`~scoutsim._core.numerics.events.record_step`), the state before a transition
#: (``s_before``, for the event records) and the work-energy accounting (``energy``: the
#: accumulated energies, layout ``EN_*``, empty when the run does not account; ``ew_e``
#: an evaluation workspace of its own and ``y_e, ds_e, aux_e, p_e`` its scratch:
#: :func:`accumulate_energy`)
AdvanceScratch = namedtuple("AdvanceScratch",
                            "e_end pending mi_before s_before steps stepc energy ew_e y_e "
                            "ds_e aux_e p_e imp")

#: Gauss-Legendre nodes and weights on [0, 1] (3 points, exact for polynomials of degree 5)
GAUSS_NODES = (0.5 - 0.15 ** 0.5, 0.5, 0.5 + 0.15 ** 0.5)
GAUSS_WEIGHTS = (5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0)


@kernel
def accumulate_energy(method, s, y_new, h, K, P, mi, mf, cmd, sc):
    """Add the energy of every power flow (model/power_flows.py) over the step of size ``h``
    from ``s`` to ``y_new`` to ``sc.energy``: 3-point Gauss-Legendre quadrature on the
    method's continuous extension, with the step's modes and held commands. Uses its own
    evaluation workspace, so the integration is unchanged, bit for bit."""
    ew = sc.ew_e
    y = sc.y_e
    p = sc.p_e
    for g in range(3):
        method_dense(method, s, y_new, h, K, GAUSS_NODES[g], y)
        project_state(y, P, mi, mf)
        evaluate_ws(y, P, mi, mf, cmd, sc.ds_e, sc.aux_e, ew, False, ew[3],
                    True)
        power_flows(y, sc.ds_e, sc.aux_e, P, mi, ew[0], ew[1], p)
        w = GAUSS_WEIGHTS[g] * h
        for i in range(p.shape[0]):
            sc.energy[i] += w * p[i]


@kernel
def advance(t, t_end, plant, hwork, aux, log, nev, method, work, evw, sc, fresh=False):
    """Integrate from t to t_end (one control period) with events.

    ``plant`` (:class:`~scoutsim._core.numerics.work.Plant`): the state ``s``, advanced in place,
    with its parameters, modes and held commands; ``aux``: the outputs at ``s``; ``log``
    (``EventLog``): the event records and the statistics, ``nev`` records in use;
    ``work`` (``StepWork``): the steps' arrays and tolerances (``method``: METHOD_DOPRI5 or
    an ARK method, whose stiff factors are ``work.SF0`` / ``SF1``); ``evw`` (``EventWork``):
    the event functions' arrays; ``sc``: :data:`AdvanceScratch`. hwork[HW_STEP] carries the
    step-size guess between calls. ``fresh``: K[0] and aux already hold f(s) and its
    outputs (and SF0 usable stiff factors). Returns (t, nev, status)."""
    s, P, mi, mf, cmd = plant
    ev, stats = log
    K, y_new, aux_new, ew, SF0, SF1 = work.K, work.y_new, work.aux_new, work.ew, work.SF0, \
        work.SF1
    armed, e_old, e_new = evw.armed, evw.e_old, evw.e_new
    imp = sc.imp
    K0 = K[0]
    expo = -0.25 if method == METHOD_ARK4 else (-1.0 / 3.0 if method == METHOD_ARK3 else -0.2)
    nfail = 0
    # stall guards (a run must end with an outcome, never loop without end): events and
    # steps within one control period
    n_events_here = 0
    n_steps_here = 0
    e_end = sc.e_end
    pending = sc.pending
    mi_before = sc.mi_before
    e_tmp = evw.e_tmp
    if not fresh:
        # (if fresh, K0 and aux were just computed at s by settle(); the ARK stiff factors
        # SF0 are kept from the end of the previous step: any splitting matrix keeps the
        # method's order)
        project_state(s, P, mi, mf)
        eval_k0(method, s, P, mi, mf, cmd, K0, aux, ew, SF0)
        stats[S_NFEV] += 1
    event_values(s, aux, P, mi, e_old)
    for i in range(NEV):
        if e_old[i] > 0.0:
            armed[i] = True
    arm_jams(mi, e_old, armed)
    h = hwork[HW_STEP]
    if h >= WHOLE_PERIOD_FRACTION * (t_end - t):
        h = t_end - t
    while t < t_end:
        remaining = t_end - t
        last = False
        if h >= remaining * (1.0 - 1e-12):
            h = remaining
            last = True
        # the ARK splitting matrix is refreshed at every accepted step and after every mode
        # change (measured: refreshing every 8th step saves ~2 % of a Model II run but
        # changes the step sequence, so 10 s gait metrics move by ~1e-3 at rtol 1e-5)
        err, ok, nf = do_step(method, s, h, P, mi, mf, cmd, work, False, True)
        stats[S_NFEV] += nf
        if not ok or not (err == err):
            h *= 0.25
            nfail += 1
            if h < 1e-14 or nfail > 60:
                return t, nev, ST_NUMERICAL_FAILURE
            continue
        if err > 1.0:
            stats[S_NREJECT] += 1
            fac = 0.9 * err ** expo
            if fac < 0.2:
                fac = 0.2
            h *= fac
            if h < 1e-14:
                return t, nev, ST_NUMERICAL_FAILURE
            continue
        nfail = 0
        project_state(y_new, P, mi, mf)
        event_values(y_new, aux_new, P, mi, e_new)
        # earliest triggered event
        kmin = -1
        thmin = 2.0
        th_hop = 2.0
        for i in range(NEV):
            e_end[i] = e_new[i]
        for k in range(NEV):
            hop = (not armed[k] and e_end[k] < 0.0 and is_contact_event(k)
                   and event_slot(k) == EVC_GROUND and mi[MI_CONTACT_B + event_leg(k)] == FLIGHT
                   and e_old[k] > -SIMULTANEOUS_EVENT_TOL and not is_set(P[P_MASSLESS]))
            if (armed[k] or hop) and e_end[k] < 0.0:
                # Illinois on the continuous extension, bracket [0, 1]
                a = 0.0
                fa = e_old[k]
                b = 1.0
                fb = e_end[k]
                if hop:
                    # a toe that left the ground at the start of this step (its touchdown
                    # is armed only once it is seen above the ground) and ends it below:
                    # a hop shorter than the step. Look for an instant above the ground
                    # (halving towards the start): the step is then cut there (below),
                    # the toe is seen above the ground and its landing is located like any
                    # touchdown; none: it never rose, and the step goes on (settle_ws has
                    # decided it stays in flight)
                    thp = 0.5
                    for _ in range(40):
                        dense_event_values(method, s, h, thp, P, mi, mf, cmd, work, evw)
                        stats[S_NFEV] += 1
                        if e_tmp[k] > 0.0:
                            if thp < th_hop:
                                th_hop = thp
                            break
                        thp *= 0.5
                    continue
                if fa <= 0.0:
                    th = 0.0
                else:
                    side = 0
                    th = 1.0
                    for _ in range(100):
                        th = (a * fb - b * fa) / (fb - fa)
                        dense_event_values(method, s, h, th, P, mi, mf, cmd, work, evw)
                        stats[S_NFEV] += 1
                        fc = e_tmp[k]
                        a, fa, b, fb, side = illinois_update(th, fc, a, fa, b, fb, side)
                        if (b - a) * h < EVENT_TIME_TOL or fc == 0.0:
                            break
                    th = b
                if th < thmin:
                    thmin = th
                    kmin = k
        if th_hop < 1.0 and th_hop < thmin:
            # a hop shorter than the step, before any other event: cut the step where the
            # toe is above the ground
            h *= th_hop
            continue
        if kmin >= 0:
            # redo the step exactly to the event time
            he = thmin * h
            if he > 0.0:
                err, ok, nf = do_step(method, s, he, P, mi, mf, cmd, work, True, False)
                stats[S_NFEV] += nf
                # The continuous extension is only an interpolant: on a stiff component (a
                # gear rate in the belt transient after a touchdown, under ARK's cubic
                # Hermite) its zero can lie microseconds from that of the step itself, and
                # a transition applied there is applied to the wrong state (a joint "at
                # rest" that still turns). Check the event function on the redone step and,
                # if it is not at its zero, locate the zero on the steps themselves.
                he, kmin, nf = refine_event(kmin, s, h, thmin, e_end, method, P, mi, mf, cmd,
                                            work, evw)
                stats[S_NFEV] += nf
                if sc.energy.shape[0] > 0:
                    accumulate_energy(method, s, y_new, he, K, P, mi, mf, cmd, sc)
                for i in range(NS):
                    s[i] = y_new[i]
                t = t + he
                if sc.stepc[1] != 0:   # (tested here: no call when steps are not recorded)
                    record_step(sc.steps, sc.stepc, t, s, mi)
            stats[S_NSTEP] += 1
            project_state(s, P, mi, mf)
            evaluate_ws(s, P, mi, mf, cmd, K0, aux, ew, False, ew[3], True)
            n_events_here += 1
            if n_events_here > MAX_EVENTS_PER_PERIOD:
                return t, nev, ST_NUMERICAL_FAILURE
            # transition audit: mechanical energy before the transition
            nev0 = nev
            e_before = aux[A_ENERGY]
            s_before = sc.s_before
            for i in range(NS):
                s_before[i] = s[i]
            # apply the event, then any other armed event that has also been reached at
            # this instant (simultaneous touchdowns of a pitch-free landing, ...): reached
            # means crossing within the step (negative at its full length) and within
            # SIMULTANEOUS_EVENT_TOL of zero, on either side, so that which of two
            # simultaneous events rounding puts first decides nothing; a function at zero
            # that moves away (a massless toe re-placed at ground level as it lifts off)
            # is not an event
            for i in range(NEV):
                pending[i] = armed[i]
            kcur = kmin
            for _ in range(NEV):
                stats[S_NEVENT] += 1
                pending[kcur] = False
                for i in range(NMI):
                    mi_before[i] = mi[i]
                nev, ok = apply_event(kcur, t, s, P, mi, mf, aux, ev, nev, stats, imp)
                if kcur == EV_FALL_HEIGHT or kcur == EV_FALL_PITCH:
                    stamp_transition(ev, nev0, nev, e_before, e_before, 0, s_before, s)
                    return t, nev, ST_FELL
                if not ok:
                    stamp_transition(ev, nev0, nev, e_before, np.nan, V_SINGULAR, s_before, s)
                    return t, nev, ST_NUMERICAL_FAILURE
                nev = settle_ws(t, s, P, mi, mf, cmd, K0, aux, log, nev, ew, False)
                stats[S_NFEV] += 1
                if not is_set(aux[A_KKT_OK]):
                    stamp_transition(ev, nev0, nev, e_before, np.nan, V_SINGULAR, s_before, s)
                    return t, nev, ST_NUMERICAL_FAILURE
                event_values(s, aux, P, mi, e_old)
                kcur = -1
                for i in range(NEV):
                    if pending[i] and e_old[i] <= SIMULTANEOUS_EVENT_TOL and e_end[i] < 0.0:
                        # only if the slot still means the same thing (its leg's modes
                        # unchanged)
                        same = True
                        if is_contact_event(i):
                            lg = event_leg(i)
                            same = mi[MI_CONTACT_B + lg] == mi_before[MI_CONTACT_B + lg]
                        elif i < EV_FALL_HEIGHT:
                            lg = i - EV_MOTOR_B
                            same = mi[MI_MOTOR_B + lg] == mi_before[MI_MOTOR_B + lg]
                        if same:
                            kcur = i
                            break
                if kcur < 0:
                    break
            stamp_transition(ev, nev0, nev, e_before, aux[A_ENERGY],
                             mode_violations(s, K0, aux, P, mi), s_before, s)
            for i in range(NEV):
                armed[i] = e_old[i] > 0.0
            for leg in range(2):
                # a toe that sticks on the edge of the friction cone (a slide come to rest
                # with the friction at mu F_n) starts with its stick -> slip function at
                # zero, within the stick rule's tolerance: armed, so that it fires at once
                # if the force leaves the cone (otherwise it could leave it unnoticed)
                kc = contact_event(leg, EVC_CONE)
                if mi[MI_CONTACT_B + leg] == STICK and e_old[kc] > -CONE_ARM_TOL:
                    armed[kc] = True
            arm_jams(mi, e_old, armed)
            if method >= METHOD_ARK4:
                # stiff factors at the post-event state (settle() filled K0 and aux)
                eval_k0(method, s, P, mi, mf, cmd, K0, aux, ew, SF0)
                stats[S_NFEV] += 1
            if he > 0.0 and he < h:
                h = max(he, 1e-6)
            if t_end - t < 1e-12:
                t = t_end
            continue
        # accept
        stats[S_NSTEP] += 1
        n_steps_here += 1
        if n_steps_here > MAX_STEPS_PER_PERIOD:
            return t, nev, ST_NUMERICAL_FAILURE
        if h < stats[S_HMIN]:
            stats[S_HMIN] = h
        if h > stats[S_HMAX]:
            stats[S_HMAX] = h
        if sc.energy.shape[0] > 0:
            accumulate_energy(method, s, y_new, h, K, P, mi, mf, cmd, sc)
        for i in range(NS):
            s[i] = y_new[i]
            K0[i] = K[6, i]
        if method >= METHOD_ARK4:
            for i in range(NS):
                for j in range(2 * ark.NSTIFF):
                    SF0[i, j] = SF1[i, j]
        for i in range(NAUX):
            aux[i] = aux_new[i]
        for i in range(NEV):
            e_old[i] = e_new[i]
            if e_new[i] > 0.0:
                armed[i] = True
        record_friction(aux, P, mi, stats)
        if last:
            t = t_end
        else:
            t = t + h
        if sc.stepc[1] != 0:
            record_step(sc.steps, sc.stepc, t, s, mi)
        fac = 5.0 if err == 0.0 else 0.9 * err ** expo
        if fac > 5.0:
            fac = 5.0
        if fac < 0.2:
            fac = 0.2
        hnext = h * fac
        if last:
            # keep the unclipped guess for the next control period
            hnext = max(hnext, hwork[HW_STEP] if hwork[HW_STEP] < 10 * h else h)
        h = hnext
        hwork[HW_STEP] = h
    hwork[HW_STEP] = h if h > 1e-7 else 1e-7
    return t, nev, ST_RUNNING
