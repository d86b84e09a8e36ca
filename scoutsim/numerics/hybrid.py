"""Hybrid integration: adaptive steps, located events, mode transitions, control samples.

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

import math
from collections import namedtuple

import numpy as np

from ..jit import allocating, kernel
from ..model.dynamics import (evaluate_command_change, evaluate_ws, impact, leg_damping,
                              project_state)
from ..model.layout import (
    A_ENERGY, A_FAX, A_GN, A_GT, A_HOLD, A_KKT_OK, A_OMEGA_M, A_SLIP_V, A_STRUT, A_TOE_X,
    A_TOE_Y,
    EK_FALL, EK_LIFTOFF, EK_MOTOR_SLIP,
    EK_MOTOR_STICK, EK_SLIDE_START, EK_STICK, EK_STRUT_END, EK_STRUT_START, EK_TOUCHDOWN,
    EV_FALL_HEIGHT, EV_FALL_PITCH, EV_MOTOR_B, EVR_E_AFTER, EVR_E_BEFORE, EVR_VIOLATIONS,
    FLIGHT, IL_B, ITH, IY, MF_ANCHOR_B, MI_CONTACT_B,
    MI_MOTOR_B, MI_SLIDE_DIR_B, MODEL_II, NAUX, NMI, NAUX_LEG, NEV, NEV_CONTACT, NS,
    NQ, P_G, P_K, P_L, P_L0, P_LEG_FRIC_SIDE, P_MASSLESS, P_ML, P_MODEL, P_MT, P_MU, P_N, P_NP,
    P_TAU_S, P_THETA_LIM,
    P_TORSO_H, P_TORSO_LEN, SLIDE, SLIP_NEG, SLIP_POS, ST_FELL,
    ST_NUMERICAL_FAILURE, ST_RUNNING, STICK, STRUT, STUCK, V_GROUND_PULLS, V_OUTSIDE_CONE,
    V_SINGULAR, V_SLIDE_DIRECTION, V_SLIDE_NOT_PUSHING, V_SLIP_DIRECTION,
    V_BEYOND_STOP, V_STICTION_EXCEEDED, V_STRUT_COMPRESSED, V_TOE_BELOW_GROUND,
    V_TOE_ENTERS_GROUND, SLIDE_CAUSE_LEG_PUSHES, SLIDE_CAUSE_CONE, SLIDE_CAUSE_NO_PIN_IMPULSE,
    SLIDE_CAUSE_STUB,
)
from . import ark
from .dopri5 import dense, eval_workspace, step

# integration methods (``run(..., method)``)
# (the user-level choice, e.g. ARK3 for Model II at the default tolerance, is made by
# ``simulation.IntegratorSettings.resolve``; run() itself maps AUTO to DOPRI5)
METHOD_AUTO = -1      # DOPRI5
METHOD_DOPRI5 = 0     # explicit Dormand-Prince 5(4): the reference
METHOD_ARK4 = 1       # additive RK 4(3), belt spring-dampers implicit (ark.py; Model II)
METHOD_ARK3 = 2       # additive RK 3(2) (ark.py, ARK3(2)4L[2]SA), same splitting

# integrator statistics slots
S_NFEV = 0
S_NSTEP = 1
S_NREJECT = 2
S_NEVENT = 3
S_NEND_SLIDE = 4      # end-of-stance slides (SPEC.md 3 consistency case)
S_NSTRUT = 5
S_MAX_FRICTION = 6    # largest |Ft|/Fn in stance with Fn above 5 % body weight
S_MAX_IMPULSE_RATIO = 7
S_HMIN = 8
S_HMAX = 9
S_NSTUB = 10          # toe-stub slides (toe_enters_ground)
NSTAT = 11
#: result.stats keys, in slot order
STAT_NAMES = ("rhs_evaluations", "steps", "rejected_steps", "events", "end_of_stance_slides",
              "strut_phases", "max_friction_ratio", "max_impact_impulse_ratio", "min_step_s",
              "max_step_s", "toe_stub_slides")

# slots of run()'s hwork array, carried between calls
HW_STEP = 0           # step-size guess [s]
HW_STIFF_VALID = 1    # 1: the ARK stiff factors sfwork are valid
HW_EVAL_KEPT = 2      # 1: the evaluation workspace holds the last evaluation of the state
NHW = 3

EVENT_TIME_TOL = 1e-13
#: an event function counts as at its zero on a step that ends within this time of it [s]
#: (measured with the function's slope over the step; SPEC.md 7 asks for 1e-9 s)
EVENT_STATE_TOL = 1e-10
#: a pending event counts as reached at another event's instant when its (normalised)
#: function is below this: toe height 3e-13 m, a force of 2.4e-10 N on Scout II
SIMULTANEOUS_EVENT_TOL = 1e-12
#: Speeds below which a sliding toe [m/s] or a slipping motor joint [rad/s, motor side] that
#: moves against its recorded direction counts as at rest (the event that stops it is
#: located to EVENT_TIME_TOL, so the rate at a located zero crossing is a little off zero,
#: by at most ~1e-6 for Scout II's largest accelerations).
SLIDE_SPEED_TOL = 1e-6
MOTOR_SPEED_TOL = 1e-4
#: a stick -> slip function (normalised by body weight) this close below zero right after
#: a transition is armed: the stick rule of settle() accepts |F_t| <= mu F_n (1 + 1e-9) +
#: 1e-9 W, i.e. values down to about -2e-9
CONE_ARM_TOL = 1e-8
#: a pinned leg at its stop counts as extending beyond this leg-length rate [m/s]
LEG_STOP_SPEED_TOL = 1e-6
#: a toe at ground level moving down faster than this [m/s] enters the ground
TOE_REST_SPEED = 1e-7
#: a toe at ground level that would rise at most this height [m] before
#: its (downward) acceleration brings it back counts as pressed into the ground: the touchdown
#: event of so short a hop (microseconds) can fall within one step and be missed
TOE_HOP_TOL = 1e-9
#: a toe in flight counts as at ground level within this height [m] (a released strut's toe
#: is lifted by its ~3e-8 m of length drift)
TOE_AT_GROUND_TOL = 1e-7
MAX_EVENTS_PER_PERIOD = 2000     # chattering guard: more events in one control period
MAX_STEPS_PER_PERIOD = 200000    # stall guard: more steps in one control period
# A control period starts with one step over the whole period when the carried step-size
# guess is at least this fraction of it (the command has just changed, so the guess is
# only a guess; measured on 10 s of Model II at the default tolerance: 8 % fewer
# evaluations than starting from the guess, gait metrics within 2e-5 of the reference)
WHOLE_PERIOD_FRACTION = 0.5


@kernel
def body_weight(P):
    return (P[P_MT] + 2.0 * P[P_NP] * P[P_ML]) * P[P_G]


@kernel
def event_values(s, aux, P, mi, out):
    """Event functions of the current modes; an event happens when one goes below zero."""
    W = body_weight(P)
    l0 = P[P_L0]
    massless = P[P_MASSLESS] > 0.5
    coulomb = P[P_MU] < 1e300
    for i in range(NEV):
        out[i] = 1.0
    for leg in range(2):
        o = leg * NAUX_LEG
        e = leg * NEV_CONTACT
        mode = mi[MI_CONTACT_B + leg]
        if mode == FLIGHT:
            out[e] = aux[o + A_TOE_Y] / l0
        elif mode == STICK:
            out[e] = aux[o + A_GN] / W
            if not massless:
                out[e + 1] = (l0 - s[IL_B + leg]) / l0
            if coulomb:
                out[e + 2] = (P[P_MU] * aux[o + A_GN] - abs(aux[o + A_GT])) / W
        elif mode == SLIDE:
            out[e] = aux[o + A_GN] / W
            if coulomb:
                out[e + 1] = aux[o + A_SLIP_V] * mi[MI_SLIDE_DIR_B + leg]
        elif mode == STRUT:
            out[e] = aux[o + A_GN] / W
            out[e + 1] = aux[o + A_STRUT] / W
        if int(P[P_MODEL]) == MODEL_II and P[P_TAU_S] > 0.0:
            mm = mi[MI_MOTOR_B + leg]
            if mm == STUCK:
                out[EV_MOTOR_B + leg] = (P[P_TAU_S] - abs(aux[o + A_HOLD])) / P[P_TAU_S]
            else:
                out[EV_MOTOR_B + leg] = aux[o + A_OMEGA_M] * mm / P[P_N]
    th = s[2]
    a = 0.5 * P[P_TORSO_LEN]
    b = 0.5 * P[P_TORSO_H]
    out[EV_FALL_HEIGHT] = s[1] - a * abs(math.sin(th)) - b * abs(math.cos(th))
    out[EV_FALL_PITCH] = P[P_THETA_LIM] - abs(th)


@kernel
def log_event(ev, nev, t, kind, leg, v1, v2, v3):
    if nev < ev.shape[0]:
        ev[nev, 0] = t
        ev[nev, 1] = kind
        ev[nev, 2] = leg
        ev[nev, 3] = v1
        ev[nev, 4] = v2
        ev[nev, 5] = v3
        ev[nev, EVR_E_BEFORE] = np.nan
        ev[nev, EVR_E_AFTER] = np.nan
        ev[nev, EVR_VIOLATIONS] = 0.0
    return nev + 1


@kernel
def mode_violations(s, ds, aux, P, mi):
    """Bit mask (layout.V_*) of the mode invariants that the state ``s``, its derivative
    ``ds`` and outputs ``aux`` (an evaluation of ``s`` in modes ``mi``) and the modes
    violate: after every
    transition the modes must agree with the velocities and forces. The tolerances are
    those of the transition rules, widened by a margin for rounding (1e-6 of body weight
    for forces)."""
    W = body_weight(P)
    ftol = 1e-6 * W
    coulomb = P[P_MU] < 1e300
    bits = 0
    if aux[A_KKT_OK] < 0.5:
        bits |= V_SINGULAR
    for leg in range(2):
        o = leg * NAUX_LEG
        mode = mi[MI_CONTACT_B + leg]
        gn = aux[o + A_GN]
        if mode == STICK or mode == STRUT:
            if gn < -ftol:
                bits |= V_GROUND_PULLS
            if mode == STICK and coulomb and (abs(aux[o + A_GT]) >
                                              P[P_MU] * gn * (1.0 + 1e-6) + ftol):
                bits |= V_OUTSIDE_CONE
            if mode == STRUT and aux[o + A_STRUT] < -ftol:
                bits |= V_STRUT_COMPRESSED
            if mode == STICK and s[IL_B + leg] > P[P_L0] + 1e-6:
                # (1 um: a strut's length is Baumgarte-stabilised, not projected, and
                # drifts by ~3e-8 m before it ends)
                bits |= V_BEYOND_STOP
        elif mode == SLIDE:
            if coulomb and aux[o + A_SLIP_V] * mi[MI_SLIDE_DIR_B + leg] < -SLIDE_SPEED_TOL:
                bits |= V_SLIDE_DIRECTION
            if ((aux[o + A_FAX] < -ftol or gn < -ftol)
                    and not slide_toe_pressed(s, ds, aux, P, leg)):
                bits |= V_SLIDE_NOT_PUSHING
        elif P[P_MASSLESS] < 0.5:
            # (a massless leg is placed kinematically at its touchdown angle in flight, which
            # can put its toe below the ground just after lift-off: the passive model's
            # convention, SPEC.md 2; it touches down when the toe comes down through it)
            if aux[o + A_TOE_Y] < -1e-9:
                bits |= V_TOE_BELOW_GROUND
            if flight_toe_enters_ground(s, ds, aux, P, leg):
                bits |= V_TOE_ENTERS_GROUND
        if int(P[P_MODEL]) == MODEL_II and P[P_TAU_S] > 0.0:
            mm = mi[MI_MOTOR_B + leg]
            if mm == STUCK:
                if abs(aux[o + A_HOLD]) > P[P_TAU_S] * (1.0 + 1e-6):
                    bits |= V_STICTION_EXCEEDED
            elif aux[o + A_OMEGA_M] * mm < -MOTOR_SPEED_TOL:
                bits |= V_SLIP_DIRECTION
    return bits


@kernel
def stamp_transition(ev, nev0, nev, e_before, e_after, bits):
    """Write the transition audit (energies before / after [J], violated invariants) into
    the event records nev0 .. nev-1 logged while one transition was processed."""
    for j in range(nev0, min(nev, ev.shape[0])):
        ev[j, EVR_E_BEFORE] = e_before
        ev[j, EVR_E_AFTER] = e_after
        ev[j, EVR_VIOLATIONS] = bits


@kernel
def stance_leg_rate(s, P, leg):
    """dl/dt [m/s] of a leg whose toe is pinned: minus the hip velocity along the leg."""
    sL = (2.0 * leg - 1.0) * P[P_L]
    th = s[2]
    g = th + s[3 + leg]
    hvx = s[NQ] - sL * math.sin(th) * s[NQ + 2]
    hvy = s[NQ + 1] + sL * math.cos(th) * s[NQ + 2]
    return -(hvx * math.sin(g) - hvy * math.cos(g))


#: toe_enters_ground results
TOE_STAYS = 0          # the toe does not move into the ground
TOE_PRESSED = 1        # at rest vertically at ground level, accelerating into the ground
TOE_ENTERS = 2         # moving into the ground faster than TOE_REST_SPEED


@kernel
def toe_vertical_motion(s, ds, P, leg, ld):
    """Rate [m/s] and acceleration [m/s^2] of the height of the toe of ``leg`` moving as in
    flight: leg-length rate ``ld`` [m/s] (the flight rate) and the flight relaxation's
    ldd = -k ld / c (exact for a constant damper without leg friction; first order
    otherwise)."""
    sL = (2.0 * leg - 1.0) * P[P_L]
    ll = s[IL_B + leg]
    th = s[ITH]
    dth = s[NQ + ITH]
    ddth = ds[NQ + ITH]
    g = th + s[3 + leg]
    dg = dth + s[NQ + 3 + leg]
    ddg = ddth + ds[NQ + 3 + leg]
    sg = math.sin(g)
    cg = math.cos(g)
    ldd = 0.0
    c = leg_damping(s[3 + leg], P)
    if ld != 0.0 and c > 0.0:
        ldd = -P[P_K] * ld / c
    # toe height y + sL sin(th) - l cos(g)
    vy = s[NQ + IY] + sL * math.cos(th) * dth - ld * cg + ll * sg * dg
    ay = (ds[NQ + IY] + sL * (math.cos(th) * ddth - math.sin(th) * dth * dth)
          - ldd * cg + 2.0 * ld * sg * dg + ll * (cg * dg * dg + sg * ddg))
    return vy, ay


@kernel
def toe_enters_ground(s, ds, P, leg, ld):
    """Whether the toe of ``leg``, at ground level, would move into the ground in flight
    (TOE_* above; ``ld``: its flight leg-length rate [m/s]; ``ds``: the state derivative of
    an evaluation in which the leg carries no force, or a small one: flight, or a slide
    about to end).

    The toe stub: a leg swept through with its toe at the ground (a back leg swung forward
    from behind the hip, its toe going down as the leg nears the vertical), or a toe released
    at rest whose leg goes on extending. Pinned, the ground would have to pull the toe;
    released to flight, the toe moves into the ground. The consistent contact is a slide in
    which the leg is compressed as it is swept on (settle_ws). A hop of at most TOE_HOP_TOL
    counts as pressed."""
    if P[P_MASSLESS] > 0.5:
        return TOE_STAYS
    vy, ay = toe_vertical_motion(s, ds, P, leg, ld)
    if vy < -TOE_REST_SPEED:
        return TOE_ENTERS
    if ay >= 0.0:
        return TOE_STAYS
    return TOE_PRESSED if vy * vy <= -2.0 * ay * TOE_HOP_TOL else TOE_STAYS


@kernel
def flight_toe_enters_ground(s, ds, aux, P, leg):
    """A leg in flight whose toe is at ground level (within TOE_AT_GROUND_TOL: a released
    strut's toe) and pressed into it, or at or below it and moving into it (its touchdown
    event cannot fire: it is armed only above the ground)."""
    toe_y = aux[leg * NAUX_LEG + A_TOE_Y]
    if toe_y > TOE_AT_GROUND_TOL:
        return False
    k = toe_enters_ground(s, ds, P, leg, ds[IL_B + leg])
    return k == TOE_PRESSED or (k == TOE_ENTERS and toe_y <= 0.0)


@kernel
def slide_toe_pressed(s, ds, aux, P, leg):
    """A sliding toe whose leg force has come to (or just below) zero but which would be
    pressed into the ground in flight (toe_enters_ground): the slide goes on, its leg loads
    again. Its flight leg-length rate is the slide's plus F / c (the damper balances the
    force F when the toe is free)."""
    ld = ds[IL_B + leg]
    c = P[P_NP] * leg_damping(s[3 + leg], P)
    fax = aux[leg * NAUX_LEG + A_FAX]
    if c > 0.0:
        ld += fax / c
    elif fax < 0.0:
        return False   # an undamped leg pulling: beyond its stop
    return toe_enters_ground(s, ds, P, leg, ld) == TOE_PRESSED


@kernel
def start_stub_slide(t, s, mi, aux, ev, nev, leg):
    """A toe pressed into the ground at the leg's stop slides (toe_enters_ground):
    in the direction the toe moves, or, at rest, away from the force that pinned it."""
    o = leg * NAUX_LEG
    mi[MI_CONTACT_B + leg] = SLIDE
    v = aux[o + A_SLIP_V]
    if v > SLIDE_SPEED_TOL:
        mi[MI_SLIDE_DIR_B + leg] = 1
    elif v < -SLIDE_SPEED_TOL:
        mi[MI_SLIDE_DIR_B + leg] = -1
    else:
        mi[MI_SLIDE_DIR_B + leg] = -1 if aux[o + A_GT] > 0.0 else 1
    return log_event(ev, nev, t, EK_SLIDE_START, leg, aux[o + A_GN], aux[o + A_FAX],
                     SLIDE_CAUSE_STUB)


@kernel
def leave_contact(s, mi, leg):
    """Switch a leg to flight (its current leg length is kept as the toe's state)."""
    mi[MI_CONTACT_B + leg] = FLIGHT


@allocating
def settle(t, s, P, mi, mf, cmd, ds, aux, ev, nev, stats):
    """:func:`settle_ws` with its own evaluation workspace."""
    return settle_ws(t, s, P, mi, mf, cmd, ds, aux, ev, nev, stats, eval_workspace(), False)


@kernel
def settle_ws(t, s, P, mi, mf, cmd, ds, aux, ev, nev, stats, ew, command_only=False):
    """Make the modes consistent with the forces at the current state (after a reset or a
    change of command): a pinned toe the ground would have to pull is released (to flight,
    or to a slide if the leg still pushes, SPEC.md 3), a strut in compression becomes a
    spring leg, a stuck motor joint loaded beyond breakaway slips, a slipping joint at rest
    sticks if stiction can hold it. Returns the updated event count.

    ``command_only``: s is projected and ds, aux and the workspace ``ew`` hold its last
    evaluation with the same modes, only ``cmd`` has changed (a new control sample after a
    plain step): the first evaluation is then :func:`evaluate_command_change`."""
    W = body_weight(P)
    # a contact force counts as pulling only beyond rounding: a massless undamped leg
    # touches down at rest length with a normal force of 0 +- 1e-14 N, which must not
    # release it at once (the toe would then be disarmed at height <= 0 and fall through)
    gn_tol = -1e-9 * W
    coulomb = P[P_MU] < 1e300
    model2 = int(P[P_MODEL]) == MODEL_II and P[P_TAU_S] > 0.0
    for it in range(12):
        if it == 0 and command_only and P[P_LEG_FRIC_SIDE] == 0.0:
            # (a side-load leg friction depends on the hip torque, so on the command, in
            # the leg force: then a fresh evaluation)
            evaluate_command_change(P, mi, cmd, ds, aux, ew[0], ew[1], ew[2])
        else:
            project_state(s, P, mi, mf)
            evaluate_ws(s, P, mi, mf, cmd, ds, aux, ew[0], ew[1], ew[2], False, ew[3], True)
        changed = False
        for leg in range(2):
            o = leg * NAUX_LEG
            mode = mi[MI_CONTACT_B + leg]
            gn = aux[o + A_GN]
            if mode == FLIGHT:
                if flight_toe_enters_ground(s, ds, aux, P, leg):
                    # a toe stub (a released pinned toe, or one swept down onto the
                    # ground at the stop): slides, its leg compressed as it is swept
                    nev = start_stub_slide(t, s, mi, aux, ev, nev, leg)
                    stats[S_NSTUB] += 1
                    changed = True
            elif mode == STICK:
                if gn < gn_tol:
                    if aux[o + A_FAX] > 1e-9 * W and P[P_MASSLESS] < 0.5:
                        mi[MI_CONTACT_B + leg] = SLIDE
                        gt = aux[o + A_GT]
                        mi[MI_SLIDE_DIR_B + leg] = -1 if gt > 0.0 else 1
                        nev = log_event(ev, nev, t, EK_SLIDE_START, leg, gn, aux[o + A_FAX],
                                        SLIDE_CAUSE_LEG_PUSHES)
                        stats[S_NEND_SLIDE] += 1
                    else:
                        leave_contact(s, mi, leg)
                        nev = log_event(ev, nev, t, EK_LIFTOFF, leg, s[IL_B + leg], 0.0, 0.0)
                    changed = True
                elif coulomb and abs(aux[o + A_GT]) > P[P_MU] * gn * (1.0 + 1e-9) + 1e-9 * W:
                    mi[MI_CONTACT_B + leg] = SLIDE
                    mi[MI_SLIDE_DIR_B + leg] = -1 if aux[o + A_GT] > 0.0 else 1
                    nev = log_event(ev, nev, t, EK_SLIDE_START, leg, gn, aux[o + A_FAX],
                                    SLIDE_CAUSE_CONE)
                    changed = True
            elif mode == STRUT:
                if gn < gn_tol:
                    leave_contact(s, mi, leg)
                    nev = log_event(ev, nev, t, EK_LIFTOFF, leg, s[IL_B + leg], 0.0, 0.0)
                    changed = True
                elif aux[o + A_STRUT] < 0.0:
                    mi[MI_CONTACT_B + leg] = STICK
                    nev = log_event(ev, nev, t, EK_STRUT_END, leg, 0.0, 0.0, 0.0)
                    changed = True
            elif mode == SLIDE:
                if ((gn < gn_tol or aux[o + A_FAX] <= 0.0)
                        and not slide_toe_pressed(s, ds, aux, P, leg)):
                    # (a slide at the stop whose toe is pressed into the ground starts with
                    # its leg force at zero, to rounding, and loads as the leg is swept on)
                    leave_contact(s, mi, leg)
                    nev = log_event(ev, nev, t, EK_LIFTOFF, leg, s[IL_B + leg], 0.0, 0.0)
                    changed = True
                elif coulomb and aux[o + A_SLIP_V] * mi[MI_SLIDE_DIR_B + leg] < -SLIDE_SPEED_TOL:
                    # the toe slides against its recorded direction (its velocity jumped, e.g.
                    # at the other leg's touchdown impact): friction opposes the motion it
                    # has, so the direction follows the velocity. Pinning the moving toe
                    # instead would take an impulse that the sliding contact cannot give
                    # (the massless toe on its compliant leg carries none).
                    mi[MI_SLIDE_DIR_B + leg] = -mi[MI_SLIDE_DIR_B + leg]
                    changed = True
            if model2:
                mm = mi[MI_MOTOR_B + leg]
                if mm == STUCK:
                    hold = aux[o + A_HOLD]
                    if abs(hold) > P[P_TAU_S] * (1.0 + 1e-9):
                        mi[MI_MOTOR_B + leg] = SLIP_NEG if hold > 0.0 else SLIP_POS
                        nev = log_event(ev, nev, t, EK_MOTOR_SLIP, leg, hold, 0.0, 0.0)
                        changed = True
                elif aux[o + A_OMEGA_M] * mm < -MOTOR_SPEED_TOL:
                    # slipping against its recorded direction (a stale mode, e.g. a resumed
                    # state): the Coulomb torque opposes the motion the joint has. Stopping
                    # it (sticking) would take an impulse that stiction cannot give; a
                    # joint comes to rest only through its rate's zero crossing (an event).
                    mi[MI_MOTOR_B + leg] = -mm
                    changed = True
        if not changed:
            # ds and aux are those of the (projected) state as it stands
            return nev
    project_state(s, P, mi, mf)
    evaluate_ws(s, P, mi, mf, cmd, ds, aux, ew[0], ew[1], ew[2], False, ew[3], True)
    return nev


@allocating
def touchdown(t, s, P, mi, mf, leg, aux, ev, nev, stats, imp):
    """Pin the toe where it touched the ground and apply the impact (SPEC.md 3)."""
    o = leg * NAUX_LEG
    mf[MF_ANCHOR_B + leg] = aux[o + A_TOE_X]
    mi[MI_CONTACT_B + leg] = STICK
    s_pre = s.copy()
    mi_pre = mi.copy()
    ok = impact(s, P, mi, mf, imp)
    if (ok and P[P_MASSLESS] < 0.5 and s[IL_B + leg] >= P[P_L0] * (1.0 - 1e-12)
            and stance_leg_rate(s, P, leg) > LEG_STOP_SPEED_TOL):
        # the toe lands with the leg at its stop while the hip moves away from it: the
        # massless toe cannot slide out beyond the stop, so the stop takes an impulse as
        # well (the leg lands as a rigid strut, SPEC.md 3); settle() makes it a spring leg
        # again once the strut is in compression
        for i in range(s.shape[0]):
            s[i] = s_pre[i]
        for i in range(mi.shape[0]):
            mi[i] = mi_pre[i]
        mi[MI_CONTACT_B + leg] = STRUT
        stats[S_NSTRUT] += 1
        ok = impact(s, P, mi, mf, imp)
    pn = imp[3 * leg]
    pt = imp[3 * leg + 1]
    if P[P_MU] < 1e300 and P[P_MASSLESS] < 0.5 and abs(pt) > P[P_MU] * pn:
        # Coulomb floor: the pinning impulse lies outside the friction cone (for a
        # massless toe on a compliant leg the only cone-consistent impulse is zero):
        # no impulse, the toe lands sliding. (A no-slip floor pins the toe whatever the
        # impulse's direction, docs/model.md: its impulse ratio is reported instead.)
        for i in range(s.shape[0]):
            s[i] = s_pre[i]
        for i in range(mi.shape[0]):
            mi[i] = mi_pre[i]
        mi[MI_CONTACT_B + leg] = SLIDE
        mi[MI_SLIDE_DIR_B + leg] = 1 if aux[o + A_SLIP_V] >= 0.0 else -1
        project_state(s, P, mi, mf)
        nev = log_event(ev, nev, t, EK_TOUCHDOWN, leg, 0.0, 0.0, 0.0)
        nev = log_event(ev, nev, t, EK_SLIDE_START, leg, 0.0, 0.0, SLIDE_CAUSE_NO_PIN_IMPULSE)
        return nev, True
    if pn > 0.0:
        r = abs(pt) / pn
        if r > stats[S_MAX_IMPULSE_RATIO]:
            stats[S_MAX_IMPULSE_RATIO] = r
    # stiction carries no impulse: impact() released stuck joints; settle() re-examines
    nev = log_event(ev, nev, t, EK_TOUCHDOWN, leg, pn, pt, imp[6])
    return nev, ok


@kernel
def apply_event(k, t, s, P, mi, mf, aux, ev, nev, stats, imp):
    """Mode transition for event slot k at time t (state s already at the event)."""
    ok = True
    if k < 2 * NEV_CONTACT:
        leg = k // NEV_CONTACT
        slot = k % NEV_CONTACT
        mode = mi[MI_CONTACT_B + leg]
        o = leg * NAUX_LEG
        if mode == FLIGHT:
            nev, ok = touchdown(t, s, P, mi, mf, leg, aux, ev, nev, stats, imp)
        elif mode == STICK:
            if slot == 0:
                # normal force reached zero: lift-off, or a slide if the leg still pushes
                if aux[o + A_FAX] > 1e-9 * body_weight(P) and P[P_MASSLESS] < 0.5:
                    mi[MI_CONTACT_B + leg] = SLIDE
                    mi[MI_SLIDE_DIR_B + leg] = -1 if aux[o + A_GT] > 0.0 else 1
                    stats[S_NEND_SLIDE] += 1
                    nev = log_event(ev, nev, t, EK_SLIDE_START, leg, aux[o + A_GN],
                                    aux[o + A_FAX], SLIDE_CAUSE_LEG_PUSHES)
                else:
                    leave_contact(s, mi, leg)
                    nev = log_event(ev, nev, t, EK_LIFTOFF, leg, s[IL_B + leg], 0.0, 0.0)
            elif slot == 1:
                mi[MI_CONTACT_B + leg] = STRUT
                stats[S_NSTRUT] += 1
                nev = log_event(ev, nev, t, EK_STRUT_START, leg, aux[o + A_GN], 0.0, 0.0)
            else:
                mi[MI_CONTACT_B + leg] = SLIDE
                mi[MI_SLIDE_DIR_B + leg] = -1 if aux[o + A_GT] > 0.0 else 1
                nev = log_event(ev, nev, t, EK_SLIDE_START, leg, aux[o + A_GN],
                                aux[o + A_FAX], SLIDE_CAUSE_CONE)
        elif mode == SLIDE:
            if slot == 0:
                leave_contact(s, mi, leg)
                nev = log_event(ev, nev, t, EK_LIFTOFF, leg, s[IL_B + leg], 0.0, 0.0)
            else:
                # slide velocity reached zero: stick here; settle() slides on (possibly
                # reversed) if the friction cone cannot hold the toe
                mi[MI_CONTACT_B + leg] = STICK
                mf[MF_ANCHOR_B + leg] = aux[o + A_TOE_X]
                nev = log_event(ev, nev, t, EK_STICK, leg, aux[o + A_TOE_X], 0.0, 0.0)
        elif mode == STRUT:
            if slot == 0:
                leave_contact(s, mi, leg)
                nev = log_event(ev, nev, t, EK_LIFTOFF, leg, s[IL_B + leg], 0.0, 0.0)
            else:
                mi[MI_CONTACT_B + leg] = STICK
                nev = log_event(ev, nev, t, EK_STRUT_END, leg, 0.0, 0.0, 0.0)
    elif k < EV_FALL_HEIGHT:
        leg = k - EV_MOTOR_B
        o = leg * NAUX_LEG
        if mi[MI_MOTOR_B + leg] == STUCK:
            hold = aux[o + A_HOLD]
            mi[MI_MOTOR_B + leg] = SLIP_NEG if hold > 0.0 else SLIP_POS
            nev = log_event(ev, nev, t, EK_MOTOR_SLIP, leg, hold, 0.0, 0.0)
        else:
            # a slipping joint comes to rest: stuck; settle() lets it slip on if the
            # holding torque needed exceeds the breakaway level
            mi[MI_MOTOR_B + leg] = STUCK
            nev = log_event(ev, nev, t, EK_MOTOR_STICK, leg, aux[o + A_HOLD], 0.0, 0.0)
    else:
        nev = log_event(ev, nev, t, EK_FALL, -1, s[1], s[2], 0.0)
    return nev, ok


@kernel
def record_friction(aux, P, mi, stats):
    """Track the largest friction ratio |Ft|/Fn needed by a pinned toe (Fn > 5 % weight)."""
    W = body_weight(P)
    for leg in range(2):
        mode = mi[MI_CONTACT_B + leg]
        if mode == STICK or mode == STRUT:
            o = leg * NAUX_LEG
            gn = aux[o + A_GN]
            if gn > 0.05 * W:
                r = abs(aux[o + A_GT]) / gn
                if r > stats[S_MAX_FRICTION]:
                    stats[S_MAX_FRICTION] = r


@kernel
def do_step(method, s, h, K, P, mi, mf, cmd, y_new, aux_new, tmp, rtol, atol, ew, SF0, SF1,
            Z, eval_end, want_sf=True):
    """One step of the selected method; returns (error_norm, ok, evaluations).
    ``want_sf``: the ARK methods also refresh the stiff factors at the step's end (SF1)."""
    if method == METHOD_ARK4:
        return ark.step(s, h, K, P, mi, mf, cmd, y_new, aux_new, tmp, rtol, atol, ew, SF0,
                        SF1, Z, eval_end, want_sf)
    if method == METHOD_ARK3:
        return ark.step3(s, h, K, P, mi, mf, cmd, y_new, aux_new, tmp, rtol, atol, ew, SF0,
                         SF1, Z, eval_end, want_sf)
    err, ok = step(s, h, K, P, mi, mf, cmd, y_new, aux_new, tmp, rtol, atol, ew)
    return err, ok, 6


@kernel
def eval_k0(method, s, P, mi, mf, cmd, K0, aux, ew, SF0):
    """f(s) into K0 (and, for the ARK method, the stiff factors into SF0)."""
    return evaluate_ws(s, P, mi, mf, cmd, K0, aux, ew[0], ew[1], ew[2],
                       method >= METHOD_ARK4, SF0, True)


@kernel(inline="always")
def dense_event_values(method, s, y_new, h, K, th, P, mi, mf, cmd, ybuf, tmp, aux_tmp, ew,
                       e_tmp):
    """Event functions (into e_tmp) at the fraction ``th`` of the step of size ``h`` from
    ``s`` to ``y_new``, on the method's continuous extension (one evaluation)."""
    if method >= METHOD_ARK4:
        ark.dense(s, y_new, h, K, th, ybuf)
    else:
        dense(s, h, K, th, ybuf)
    evaluate_ws(ybuf, P, mi, mf, cmd, tmp, aux_tmp, ew[0], ew[1], ew[2], False, ew[3], True)
    project_state(ybuf, P, mi, mf)
    event_values(ybuf, aux_tmp, P, mi, e_tmp)


@kernel(inline="always")
def illinois_update(th, fc, a, fa, b, fb, side):
    """One bracket update of the Illinois method (regula falsi with the stale end's value
    halved): the new point ``th`` with value ``fc`` replaces the end of its sign. Returns
    (a, fa, b, fb, side)."""
    if fc > 0.0:
        if side == -1:
            fb *= 0.5
        return th, fc, b, fb, -1
    if side == 1:
        fa *= 0.5
    return a, fa, th, fc, 1


@kernel(inline="always")
def smallest_armed_event(y, ybuf, P, mi, mf, cmd, tmp, aux_tmp, ew, e_tmp, armed):
    """The smallest armed event function at state ``y`` (evaluated on a projected copy)
    and its slot: (value, slot)."""
    for i in range(NS):
        ybuf[i] = y[i]
    project_state(ybuf, P, mi, mf)
    evaluate_ws(ybuf, P, mi, mf, cmd, tmp, aux_tmp, ew[0], ew[1], ew[2], False, ew[3], True)
    event_values(ybuf, aux_tmp, P, mi, e_tmp)
    fc = 1.0
    k = -1
    for i in range(NEV):
        if armed[i] and e_tmp[i] < fc:
            fc = e_tmp[i]
            k = i
    return fc, k


@kernel
def refine_event(kmin, s, h, th0, armed, e_start, e_full, method, K, P, mi, mf, cmd, y_new,
                 aux_new, tmp, rtol, atol, ew, SF0, SF1, Z, ybuf, aux_tmp, e_tmp):
    """Make the step from ``s`` end on the earliest zero of the armed event functions
    themselves (not of their continuous-extension interpolants).

    ``y_new`` holds the step of length th0 h located on the continuous extension for event
    ``kmin``; ``e_start`` / ``e_full`` are the event values at the step's start (armed ones
    > 0) and at its full length h. The step stands if, on it, the smallest armed event
    function g = min_i e_i has crossed (<= 0) by no more than EVENT_STATE_TOL of its slope;
    otherwise g's zero is located by Illinois iterations on redone steps. Using g, not
    e_kmin alone, keeps a refinement from stepping over another event. Returns
    (he, event slot, evaluations); y_new holds the step to he."""
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
    for it in range(60):
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
        err, ok, nfs = do_step(method, s, th * h, K, P, mi, mf, cmd, y_new, aux_new, tmp,
                               rtol, atol, ew, SF0, SF1, Z, True, False)
        nf += nfs
        if done:
            break
    # bracket closed to EVENT_TIME_TOL: the step to b, where g <= 0
    fc, kk = smallest_armed_event(y_new, ybuf, P, mi, mf, cmd, tmp, aux_tmp, ew, e_tmp, armed)
    nf += 1
    if kk >= 0:
        k = kk
    return th * h, k, nf


AdvanceScratch = namedtuple("AdvanceScratch", "e_end pending mi_before e_tmp aux_tmp")


@kernel
def advance(t, t_end, s, P, mi, mf, cmd, rtol, atol, hwork, K, y_new, tmp, aux, aux_new,
            ev, nev, stats, armed, e_old, e_new, ybuf, imp, ew, method, SF0, SF1, Z, sc,
            fresh=False):
    """Integrate from t to t_end (one control period) with events.

    hwork[HW_STEP] carries the step-size guess between calls. ``method``: METHOD_DOPRI5 or
    METHOD_ARK4 (SF0, SF1, Z: its stiff-factor and stage scratch). ``fresh``: K[0] and aux
    already hold f(s) and its outputs (and SF0 usable stiff factors). Returns
    (t, nev, status)."""
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
    e_tmp = sc.e_tmp
    aux_tmp = sc.aux_tmp
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
        err, ok, nf = do_step(method, s, h, K, P, mi, mf, cmd, y_new, aux_new, tmp, rtol, atol,
                              ew, SF0, SF1, Z, False)
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
            hop = (not armed[k] and e_end[k] < 0.0 and k < 2 * NEV_CONTACT
                   and k % NEV_CONTACT == 0 and mi[MI_CONTACT_B + k // NEV_CONTACT] == FLIGHT
                   and e_old[k] > -SIMULTANEOUS_EVENT_TOL and P[P_MASSLESS] < 0.5)
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
                        dense_event_values(method, s, y_new, h, K, thp, P, mi, mf, cmd, ybuf,
                                           tmp, aux_tmp, ew, e_tmp)
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
                        dense_event_values(method, s, y_new, h, K, th, P, mi, mf, cmd, ybuf,
                                           tmp, aux_tmp, ew, e_tmp)
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
                err, ok, nf = do_step(method, s, he, K, P, mi, mf, cmd, y_new, aux_new, tmp,
                                      rtol, atol, ew, SF0, SF1, Z, True, False)
                stats[S_NFEV] += nf
                # The continuous extension is only an interpolant: on a stiff component (a
                # gear rate in the belt transient after a touchdown, under ARK's cubic
                # Hermite) its zero can lie microseconds from that of the step itself, and
                # a transition applied there is applied to the wrong state (a joint "at
                # rest" that still turns). Check the event function on the redone step and,
                # if it is not at its zero, locate the zero on the steps themselves.
                he, kmin, nf = refine_event(kmin, s, h, thmin, armed, e_old, e_end, method, K,
                                            P, mi, mf, cmd, y_new, aux_new, tmp, rtol, atol,
                                            ew, SF0, SF1, Z, ybuf, aux_tmp, e_tmp)
                stats[S_NFEV] += nf
                for i in range(NS):
                    s[i] = y_new[i]
                t = t + he
            stats[S_NSTEP] += 1
            project_state(s, P, mi, mf)
            evaluate_ws(s, P, mi, mf, cmd, K0, aux, ew[0], ew[1], ew[2], False, ew[3], True)
            n_events_here += 1
            if n_events_here > MAX_EVENTS_PER_PERIOD:
                return t, nev, ST_NUMERICAL_FAILURE
            # transition audit: mechanical energy before the transition
            nev0 = nev
            e_before = aux[A_ENERGY]
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
                    stamp_transition(ev, nev0, nev, e_before, e_before, 0)
                    return t, nev, ST_FELL
                if not ok:
                    stamp_transition(ev, nev0, nev, e_before, np.nan, V_SINGULAR)
                    return t, nev, ST_NUMERICAL_FAILURE
                nev = settle_ws(t, s, P, mi, mf, cmd, K0, aux, ev, nev, stats, ew)
                stats[S_NFEV] += 1
                if aux[A_KKT_OK] < 0.5:
                    stamp_transition(ev, nev0, nev, e_before, np.nan, V_SINGULAR)
                    return t, nev, ST_NUMERICAL_FAILURE
                event_values(s, aux, P, mi, e_old)
                kcur = -1
                for i in range(NEV):
                    if pending[i] and e_old[i] <= SIMULTANEOUS_EVENT_TOL and e_end[i] < 0.0:
                        # only if the slot still means the same thing (its leg's modes
                        # unchanged)
                        same = True
                        if i < 2 * NEV_CONTACT:
                            lg = i // NEV_CONTACT
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
                             mode_violations(s, K0, aux, P, mi))
            for i in range(NEV):
                armed[i] = e_old[i] > 0.0
            for leg in range(2):
                # a toe that sticks on the edge of the friction cone (a slide come to rest
                # with the friction at mu F_n) starts with its stick -> slip function at
                # zero, within the stick rule's tolerance: armed, so that it fires at once
                # if the force leaves the cone (otherwise it could leave it unnoticed)
                kc = leg * NEV_CONTACT + 2
                if mi[MI_CONTACT_B + leg] == STICK and e_old[kc] > -CONE_ARM_TOL:
                    armed[kc] = True
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
