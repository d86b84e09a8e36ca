"""Event functions of the hybrid model and the transition audit's invariants.

The plant's events (touchdown, lift-off, slide start and stop, strut, stiction stick and
slip, fall) are sign changes of the event functions of :func:`event_values` in the current
modes; :mod:`scoutsim._core.numerics.hybrid` locates them, :mod:`scoutsim._core.numerics.transitions`
applies them. :func:`mode_violations` checks, after every transition, that the modes agree
with the velocities and forces (layout ``V_*``), and the event log records carry the
energies and that mask (:func:`stamp_transition`). The toe predicates decide whether a
toe at ground level would move into the ground in flight (the toe stub).
"""

from __future__ import annotations

import math

import numpy as np

from ..._numba.jit import kernel
from ..model.contact import JAM_AXIAL_SHARE, slide_axial_share, slide_is_jammed, toe_can_slip
from ..model.flags import is_set
from ..model.kinematics import hip_offset
from ..model.layout import (
    A_FAX,
    A_GN,
    A_GT,
    A_HOLD,
    A_KKT_OK,
    A_OMEGA_M,
    A_SLIP_V,
    A_STRUT,
    A_TOE_Y,
    BACK,
    EV_FALL_HEIGHT,
    EV_FALL_PITCH,
    EV_MOTOR_B,
    EVC_CONE,
    EVC_GROUND,
    EVC_STOP_OR_REST,
    EVR_E_AFTER,
    EVR_E_BEFORE,
    EVR_STATE_AFTER,
    EVR_STATE_BEFORE,
    EVR_VIOLATIONS,
    FLIGHT,
    FRONT,
    IL_B,
    IPHB,
    ITH,
    IY,
    MI_CONTACT_B,
    MI_MOTOR_B,
    MI_SLIDE_DIR_B,
    NAUX_LEG,
    NEV,
    NEV_CONTACT,
    NEVBUF,
    NQ,
    NS,
    P_G,
    P_K,
    P_L0,
    P_MASSLESS,
    P_ML,
    P_MT,
    P_MU,
    P_N,
    P_NP,
    P_TAU_S,
    P_THETA_LIM,
    P_TORSO_H,
    P_TORSO_LEN,
    SLIDE,
    STICK,
    STP_CONTACT_B,
    STP_MOTOR_B,
    STP_STATE,
    STP_T,
    STRUT,
    STUCK,
    V_BEYOND_STOP,
    V_GROUND_PULLS,
    V_OUTSIDE_CONE,
    V_SINGULAR,
    V_SLIDE_DIRECTION,
    V_SLIDE_NOT_PUSHING,
    V_SLIP_DIRECTION,
    V_STICTION_EXCEEDED,
    V_STRUT_COMPRESSED,
    V_TOE_BELOW_GROUND,
    V_TOE_ENTERS_GROUND,
)
from ..model.leg import leg_damping
from ..model.transmission import joint_has_stiction

#: Speeds below which a sliding toe [m/s] or a slipping motor joint [rad/s, motor side] that
#: moves against its recorded direction counts as at rest (the event that stops it is
#: located to EVENT_TIME_TOL, so the rate at a located zero crossing is a little off zero,
#: by at most ~1e-6 for Scout II's largest accelerations).
SLIDE_SPEED_TOL = 1e-6
MOTOR_SPEED_TOL = 1e-4
#: a toe at ground level moving down faster than this [m/s] enters the ground
TOE_REST_SPEED = 1e-7
#: a toe at ground level that would rise at most this height [m] before
#: its (downward) acceleration brings it back counts as pressed into the ground: the touchdown
#: event of so short a hop (microseconds) can fall within one step and be missed
TOE_HOP_TOL = 1e-9
#: a toe in flight counts as at ground level within this height [m] (a released strut's toe
#: is lifted by its ~3e-8 m of length drift)
TOE_AT_GROUND_TOL = 1e-7


@kernel(inline="always")
def contact_event(leg, slot):
    """Event slot of virtual leg ``leg``'s contact event ``slot`` (layout ``EVC_*``)."""
    return leg * NEV_CONTACT + slot


@kernel(inline="always")
def is_contact_event(k):
    """True if event slot ``k`` is one of the legs' contact events."""
    return k < 2 * NEV_CONTACT


@kernel(inline="always")
def event_leg(k):
    """The virtual leg of contact event slot ``k``."""
    return k // NEV_CONTACT


@kernel(inline="always")
def event_slot(k):
    """Which of its leg's contact events (layout ``EVC_*``) event slot ``k`` is."""
    return k % NEV_CONTACT


@kernel(inline="always")
def body_weight(P):
    """The robot's weight [N]: torso and all leg bodies (the force scale of the events)."""
    return (P[P_MT] + P[P_NP] * (P[P_ML + BACK] + P[P_ML + FRONT])) * P[P_G]


@kernel
def event_values(s, aux, P, mi, out):
    """Event functions of the current modes; an event happens when one goes below zero."""
    event_values_at(s, aux, P, mi, out, math.sin(s[ITH]), math.cos(s[ITH]))


@kernel(inline="always")
def event_values_at(s, aux, P, mi, out, sth, cth):
    """:func:`event_values` given the pitch's sine and cosine ``sth, cth`` at ``s`` (as the
    evaluation of ``s`` computed them)."""
    W = body_weight(P)
    massless = is_set(P[P_MASSLESS])
    coulomb = toe_can_slip(P)
    for i in range(NEV):
        out[i] = 1.0
    for leg in range(2):
        o = leg * NAUX_LEG
        mode = mi[MI_CONTACT_B + leg]
        l0 = P[P_L0 + leg]
        tau_s = P[P_TAU_S + leg]
        if mode == FLIGHT:
            out[contact_event(leg, EVC_GROUND)] = aux[o + A_TOE_Y] / l0
        elif mode == STICK:
            out[contact_event(leg, EVC_GROUND)] = aux[o + A_GN] / W
            if not massless:
                out[contact_event(leg, EVC_STOP_OR_REST)] = (l0 - s[IL_B + leg]) / l0
            if coulomb:
                out[contact_event(leg, EVC_CONE)] = (
                    P[P_MU] * aux[o + A_GN] - abs(aux[o + A_GT])
                ) / W
        elif mode == SLIDE:
            out[contact_event(leg, EVC_GROUND)] = aux[o + A_GN] / W
            if coulomb:
                out[contact_event(leg, EVC_STOP_OR_REST)] = (
                    aux[o + A_SLIP_V] * mi[MI_SLIDE_DIR_B + leg]
                )
                # the slide's ground force turning perpendicular to the leg: a jam
                if not massless:
                    out[contact_event(leg, EVC_CONE)] = (
                        slide_axial_share(s[ITH] + s[IPHB + leg], mi[MI_SLIDE_DIR_B + leg], P)
                        - JAM_AXIAL_SHARE
                    )
        elif mode == STRUT:
            out[contact_event(leg, EVC_GROUND)] = aux[o + A_GN] / W
            out[contact_event(leg, EVC_STOP_OR_REST)] = aux[o + A_STRUT] / W
        if joint_has_stiction(leg, P):
            mm = mi[MI_MOTOR_B + leg]
            if mm == STUCK:
                out[EV_MOTOR_B + leg] = (tau_s - abs(aux[o + A_HOLD])) / tau_s
            else:
                out[EV_MOTOR_B + leg] = aux[o + A_OMEGA_M] * mm / P[P_N + leg]
    a = 0.5 * P[P_TORSO_LEN]
    b = 0.5 * P[P_TORSO_H]
    out[EV_FALL_HEIGHT] = s[IY] - a * abs(sth) - b * abs(cth)
    out[EV_FALL_PITCH] = P[P_THETA_LIM] - abs(s[ITH])


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
        if ev.shape[1] >= NEVBUF:
            for i in range(2 * NS):  # unknown until the transition is stamped
                ev[nev, EVR_STATE_BEFORE + i] = np.nan
    return nev + 1


@kernel
def stamp_states(ev, nev0, nev, s_before, s_after):
    """Write the exact state just before one transition and after its modes have settled
    (layout STATE_NAMES, SI) into the event records nev0 .. nev-1 logged while it was
    processed (buffers of ``NEVBUF`` columns; narrower ones have no room for them)."""
    if ev.shape[1] < NEVBUF:
        return
    for j in range(nev0, min(nev, ev.shape[0])):
        for i in range(NS):
            ev[j, EVR_STATE_BEFORE + i] = s_before[i]
            ev[j, EVR_STATE_AFTER + i] = s_after[i]


@kernel
def record_step(steps, stepc, t, s, mi):
    """Append one integrator step (its end time [s], the state there, the plant modes
    during it; layout ``STP_*``) to ``steps`` if step recording is on (``stepc[1]``);
    ``stepc[0]`` counts the rows. The run loop hands the buffer back to Python before it
    can fill up (``numerics.hybrid.STEP_HEADROOM``)."""
    if stepc[1] == 0:
        return
    n = stepc[0]
    if n < steps.shape[0]:
        steps[n, STP_T] = t
        for i in range(NS):
            steps[n, STP_STATE + i] = s[i]
        for leg in range(2):
            steps[n, STP_CONTACT_B + leg] = mi[MI_CONTACT_B + leg]
            steps[n, STP_MOTOR_B + leg] = mi[MI_MOTOR_B + leg]
    stepc[0] = n + 1


@kernel
def jammed_slide_moving(s, P, mi, aux, leg):
    """True if the toe of ``leg`` slides, moving (beyond SLIDE_SPEED_TOL) in its recorded
    slide direction, and that slide is jammed (contact.slide_is_jammed): its jam event
    (armed below zero) ends the slide at this instant with the jam's impact (docs/model.md
    "A sliding toe that jams")."""
    if mi[MI_CONTACT_B + leg] != SLIDE:
        return False
    d = mi[MI_SLIDE_DIR_B + leg]
    return aux[leg * NAUX_LEG + A_SLIP_V] * d > SLIDE_SPEED_TOL and slide_is_jammed(
        s[ITH] + s[IPHB + leg], d, P
    )


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
    coulomb = toe_can_slip(P)
    bits = 0
    if not is_set(aux[A_KKT_OK]):
        bits |= V_SINGULAR
    for leg in range(2):
        o = leg * NAUX_LEG
        mode = mi[MI_CONTACT_B + leg]
        gn = aux[o + A_GN]
        if mode == STICK or mode == STRUT:
            if gn < -ftol:
                bits |= V_GROUND_PULLS
            if (
                mode == STICK
                and coulomb
                and (abs(aux[o + A_GT]) > P[P_MU] * gn * (1.0 + 1e-6) + ftol)
            ):
                bits |= V_OUTSIDE_CONE
            if mode == STRUT and aux[o + A_STRUT] < -ftol:
                bits |= V_STRUT_COMPRESSED
            if mode == STICK and s[IL_B + leg] > P[P_L0 + leg] + 1e-6:
                # (1 um: a strut's length is Baumgarte-stabilised, not projected, and
                # drifts by ~3e-8 m before it ends)
                bits |= V_BEYOND_STOP
        elif mode == SLIDE:
            if coulomb and aux[o + A_SLIP_V] * mi[MI_SLIDE_DIR_B + leg] < -SLIDE_SPEED_TOL:
                bits |= V_SLIDE_DIRECTION
            if (
                (aux[o + A_FAX] < -ftol or gn < -ftol)
                and not slide_toe_pressed(s, ds, aux, P, leg)
                and not jammed_slide_moving(s, P, mi, aux, leg)
            ):
                # (a moving toe whose slide is jammed jams at this instant: its slide's
                # forces mean nothing)
                bits |= V_SLIDE_NOT_PUSHING
        elif not is_set(P[P_MASSLESS]):
            # (a massless leg is placed kinematically at its touchdown angle in flight, which
            # can put its toe below the ground just after lift-off: the passive model's
            # convention, docs/specification.md section 2; it touches down when the toe comes down through it)
            if aux[o + A_TOE_Y] < -1e-9:
                bits |= V_TOE_BELOW_GROUND
            if flight_toe_enters_ground(s, ds, aux, P, leg):
                bits |= V_TOE_ENTERS_GROUND
        if joint_has_stiction(leg, P):
            mm = mi[MI_MOTOR_B + leg]
            if mm == STUCK:
                if abs(aux[o + A_HOLD]) > P[P_TAU_S + leg] * (1.0 + 1e-6):
                    bits |= V_STICTION_EXCEEDED
            elif aux[o + A_OMEGA_M] * mm < -MOTOR_SPEED_TOL:
                bits |= V_SLIP_DIRECTION
    return bits


@kernel
def stamp_transition(ev, nev0, nev, e_before, e_after, bits, s_before, s_after):
    """Write the transition audit (energies before / after [J], violated invariants, the
    states before / after: :func:`stamp_states`) into the event records nev0 .. nev-1 logged
    while one transition was processed."""
    for j in range(nev0, min(nev, ev.shape[0])):
        ev[j, EVR_E_BEFORE] = e_before
        ev[j, EVR_E_AFTER] = e_after
        ev[j, EVR_VIOLATIONS] = bits
    stamp_states(ev, nev0, nev, s_before, s_after)


#: toe_enters_ground results
TOE_STAYS = 0  # the toe does not move into the ground
TOE_PRESSED = 1  # at rest vertically at ground level, accelerating into the ground
TOE_ENTERS = 2  # moving into the ground faster than TOE_REST_SPEED


@kernel
def toe_vertical_motion(s, ds, P, leg, ld):
    """Rate [m/s] and acceleration [m/s^2] of the height of the toe of ``leg`` moving as in
    flight: leg-length rate ``ld`` [m/s] (the flight rate) and the flight relaxation's
    ldd = -k ld / c (exact for a constant damper without leg friction; first order
    otherwise)."""
    sL = hip_offset(P, leg)
    ll = s[IL_B + leg]
    th = s[ITH]
    dth = s[NQ + ITH]
    ddth = ds[NQ + ITH]
    g = th + s[IPHB + leg]
    dg = dth + s[NQ + IPHB + leg]
    ddg = ddth + ds[NQ + IPHB + leg]
    sg = math.sin(g)
    cg = math.cos(g)
    ldd = 0.0
    c = leg_damping(s[IPHB + leg], leg, P)
    if ld != 0.0 and c > 0.0:
        ldd = -P[P_K + leg] * ld / c
    # toe height y + sL sin(th) - l cos(g)
    vy = s[NQ + IY] + sL * math.cos(th) * dth - ld * cg + ll * sg * dg
    ay = (
        ds[NQ + IY]
        + sL * (math.cos(th) * ddth - math.sin(th) * dth * dth)
        - ldd * cg
        + 2.0 * ld * sg * dg
        + ll * (cg * dg * dg + sg * ddg)
    )
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
    if is_set(P[P_MASSLESS]):
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
    c = P[P_NP] * leg_damping(s[IPHB + leg], leg, P)
    fax = aux[leg * NAUX_LEG + A_FAX]
    if c > 0.0:
        ld += fax / c
    elif fax < 0.0:
        return False  # an undamped leg pulling: beyond its stop
    return toe_enters_ground(s, ds, P, leg, ld) == TOE_PRESSED
