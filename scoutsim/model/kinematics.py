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

from ..jit import kernel
from .hip_unit import geared
from .layout import (
    HIP_SIGN, IL_B, MF_ANCHOR_B, MI_CONTACT_B, MI_MOTOR_B, NQ, P_C, P_CLAMP_LEGS,
    P_CLAMP_TORSO, P_COM_OFFSET, P_L, P_L0, P_MASSLESS, P_TD_B, P_TD_WORLD, SLIDE, STICK, STRUT,
    STUCK,
)


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
    return q[0] + sL * math.cos(q[2]), q[1] + sL * math.sin(q[2])


@kernel
def hip_velocity(q, dq, P, leg):
    """Hip velocity [m/s]."""
    sL = hip_offset(P, leg)
    return dq[0] - sL * math.sin(q[2]) * dq[2], dq[1] + sL * math.cos(q[2]) * dq[2]


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
    :func:`~scoutsim.model.evaluate.evaluate_ws` to reuse.
    """
    gear = geared(P)
    massless = P[P_MASSLESS] > 0.5
    if P[P_CLAMP_TORSO] > 0.5:
        # bench rig: the clamped torso is at rest (add_clamp_rows)
        dq[0] = 0.0
        dq[1] = 0.0
        dq[2] = 0.0
        if P[P_CLAMP_LEGS] > 0.5:
            dq[3] = 0.0
            dq[4] = 0.0
    sth = math.sin(q[2])
    cth = math.cos(q[2])
    sg0 = 0.0
    cg0 = 1.0
    sg1 = 0.0
    cg1 = 1.0
    for leg in range(2):
        mode = mi[MI_CONTACT_B + leg]
        sL = hip_offset(P, leg)
        l0 = P[P_L0 + leg]
        hx = q[0] + sL * cth
        hy = q[1] + sL * sth
        hvx = dq[0] - sL * sth * dq[2]
        hvy = dq[1] + sL * cth * dq[2]
        if mode == STICK or mode == STRUT:
            px = mf[MF_ANCHOR_B + leg]
            ddx = px - hx
            ddy = -hy
            ll = math.sqrt(ddx * ddx + ddy * ddy)
            g = math.atan2(ddx, -ddy)
            sg = ddx / ll
            cg = -ddy / ll
            q[3 + leg] = g - q[2]
            dg = -(hvx * cg + hvy * sg) / ll
            dq[3 + leg] = dg - dq[2]
            l[leg] = ll
        elif mode == SLIDE:
            g = q[2] + q[3 + leg]
            sg = math.sin(g)
            cg = math.cos(g)
            l[leg] = hy / cg
        else:
            if massless:
                td = P[P_TD_B + leg]
                if P[P_TD_WORLD] > 0.5:
                    q[3 + leg] = td - q[2]
                    dq[3 + leg] = -dq[2]
                else:
                    q[3 + leg] = td
                    dq[3 + leg] = 0.0
                l[leg] = l0
            else:
                if P[P_C + leg] <= 0.0 or l[leg] > l0:
                    l[leg] = l0
            g = q[2] + q[3 + leg]
            sg = math.sin(g)
            cg = math.cos(g)
        if leg == 0:
            sg0 = sg
            cg0 = cg
        else:
            sg1 = sg
            cg1 = cg
        if not gear:
            q[5 + leg] = q[3 + leg]
            dq[5 + leg] = dq[3 + leg]
        elif mi[MI_MOTOR_B + leg] == STUCK:
            dq[5 + leg] = 0.0
    return sth, cth, sg0, cg0, sg1, cg1


@kernel
def project_state(s, P, mi, mf):
    """Project the dependent coordinates of a full state vector in place."""
    # views: project() writes the dependent coordinates straight into s
    project(s[0:NQ], s[NQ:2 * NQ], s[IL_B:IL_B + 2], P, mi, mf)
