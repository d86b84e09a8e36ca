"""Mode transitions of the hybrid model: what happens at an event, and the rules that make
the modes agree with the forces after a reset or a new command (docs/model.md, "Events and
transitions"): touchdown impacts, lift-off or slide at the end of stance, the strut,
stick and slip of the toe and of the Model II motor joints, the toe stub.
"""

from __future__ import annotations

import math

from ..._numba.jit import allocating, kernel
from ..model.contact import slide_is_jammed, toe_can_slip
from ..model.evaluate import evaluate_command_change, evaluate_ws
from ..model.flags import is_set
from ..model.impact import impact
from ..model.kinematics import hip_offset, project_state
from ..model.layout import (
    A_FAX,
    A_GN,
    A_GT,
    A_HOLD,
    A_OMEGA_M,
    A_SLIP_V,
    A_STRUT,
    A_TOE_X,
    BACK,
    EK_FALL,
    EK_JAM,
    EK_LIFTOFF,
    EK_MOTOR_SLIP,
    EK_MOTOR_STICK,
    EK_SLIDE_START,
    EK_STICK,
    EK_STRUT_END,
    EK_STRUT_START,
    EK_TOUCHDOWN,
    EV_FALL_HEIGHT,
    EV_MOTOR_B,
    EVC_CONE,
    EVC_GROUND,
    EVC_STOP_OR_REST,
    FLIGHT,
    FRONT,
    IL_B,
    IMP_ENERGY_LOST,
    IMP_NORMAL,
    IMP_TANGENT,
    IPHB,
    ITH,
    IY,
    MF_ANCHOR_B,
    MI_CONTACT_B,
    MI_MOTOR_B,
    MI_SLIDE_DIR_B,
    NAUX_LEG,
    NIMP_LEG,
    NQ,
    P_L0,
    P_LEG_FRIC_SIDE,
    P_MASSLESS,
    P_MU,
    P_TAU_S,
    SLIDE,
    SLIDE_CAUSE_CONE,
    SLIDE_CAUSE_LEG_PUSHES,
    SLIDE_CAUSE_NO_PIN_IMPULSE,
    SLIDE_CAUSE_STUB,
    SLIP_NEG,
    SLIP_POS,
    STICK,
    STRUT,
    STUCK,
)
from ..model.transmission import joint_has_stiction
from .dopri5 import eval_workspace
from .events import (
    MOTOR_SPEED_TOL,
    SLIDE_SPEED_TOL,
    body_weight,
    event_leg,
    event_slot,
    flight_toe_enters_ground,
    is_contact_event,
    jammed_slide_moving,
    log_event,
    slide_toe_pressed,
)
from .stats import S_MAX_FRICTION, S_MAX_IMPULSE_RATIO, S_NEND_SLIDE, S_NSTRUT, S_NSTUB
from .work import EventLog

#: a pinned leg at its stop counts as extending beyond this leg-length rate [m/s]
LEG_STOP_SPEED_TOL = 1e-6


@kernel
def stance_leg_rate(s, P, leg):
    """dl/dt [m/s] of a leg whose toe is pinned: minus the hip velocity along the leg."""
    sL = hip_offset(P, leg)
    th = s[ITH]
    g = th + s[IPHB + leg]
    hvx = s[NQ] - sL * math.sin(th) * s[NQ + ITH]
    hvy = s[NQ + IY] + sL * math.cos(th) * s[NQ + ITH]
    return -(hvx * math.sin(g) - hvy * math.cos(g))


@kernel
def start_stub_slide(t, s, P, mi, mf, aux, ev, nev, leg):
    """A toe pressed into the ground at the leg's stop slides (toe_enters_ground):
    in the direction the toe moves, or, at rest, away from the force that pinned it. A toe
    at rest whose slide would be jammed (contact.slide_is_jammed) is pinned instead: pressed
    into the ground along its leg, the jammed contact locks (docs/model.md "A sliding toe
    that jams")."""
    o = leg * NAUX_LEG
    mi[MI_CONTACT_B + leg] = SLIDE
    v = aux[o + A_SLIP_V]
    if v > SLIDE_SPEED_TOL:
        mi[MI_SLIDE_DIR_B + leg] = 1
    elif v < -SLIDE_SPEED_TOL:
        mi[MI_SLIDE_DIR_B + leg] = -1
    else:
        mi[MI_SLIDE_DIR_B + leg] = -1 if aux[o + A_GT] > 0.0 else 1
        if slide_is_jammed(s[ITH] + s[IPHB + leg], mi[MI_SLIDE_DIR_B + leg], P):
            return stick_toe(t, mi, mf, aux, ev, nev, leg)
    return log_event(
        ev, nev, t, EK_SLIDE_START, leg, aux[o + A_GN], aux[o + A_FAX], SLIDE_CAUSE_STUB
    )


@kernel
def lift_off(t, s, mi, ev, nev, leg):
    """The toe of ``leg`` leaves the ground (its current leg length is kept as the toe's
    state); logged. Returns the event count."""
    mi[MI_CONTACT_B + leg] = FLIGHT
    return log_event(ev, nev, t, EK_LIFTOFF, leg, s[IL_B + leg], 0.0, 0.0)


@kernel
def stick_toe(t, mi, mf, aux, ev, nev, leg):
    """The toe of ``leg`` sticks where it is (its anchor: the toe's x now); logged.
    Returns the event count."""
    x = aux[leg * NAUX_LEG + A_TOE_X]
    mi[MI_CONTACT_B + leg] = STICK
    mf[MF_ANCHOR_B + leg] = x
    return log_event(ev, nev, t, EK_STICK, leg, x, 0.0, 0.0)


@kernel
def slide_from_pin(t, mi, aux, ev, nev, leg, cause):
    """A pinned toe starts to slide, away from the force that held it (``cause``:
    SLIDE_CAUSE_LEG_PUSHES or SLIDE_CAUSE_CONE); logged. Returns the event count."""
    o = leg * NAUX_LEG
    mi[MI_CONTACT_B + leg] = SLIDE
    mi[MI_SLIDE_DIR_B + leg] = -1 if aux[o + A_GT] > 0.0 else 1
    return log_event(ev, nev, t, EK_SLIDE_START, leg, aux[o + A_GN], aux[o + A_FAX], cause)


@kernel
def release_pin(t, s, P, mi, aux, ev, nev, stats, leg):
    """A pinned toe whose normal force has reached zero (or that the ground would have to
    pull): it slides if its leg still pushes, otherwise it lifts off (the end-of-stance
    rule: releasing a toe its leg still pushes would drive it into the ground). Returns
    the event count."""
    o = leg * NAUX_LEG
    if (
        aux[o + A_FAX] > 1e-9 * body_weight(P)
        and not is_set(P[P_MASSLESS])
        and not slide_is_jammed(s[ITH] + s[IPHB + leg], -1 if aux[o + A_GT] > 0.0 else 1, P)
    ):
        stats[S_NEND_SLIDE] += 1
        return slide_from_pin(t, mi, aux, ev, nev, leg, SLIDE_CAUSE_LEG_PUSHES)
    # (a slide that would be jammed cannot carry the leg's push: the toe is released)
    return lift_off(t, s, mi, ev, nev, leg)


@kernel
def released_toe_pressed(s, P, mi, mf, cmd, ds, aux, ew, leg):
    """Whether the pinned toe of ``leg``, released to flight, would be pressed into the
    ground or move into it (events.flight_toe_enters_ground): the motion of the body and
    the leg, not the leg force, drives it into the floor. Evaluates the state with the toe
    free into ``ds``, ``aux`` (workspace ``ew``), then again in the modes ``mi`` as they
    were, which leaves ``ds`` and ``aux`` as they came (the same evaluation).

    The rule it serves (settle_ws): a pinned toe whose cone asks for a jammed slide
    (contact.slide_is_jammed) has no slide to go to; released, it must not move into the
    ground. If it would (seen on a leg at its rest length, carrying a few 0.01 N, whose hip
    moves away along it while the leg swings forward beyond the friction angle: the free
    toe accelerates into the floor at about g), no contact mode is free of contradiction
    but the pin: pressed into the ground by the motion, the jammed contact locks, as it
    does when the leg pushes (docs/model.md "A sliding toe that jams"). Releasing it
    instead gives a hop of a nanometre, a touchdown and a pin impulse 30-70 us later, again
    and again, until the hop is shorter than events.TOE_HOP_TOL and the toe stub's slide,
    jammed, sends it back: the settling rules then go round without end."""
    mode = mi[MI_CONTACT_B + leg]
    mi[MI_CONTACT_B + leg] = FLIGHT
    evaluate_ws(s, P, mi, mf, cmd, ds, aux, ew, False, ew[3], True)
    pressed = flight_toe_enters_ground(s, ds, aux, P, leg)
    mi[MI_CONTACT_B + leg] = mode
    evaluate_ws(s, P, mi, mf, cmd, ds, aux, ew, False, ew[3], True)
    return pressed


@allocating
def settle(t, s, P, mi, mf, cmd, ds, aux, ev, nev, stats):
    """:func:`settle_ws` with its own evaluation workspace."""
    return settle_ws(
        t, s, P, mi, mf, cmd, ds, aux, EventLog(ev, stats), nev, eval_workspace(), False
    )


@kernel
def settle_ws(t, s, P, mi, mf, cmd, ds, aux, log, nev, ew, command_only=False):
    """Make the modes consistent with the forces at the current state (after a reset or a
    change of command): a pinned toe the ground would have to pull is released (to flight,
    or to a slide if the leg still pushes, docs/specification.md section 3), a strut in compression becomes a
    spring leg, a stuck motor joint loaded beyond breakaway slips, a slipping joint at rest
    sticks if stiction can hold it. Returns the updated event count.

    ``command_only``: s is projected and ds, aux and the workspace ``ew`` hold its last
    evaluation with the same modes, only ``cmd`` has changed (a new control sample after a
    plain step): the first evaluation is then :func:`evaluate_command_change`. ``log``
    (:class:`~scoutsim._core.numerics.work.EventLog`): the event records (``nev`` in use) and the
    statistics."""
    ev, stats = log
    W = body_weight(P)
    # a contact force counts as pulling only beyond rounding: a massless undamped leg
    # touches down at rest length with a normal force of 0 +- 1e-14 N, which must not
    # release it at once (the toe would then be disarmed at height <= 0 and fall through)
    gn_tol = -1e-9 * W
    coulomb = toe_can_slip(P)
    for it in range(12):
        if (
            it == 0
            and command_only
            and P[P_LEG_FRIC_SIDE + BACK] == 0.0
            and P[P_LEG_FRIC_SIDE + FRONT] == 0.0
        ):
            # (a side-load leg friction depends on the hip torque, so on the command, in
            # the leg force: then a fresh evaluation)
            evaluate_command_change(P, mi, cmd, ds, aux, ew[0], ew[1], ew[2])
        else:
            project_state(s, P, mi, mf)
            evaluate_ws(s, P, mi, mf, cmd, ds, aux, ew, False, ew[3], True)
        changed = False
        for leg in range(2):
            o = leg * NAUX_LEG
            mode = mi[MI_CONTACT_B + leg]
            gn = aux[o + A_GN]
            if mode == FLIGHT:
                if flight_toe_enters_ground(s, ds, aux, P, leg):
                    # a toe stub (a released pinned toe, or one swept down onto the
                    # ground at the stop): slides, its leg compressed as it is swept
                    nev = start_stub_slide(t, s, P, mi, mf, aux, ev, nev, leg)
                    stats[S_NSTUB] += 1
                    changed = True
            elif mode == STICK:
                if gn < gn_tol:
                    nev = release_pin(t, s, P, mi, aux, ev, nev, stats, leg)
                    changed = True
                elif coulomb and abs(aux[o + A_GT]) > P[P_MU] * gn * (1.0 + 1e-9) + 1e-9 * W:
                    if not slide_is_jammed(
                        s[ITH] + s[IPHB + leg], -1 if aux[o + A_GT] > 0.0 else 1, P
                    ):
                        nev = slide_from_pin(t, mi, aux, ev, nev, leg, SLIDE_CAUSE_CONE)
                        changed = True
                    elif aux[o + A_FAX] <= 0.0 and not released_toe_pressed(
                        s, P, mi, mf, cmd, ds, aux, ew, leg
                    ):
                        # the slide the cone asks for is jammed (its ground force would be
                        # perpendicular to the leg) and the toe is not pressed into the
                        # ground, neither by its leg nor by the motion: it is released.
                        # (A toe that is pressed stays pinned: the jammed contact locks,
                        # docs/model.md "A sliding toe that jams"; released_toe_pressed)
                        nev = lift_off(t, s, mi, ev, nev, leg)
                        changed = True
            elif mode == STRUT:
                if gn < gn_tol:
                    nev = lift_off(t, s, mi, ev, nev, leg)
                    changed = True
                elif aux[o + A_STRUT] < 0.0:
                    mi[MI_CONTACT_B + leg] = STICK
                    nev = log_event(ev, nev, t, EK_STRUT_END, leg, 0.0, 0.0, 0.0)
                    changed = True
            elif mode == SLIDE:
                if jammed_slide_moving(s, P, mi, aux, leg):
                    # a moving toe whose slide is jammed (a touchdown or a toe stub that
                    # lands sliding beyond the friction angle of its slide): no rule of the
                    # slide applies (its forces, G_n = F / share, mean nothing there). Its
                    # jam event, armed below zero (hybrid.arm_jams), fires at this instant
                    # and stops it with the jam's impact (docs/model.md "A sliding toe
                    # that jams"); lifting it off instead sends a toe that moves into the
                    # ground back to a stub slide, round and round
                    pass
                elif (gn < gn_tol or aux[o + A_FAX] <= 0.0) and not slide_toe_pressed(
                    s, ds, aux, P, leg
                ):
                    # (a slide at the stop whose toe is pressed into the ground starts with
                    # its leg force at zero, to rounding, and loads as the leg is swept on)
                    nev = lift_off(t, s, mi, ev, nev, leg)
                    changed = True
                elif coulomb and aux[o + A_SLIP_V] * mi[MI_SLIDE_DIR_B + leg] < -SLIDE_SPEED_TOL:
                    # the toe slides against its recorded direction (its velocity jumped, e.g.
                    # at the other leg's touchdown impact): friction opposes the motion it
                    # has, so the direction follows the velocity. Pinning the moving toe
                    # instead would take an impulse that the sliding contact cannot give
                    # (the massless toe on its compliant leg carries none).
                    mi[MI_SLIDE_DIR_B + leg] = -mi[MI_SLIDE_DIR_B + leg]
                    changed = True
                elif (
                    slide_is_jammed(s[ITH] + s[IPHB + leg], mi[MI_SLIDE_DIR_B + leg], P)
                    and abs(aux[o + A_SLIP_V]) <= SLIDE_SPEED_TOL
                ):
                    # a toe at rest whose slide is jammed (docs/model.md "A sliding toe
                    # that jams") cannot start it: it is pinned where it is (no impulse:
                    # it is at rest). A moving one jams through its event (hybrid.arm_jams
                    # arms it), with the impact that stops it.
                    nev = stick_toe(t, mi, mf, aux, ev, nev, leg)
                    changed = True
            if joint_has_stiction(leg, P):
                mm = mi[MI_MOTOR_B + leg]
                if mm == STUCK:
                    hold = aux[o + A_HOLD]
                    if abs(hold) > P[P_TAU_S + leg] * (1.0 + 1e-9):
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
    evaluate_ws(s, P, mi, mf, cmd, ds, aux, ew, False, ew[3], True)
    return nev


@allocating
def touchdown(t, s, P, mi, mf, leg, aux, ev, nev, stats, imp):
    """Pin the toe where it touched the ground and apply the impact (docs/specification.md section 3)."""
    o = leg * NAUX_LEG
    mf[MF_ANCHOR_B + leg] = aux[o + A_TOE_X]
    mi[MI_CONTACT_B + leg] = STICK
    s_pre = s.copy()
    mi_pre = mi.copy()
    ok = impact(s, P, mi, mf, imp)
    if (
        ok
        and not is_set(P[P_MASSLESS])
        and s[IL_B + leg] >= P[P_L0 + leg] * (1.0 - 1e-12)
        and stance_leg_rate(s, P, leg) > LEG_STOP_SPEED_TOL
    ):
        # the toe lands with the leg at its stop while the hip moves away from it: the
        # massless toe cannot slide out beyond the stop, so the stop takes an impulse as
        # well (the leg lands as a rigid strut, docs/specification.md section 3); settle() makes it a spring leg
        # again once the strut is in compression
        for i in range(s.shape[0]):
            s[i] = s_pre[i]
        for i in range(mi.shape[0]):
            mi[i] = mi_pre[i]
        mi[MI_CONTACT_B + leg] = STRUT
        stats[S_NSTRUT] += 1
        ok = impact(s, P, mi, mf, imp)
    pn = imp[leg * NIMP_LEG + IMP_NORMAL]
    pt = imp[leg * NIMP_LEG + IMP_TANGENT]
    if toe_can_slip(P) and not is_set(P[P_MASSLESS]) and abs(pt) > P[P_MU] * pn:
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
    nev = log_event(ev, nev, t, EK_TOUCHDOWN, leg, pn, pt, imp[IMP_ENERGY_LOST])
    return nev, ok


@allocating
def jam(t, s, P, mi, mf, leg, aux, ev, nev, imp):
    """A sliding toe jams (its ground force, on the edge of the friction cone, has turned
    perpendicular to the leg: contact.slide_axial_share at its jam level): the slide cannot
    go on without an unbounded normal force, so it ends in an impact without collision. The
    toe is pinned where it is and the impact onto the pinned toe's row is applied
    (model/impact.py): its impulse acts along the leg's normal, which at the jam lies on
    the edge of the friction cone (within contact.JAM_AXIAL_SHARE), opposing the slide: the
    impulse Coulomb friction gives a toe it stops. Logged as EK_JAM with the impulses and
    the kinetic energy lost; settle() then makes the modes agree with the forces (docs/model.md
    "A sliding toe that jams"). Returns (event count, ok)."""
    o = leg * NAUX_LEG
    mf[MF_ANCHOR_B + leg] = aux[o + A_TOE_X]
    mi[MI_CONTACT_B + leg] = STICK
    ok = impact(s, P, mi, mf, imp)
    nev = log_event(
        ev,
        nev,
        t,
        EK_JAM,
        leg,
        imp[leg * NIMP_LEG + IMP_NORMAL],
        imp[leg * NIMP_LEG + IMP_TANGENT],
        imp[IMP_ENERGY_LOST],
    )
    return nev, ok


@kernel
def apply_event(k, t, s, P, mi, mf, aux, ev, nev, stats, imp):
    """Mode transition for event slot k at time t (state s already at the event)."""
    ok = True
    if is_contact_event(k):
        leg = event_leg(k)
        slot = event_slot(k)
        mode = mi[MI_CONTACT_B + leg]
        o = leg * NAUX_LEG
        if mode == FLIGHT:
            nev, ok = touchdown(t, s, P, mi, mf, leg, aux, ev, nev, stats, imp)
        elif mode == STICK:
            if slot == EVC_GROUND:
                # normal force reached zero: lift-off, or a slide if the leg still pushes
                nev = release_pin(t, s, P, mi, aux, ev, nev, stats, leg)
            elif slot == EVC_STOP_OR_REST:
                mi[MI_CONTACT_B + leg] = STRUT
                stats[S_NSTRUT] += 1
                nev = log_event(ev, nev, t, EK_STRUT_START, leg, aux[o + A_GN], 0.0, 0.0)
            else:
                nev = slide_from_pin(t, mi, aux, ev, nev, leg, SLIDE_CAUSE_CONE)
        elif mode == SLIDE:
            if slot == EVC_GROUND:
                nev = lift_off(t, s, mi, ev, nev, leg)
            elif slot == EVC_CONE:
                nev, ok = jam(t, s, P, mi, mf, leg, aux, ev, nev, imp)
            else:
                # slide velocity reached zero: stick here; settle() slides on (possibly
                # reversed) if the friction cone cannot hold the toe
                nev = stick_toe(t, mi, mf, aux, ev, nev, leg)
        elif mode == STRUT:
            if slot == EVC_GROUND:
                nev = lift_off(t, s, mi, ev, nev, leg)
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
        nev = log_event(ev, nev, t, EK_FALL, -1, s[IY], s[ITH], 0.0)
    return nev, ok


@kernel(inline="always")
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
