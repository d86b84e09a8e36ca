"""Kinematics of the planar model (compiled): hip positions and velocities, and the
projection of the dependent coordinates onto the active constraints.

Coordinates and signs (docs/specification.md section 1): x forward, y up, pitch theta
counter-clockwise (nose up) positive; leg angle phi relative to the torso, positive with the
toe ahead of the hip; g = theta + phi the leg's angle from the world vertical; the toe of a
leg of length l is at hip + l (sin g, -cos g). The back hip is at -L - e, the front hip at
L - e along the torso axis from the torso COM (L = hip_spacing / 2, e = com_offset, the
COM's distance ahead of the hips' midpoint; :func:`hip_offset`).
"""

from __future__ import annotations

import math

from ..._numba.jit import kernel
from .flags import is_set
from .hip_unit import geared
from .layout import (
    HIP_SIGN,
    IALB,
    IL_B,
    IPHB,
    IPHF,
    ITH,
    IX,
    IY,
    MF_ANCHOR_B,
    MI_CONTACT_B,
    MI_MOTOR_B,
    NQ,
    P_C,
    P_CLAMP_LEGS,
    P_CLAMP_TORSO,
    P_COM_OFFSET,
    P_L,
    P_L0,
    P_MASSLESS,
    P_TD_B,
    P_TD_WORLD,
    SLIDE,
    STICK,
    STRUT,
    STUCK,
)
from .leg import held_at_stop


@kernel(inline="always")
def hip_offset(P, leg):
    """Position [m] of virtual leg ``leg``'s hip along the torso axis, measured from the
    torso COM: HIP_SIGN[leg] L - e, i.e. -L - e (back) and L - e (front), with
    L = hip_spacing / 2 and e = com_offset, the COM's distance ahead of the hips' midpoint
    (docs/specification.md section 1)."""
    return HIP_SIGN[leg] * P[P_L] - P[P_COM_OFFSET]


@kernel
def hip_position(q, P, leg):
    """Hip position (hx, hy) [m] of virtual leg ``leg`` (0 back, 1 front)."""
    sL = hip_offset(P, leg)
    return q[IX] + sL * math.cos(q[ITH]), q[IY] + sL * math.sin(q[ITH])


@kernel
def hip_velocity(q, dq, P, leg):
    """Hip velocity [m/s]."""
    sL = hip_offset(P, leg)
    return dq[IX] - sL * math.sin(q[ITH]) * dq[ITH], dq[IY] + sL * math.cos(q[ITH]) * dq[ITH]


@kernel(inline="always")
def project(q, dq, l, P, mi, mf):
    """Make the dependent coordinates consistent with the active constraints (in place).

    * stance (stick/strut) leg: phi and dphi from the toe anchor and the hip, l = |toe - hip|;
    * sliding leg: l from the toe height being zero;
    * massless leg in flight: phi prescribed (touchdown angle, torso- or world-referenced),
      l = l0;
    * massive leg in flight: l limited to the stop l0 (and = l0 for an undamped leg);
    * rigid hip unit (ideal / Model I / passive): alpha := phi; a geared unit's (Model II)
      stuck motor joint: dalpha = 0.

    Returns (sin theta, cos theta, sin g_b, cos g_b, sin g_f, cos g_f) of the projected
    configuration, g = theta + phi the leg's angle from the world vertical (for a pinned
    toe straight from the toe-hip vector), for
    :func:`~scoutsim._core.model.evaluate.evaluate_ws` to reuse.
    """
    gear = geared(P)
    massless = is_set(P[P_MASSLESS])
    if is_set(P[P_CLAMP_TORSO]):
        # bench rig: the clamped torso is at rest (add_clamp_rows)
        dq[IX] = 0.0
        dq[IY] = 0.0
        dq[ITH] = 0.0
        if is_set(P[P_CLAMP_LEGS]):
            dq[IPHB] = 0.0
            dq[IPHF] = 0.0
    sth = math.sin(q[ITH])
    cth = math.cos(q[ITH])
    sg0 = 0.0
    cg0 = 1.0
    sg1 = 0.0
    cg1 = 1.0
    for leg in range(2):
        mode = mi[MI_CONTACT_B + leg]
        sL = hip_offset(P, leg)
        l0 = P[P_L0 + leg]
        hx = q[IX] + sL * cth
        hy = q[IY] + sL * sth
        hvx = dq[IX] - sL * sth * dq[ITH]
        hvy = dq[IY] + sL * cth * dq[ITH]
        if mode == STICK or mode == STRUT:
            px = mf[MF_ANCHOR_B + leg]
            ddx = px - hx
            ddy = -hy
            ll = math.sqrt(ddx * ddx + ddy * ddy)
            g = math.atan2(ddx, -ddy)
            sg = ddx / ll
            cg = -ddy / ll
            q[IPHB + leg] = g - q[ITH]
            dg = -(hvx * cg + hvy * sg) / ll
            dq[IPHB + leg] = dg - dq[ITH]
            l[leg] = ll
        elif mode == SLIDE:
            g = q[ITH] + q[IPHB + leg]
            sg = math.sin(g)
            cg = math.cos(g)
            l[leg] = hy / cg
        else:
            if massless:
                td = P[P_TD_B + leg]
                if is_set(P[P_TD_WORLD]):
                    q[IPHB + leg] = td - q[ITH]
                    dq[IPHB + leg] = -dq[ITH]
                else:
                    q[IPHB + leg] = td
                    dq[IPHB + leg] = 0.0
                l[leg] = l0
            else:
                if held_at_stop(P[P_C + leg], l0, l[leg]):
                    l[leg] = l0
            g = q[ITH] + q[IPHB + leg]
            sg = math.sin(g)
            cg = math.cos(g)
        if leg == 0:
            sg0 = sg
            cg0 = cg
        else:
            sg1 = sg
            cg1 = cg
        if not gear:
            q[IALB + leg] = q[IPHB + leg]
            dq[IALB + leg] = dq[IPHB + leg]
        elif mi[MI_MOTOR_B + leg] == STUCK:
            dq[IALB + leg] = 0.0
    return sth, cth, sg0, cg0, sg1, cg1


@kernel
def project_state(s, P, mi, mf):
    """Project the dependent coordinates of a full state vector in place."""
    # views: project() writes the dependent coordinates straight into s
    project(s[0:NQ], s[NQ : 2 * NQ], s[IL_B : IL_B + 2], P, mi, mf)
