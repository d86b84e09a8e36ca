"""Power flows of the hybrid model (compiled): where the energy the motors draw goes.

For the work-energy balance of a run (``simulate(energy=True)``,
``SimulationResult.energy_balance``, docs/model.md "Work-energy balance"): at a state and
its evaluation, every power flow [W] of the model, per virtual leg (both motors of a leg
together), into the slots of ``layout.EN_*``. The integrator integrates them over each of
its steps, at the stages of the step (``scoutsim._core.numerics.step_energy``); the impact
losses come from the touchdown records.

Per motor, with current i, motor speed w_m (relative to the torso), delivered torque
tau_out and the paper's constant-efficiency torque tau_0 = N eta K_T i (docs/specification.md
section 4):

* electrical power at the terminals  i (R_A i + K_w w_m)
  = copper R_A i^2 + conversion (K_w - eta K_T) i w_m + gear loss (tau_0 - tau_out) w_m / N
  + hip work tau_out w_m / N (an identity, term by term);
* the conversion term is the paper's efficiency eta applied in both directions: while a leg
  back-drives its motor (i w_m < 0) it is negative, a *source*: the electrical power the
  motor generates, K_w |i w_m|, is 1/eta times the mechanical power eta K_T |i w_m| the leg
  puts in (K_w = K_T);
* the hip work goes into the mechanical system, where it is stored (kinetic energy, gravity,
  leg and belt springs) or dissipated: motor-joint friction, belt damper, leg damper and leg
  friction, a sliding toe's friction, constraint forces (zero for exact constraints), and
  the touchdown impacts.

The dissipations are computed from the forces *as they acted* in the evaluation (the axial
leg force, the belt torque, the joint friction torque, the ground force, the constraint
multipliers) times the velocities they act through, at the state as the evaluation
projected it, all read from the evaluation's workspace (its per-leg scalars ``LG_*``, the
outputs ``A_*`` are copies of: so the power of an integrator stage, evaluated without its
outputs, is read as that of any evaluation), so the balance checks that every force enters
the equations of motion with the power it claims.
"""

from __future__ import annotations

from ..._numba.jit import kernel
from .hip_unit import belt_spring, geared
from .layout import (
    EN_BATTERY_LOSS,
    EN_BELT_DAMPER,
    EN_CONSTRAINT,
    EN_CONVERSION,
    EN_COPPER,
    EN_ELECTRICAL,
    EN_GEAR_LOSS,
    EN_HIP_WORK,
    EN_JOINT_COULOMB,
    EN_JOINT_VISCOUS,
    EN_LEG_DAMPER,
    EN_LEG_FRICTION,
    EN_TOE_SLIDE,
    IALB,
    IL_B,
    IPHB,
    MI_CONTACT_B,
    MI_MOTOR_B,
    MODEL_IDEAL,
    MODEL_PASSIVE,
    NEN_LEG,
    NQ,
    P_B_J,
    P_ETA,
    P_K,
    P_KB,
    P_KT,
    P_KW,
    P_L0,
    P_MODEL,
    P_N,
    P_NP,
    P_RA,
    P_RB,
    STRUT,
    STUCK,
)
from .leg import leg_damping
from .workspace import (
    LG_CUR,
    LG_FAX,
    LG_GT,
    LG_OM,
    LG_TAPP,
    LG_TBELT,
    LG_TFRIC,
    LG_TOEVX,
    MT_NROWS,
    MT_VBATT,
    WA_R,
    WK_B,
    WK_DQ,
    WK_L,
    WK_LEG,
    WK_META,
    WK_Q,
    WK_RLEG,
)


@kernel(inline="always")
def power_flows(ds, P, mi, wk, wA, out):
    """Every power flow [W] of the model into ``out`` (layout ``EN_*``), from an evaluation
    (:func:`~scoutsim._core.model.evaluate.evaluate_ws`, with or without its outputs, or
    :func:`~scoutsim._core.model.evaluate.evaluate_command_change`) held in its workspace
    ``wk, wA`` (the projected state and velocities, the per-leg forces, currents and
    speeds, the battery voltage, the constraint rows and multipliers) and its derivative
    ``ds``."""
    model = int(P[P_MODEL])
    npl = P[P_NP]
    for i in range(out.shape[0]):
        out[i] = 0.0
    q = wk[WK_Q : WK_Q + NQ]
    dq = wk[WK_DQ : WK_DQ + NQ]
    lengths = wk[WK_L : WK_L + 2]
    LG = wk[WK_LEG:]
    p_el_total = 0.0
    for leg in range(2):
        e = leg * NEN_LEG
        mode = mi[MI_CONTACT_B + leg]
        N = P[P_N + leg]
        if model != MODEL_PASSIVE:
            cur = LG[2 * LG_CUR + leg]
            om = LG[2 * LG_OM + leg]
            tout = LG[2 * LG_TAPP + leg]
            tau0 = N * P[P_ETA + leg] * P[P_KT + leg] * cur
            p_el = npl * cur * (P[P_RA + leg] * cur + P[P_KW + leg] * om)
            out[e + EN_ELECTRICAL] = p_el
            out[e + EN_COPPER] = npl * P[P_RA + leg] * cur * cur
            out[e + EN_CONVERSION] = (
                npl * (P[P_KW + leg] - P[P_ETA + leg] * P[P_KT + leg]) * cur * om
            )
            out[e + EN_GEAR_LOSS] = npl * (tau0 - tout) * om / N
            out[e + EN_HIP_WORK] = npl * tout * om / N
            p_el_total += p_el
        if geared(P):
            om = LG[2 * LG_OM + leg]
            if mi[MI_MOTOR_B + leg] != STUCK:
                # the joint's friction torque as it acted (viscous + Coulomb)
                p_joint = npl * LG[2 * LG_TFRIC + leg] * om
                p_visc = npl * P[P_B_J + leg] * om * om
                out[e + EN_JOINT_VISCOUS] = p_visc
                out[e + EN_JOINT_COULOMB] = p_joint - p_visc
            rate = dq[IALB + leg] - dq[IPHB + leg]
            spring = P[P_KB + leg] * belt_spring(q[IALB + leg] - q[IPHB + leg], leg, P)[0]
            out[e + EN_BELT_DAMPER] = npl * (LG[2 * LG_TBELT + leg] - spring) * rate
        # telescopic leg: the axial force as it acted, less its spring part, through the
        # leg's rate of extension (in flight the massless toe's force balance makes the
        # axial force zero: the spring's power is all dissipated)
        ld = ds[IL_B + leg]
        ll = lengths[leg]
        f_spring = npl * P[P_K + leg] * (P[P_L0 + leg] - ll)
        if mode != STRUT:
            p_leg = -(LG[2 * LG_FAX + leg] - f_spring) * ld
            p_damp = npl * leg_damping(q[IPHB + leg], leg, P) * ld * ld
            out[e + EN_LEG_DAMPER] = p_damp
            out[e + EN_LEG_FRICTION] = p_leg - p_damp
        # (a pinned toe does not move: its velocity slot is zero)
        out[e + EN_TOE_SLIDE] = -LG[2 * LG_GT + leg] * LG[2 * LG_TOEVX + leg]
    # constraint forces: generalized force -R^T nu through dq, by the leg of each row
    nr = int(wk[WK_META + MT_NROWS])
    nact = 7 if geared(P) else 5
    for rr in range(nr):
        rdq = 0.0
        for j in range(nact):
            rdq += wA[WA_R + rr, j] * dq[j]
        leg = int(wk[WK_RLEG + rr])
        if leg < 0 or leg > 1:
            leg = 0
        # nu R dq: minus the power of the generalized constraint force -R^T nu
        out[leg * NEN_LEG + EN_CONSTRAINT] += wk[WK_B + nact + rr] * rdq
    if model != MODEL_IDEAL and model != MODEL_PASSIVE and P[P_RB] > 0.0:
        vb = wk[WK_META + MT_VBATT]
        ib = p_el_total / vb
        out[EN_BATTERY_LOSS] = P[P_RB] * ib * ib
