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

The method's step and continuous extension are in :mod:`scoutsim._core.numerics.stepper`,
the location of an event's zero within a step in :mod:`scoutsim._core.numerics.event_location`,
the energy of the power flows over a step in :mod:`scoutsim._core.numerics.step_energy`;
here are the step loop of one control period and the arming and application of the events.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from ..._numba.jit import kernel
from ..model.evaluate import evaluate_ws, evaluated_state
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
from ..model.roots import illinois_update
from . import ark, tangent_call
from .event_location import EVENT_TIME_TOL, dense_event_values, refine_event
from .events import (
    contact_event,
    event_leg,
    event_slot,
    event_values,
    event_values_at,
    is_contact_event,
    mode_violations,
    record_step,
    stamp_transition,
)
from .stats import S_HMAX, S_HMIN, S_NEVENT, S_NFEV, S_NREJECT, S_NSTEP
from .step_energy import accounting, power_at, take_step
from .stepper import METHOD_ARK3, METHOD_ARK4, do_step, eval_k0
from .tangent_work import carrying
from .transitions import apply_event, record_friction, settle_ws

# slots of run()'s hwork array, carried between calls
HW_STEP = 0  # step-size guess [s]
HW_STIFF_VALID = 1  # 1: the ARK stiff factors sfwork are valid
HW_EVAL_KEPT = 2  # 1: the evaluation workspace holds the last evaluation of the state
NHW = 3

#: a pending event counts as reached at another event's instant when its (normalised)
#: function is below this: toe height 3e-13 m, a force of 2.4e-10 N on Scout II
SIMULTANEOUS_EVENT_TOL = 1e-12
#: a stick -> slip function (normalised by body weight) this close below zero right after
#: a transition is armed: the stick rule of settle() accepts |F_t| <= mu F_n (1 + 1e-9) +
#: 1e-9 W, i.e. values down to about -2e-9
CONE_ARM_TOL = 1e-8
MAX_EVENTS_PER_PERIOD = 2000  # chattering guard: more events in one control period
MAX_STEPS_PER_PERIOD = 200000  # stall guard: more steps in one control period
#: free rows a step-record buffer must have at the start of a control period: the most
#: steps one period can record (accepted steps and steps cut at events, within the guards)
STEP_HEADROOM = MAX_STEPS_PER_PERIOD + MAX_EVENTS_PER_PERIOD + 2
# A control period starts with one step over the whole period when the carried step-size
# guess is at least this fraction of it (the command has just changed, so the guess is
# only a guess; measured on 10 s of Model II at the default tolerance: 8 % fewer
# evaluations than starting from the guess, gait metrics within 2e-5 of the reference)
WHOLE_PERIOD_FRACTION = 0.5


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


#: advance()'s scratch arrays (``imp``: the impulses of a touchdown), and the step recording (``steps``, ``stepc``:
#: :func:`~scoutsim._core.numerics.events.record_step`), the state before a transition
#: (``s_before``, for the event records) and the work-energy accounting (``energy``: the
#: accumulated energies, layout ``EN_*``, empty when the run does not account; each step's
#: share: :mod:`~scoutsim._core.numerics.step_energy`)
#: ``tan``: the sensitivities the run carries
#: (:data:`~scoutsim._core.numerics.tangent_work.TangentPack`; no columns when it carries none)
AdvanceScratch = namedtuple(
    "AdvanceScratch", "e_end pending mi_before s_before steps stepc energy imp tan"
)


# (a kernel of its own: inlined at Numba's IR level into the run loop, the run loop's
# stores of the evaluation the sensors read between samples, ``cb.last``, were lost, the
# motion the same (tests/control/test_sensors.py); with that copy in a kernel of its own
# the inlined loop is no faster: docs/explanation/performance.md)
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
    K, y_new, aux_new, ew, SF0, SF1 = work.K, work.y_new, work.aux_new, work.ew, work.SF0, work.SF1
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
    counting = accounting(work.energy)  # (the run's energies sc.energy have the same size)
    tan = sc.tan
    if not fresh:
        # (if fresh, K0 and aux were just computed at s by settle(); the ARK stiff factors
        # SF0 are kept from the end of the previous step: any splitting matrix keeps the
        # method's order)
        project_state(s, P, mi, mf)
        if carrying(tan):
            tangent_call.projection(s, P, mi, mf, tan)
        eval_k0(method, s, P, mi, mf, cmd, K0, aux, ew, SF0)
        stats[S_NFEV] += 1
    if counting:  # the power flows at the first step's start (ew holds K0's)
        power_at(K0, P, mi, ew, work.energy.p_start)
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
            fac = 0.9 * err**expo
            if fac < 0.2:
                fac = 0.2
            h *= fac
            if h < 1e-14:
                return t, nev, ST_NUMERICAL_FAILURE
            continue
        nfail = 0
        # the step's end was evaluated last (K[6], aux_new): y_new projected as that
        # evaluation projected it, the event functions with its pitch's sin / cos
        sth, cth = evaluated_state(ew, y_new)
        event_values_at(y_new, aux_new, P, mi, e_new, sth, cth)
        # earliest triggered event
        kmin = -1
        thmin = 2.0
        th_hop = 2.0
        for i in range(NEV):
            e_end[i] = e_new[i]
        for k in range(NEV):
            hop = (
                not armed[k]
                and e_end[k] < 0.0
                and is_contact_event(k)
                and event_slot(k) == EVC_GROUND
                and mi[MI_CONTACT_B + event_leg(k)] == FLIGHT
                and e_old[k] > -SIMULTANEOUS_EVENT_TOL
                and not is_set(P[P_MASSLESS])
            )
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
                he, kmin, nf = refine_event(
                    kmin, s, h, thmin, e_end, method, P, mi, mf, cmd, work, evw
                )
                stats[S_NFEV] += nf
                if counting:
                    take_step(he, work.energy, sc.energy)
                if carrying(tan):
                    tangent_call.flow(method, s, he, P, mi, mf, cmd, SF0, tan)
                for i in range(NS):
                    s[i] = y_new[i]
                t = t + he
                if sc.stepc[1] != 0:  # (tested here: no call when steps are not recorded)
                    record_step(sc.steps, sc.stepc, t, s, mi)
            stats[S_NSTEP] += 1
            if he > 0.0:
                # the step redone to the event was evaluated at its end last (K[6], aux_new
                # and ew, refine_event): the state as that evaluation projected it
                evaluated_state(ew, s)
                for i in range(NS):
                    K0[i] = K[6, i]
                for i in range(NAUX):
                    aux[i] = aux_new[i]
            else:
                project_state(s, P, mi, mf)
                if carrying(tan):
                    tangent_call.projection(s, P, mi, mf, tan)
                evaluate_ws(s, P, mi, mf, cmd, K0, aux, ew, False, ew[3], True)
                stats[S_NFEV] += 1
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
                if carrying(tan):
                    tangent_call.snapshot(s, mi, mf, K0, tan)
                nev, ok = apply_event(kcur, t, s, P, mi, mf, aux, ev, nev, stats, imp)
                if kcur == EV_FALL_HEIGHT or kcur == EV_FALL_PITCH:
                    stamp_transition(ev, nev0, nev, e_before, e_before, 0, s_before, s)
                    return t, nev, ST_FELL
                if not ok:
                    stamp_transition(ev, nev0, nev, e_before, np.nan, V_SINGULAR, s_before, s)
                    return t, nev, ST_NUMERICAL_FAILURE
                nev = settle_ws(t, s, P, mi, mf, cmd, K0, aux, log, nev, ew, False)
                stats[S_NFEV] += 1
                if carrying(tan):
                    tangent_call.reset(kcur, t, mi, K0, P, cmd, tan)
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
            stamp_transition(
                ev,
                nev0,
                nev,
                e_before,
                aux[A_ENERGY],
                mode_violations(s, K0, aux, P, mi),
                s_before,
                s,
            )
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
            if counting:  # the power flows after the event (ew holds K0's)
                power_at(K0, P, mi, ew, work.energy.p_start)
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
        if counting:
            take_step(h, work.energy, sc.energy)
        if carrying(tan):
            tangent_call.flow(method, s, h, P, mi, mf, cmd, SF0, tan)
            if last:
                tangent_call.margin(h, armed, e_old, e_new, tan)
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
        fac = 5.0 if err == 0.0 else 0.9 * err**expo
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
