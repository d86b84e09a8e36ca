"""The work-energy accounting of a step (scoutsim/_core/numerics/step_energy.py).

Laws checked: the energy of every power flow over a step is the method's own quadrature of
the power at its stages, h sum_j b_j P(Y_j), i.e. the method applied to the energies as
components of the state that never feed back: so the accounting leaves the motion the same
bit for bit; the power at a stage, read from the stage's evaluation, is the power of a full
evaluation at that state; the balance (input = losses + change of mechanical energy)
closes to the integration error of every method and converges as the tolerance shrinks;
and a rejected step, or a step redone to an event's instant, counts once.
"""

import math

import numpy as np
import pytest

import scoutsim
from scoutsim import IntegratorSettings, RobotParameters
from scoutsim._core.model import layout as L
from scoutsim._core.model.evaluate import evaluate_ws
from scoutsim._core.model.kinematics import project_state
from scoutsim._core.model.packing import robot_array
from scoutsim._core.numerics.dopri5 import eval_workspace
from scoutsim._core.numerics.step_energy import add_stage, begin_step, power_at, take_step
from scoutsim._core.numerics.work import StepEnergy

from ..sample_modes import sample_modes

METHODS = {
    "ark3": IntegratorSettings(method="ark3"),
    "ark4": IntegratorSettings(method="ark4", rtol=1e-5, atol=1e-6),
    "dopri5": IntegratorSettings(method="dopri5"),
}


def _step_energy():
    return StepEnergy(*(np.zeros(L.NEN) for _ in range(4)))


@pytest.mark.parametrize(
    "model, method, mu",
    [
        ("II", "ark3", 1.0),
        ("II", "ark3", math.inf),
        ("II", "ark4", 1.0),
        ("II", "dopri5", 1.0),
        ("I", "dopri5", math.inf),
    ],
)
def test_the_accounting_leaves_the_motion_unchanged(model, method, mu):
    """The accounting only reads the stages' evaluations: the samples, the events and the
    integrator's statistics are the same bit for bit with and without it, for every method,
    on a floor where the toes slide and on one where they land with impacts."""
    kw = dict(duration=1.5, model=model, friction_coefficient=mu, integrator=METHODS[method])
    a = scoutsim.simulate(**kw)
    b = scoutsim.simulate(energy=True, **kw)
    assert a.outcome == b.outcome == "completed"
    assert b.energy_flows is not None
    assert np.array_equal(a.t, b.t)
    assert np.array_equal(a.state, b.state)
    assert np.array_equal(a.aux, b.aux)
    assert np.array_equal(a.events, b.events, equal_nan=True)
    for k, v in a.stats.items():
        if k != "wall_time_s":
            assert b.stats[k] == v, k


def _sampled_evaluations(model, robot, mu):
    """Parameters and (state, modes, anchors, command) at samples of a short run, each with
    the motor-joint modes stuck and slipping and the contact modes pinned, strut, sliding
    and in flight substituted."""
    r = scoutsim.simulate(robot, duration=0.4, model=model, friction_coefficient=mu)
    P = robot_array(robot or RobotParameters(), model, friction_coefficient=mu)
    out = []
    for n in range(0, len(r.t), 10):
        mi, mf, cmd = sample_modes(r, n, 1 if n % 20 else -1)
        for motor in (None, [0, 0], [1, -1]):
            for contact in (None, [L.STICK, L.STRUT], [L.SLIDE, L.FLIGHT]):
                m = mi.copy()
                if motor is not None:
                    m[L.MI_MOTOR_B : L.MI_MOTOR_B + 2] = motor
                if contact is not None:
                    m[L.MI_CONTACT_B : L.MI_CONTACT_B + 2] = contact
                out.append((r.state[n].copy(), m, mf, cmd))
    return P, out


def _flows_from_outputs(P, mi, s, ds, aux):
    """The power flows that the outputs of an evaluation at the (projected) state ``s``
    give, by the formulas of
    docs/model.md "Work-energy balance" (per leg: electrical, copper, conversion, gear
    loss, hip work, joint friction, leg damper and friction, toe sliding; the battery's
    loss), as {(slot, leg or None): W}."""
    out = {}
    npl, model = P[L.P_NP], int(P[L.P_MODEL])
    p_el = 0.0
    for leg in range(2):
        o = leg * L.NAUX_LEG
        cur, om, tout = aux[o + L.A_CURRENT], aux[o + L.A_OMEGA_M], aux[o + L.A_TAU_APP]
        N, eta, kt = P[L.P_N + leg], P[L.P_ETA + leg], P[L.P_KT + leg]
        ra, kw = P[L.P_RA + leg], P[L.P_KW + leg]
        if model != L.MODEL_PASSIVE:
            out[(L.EN_ELECTRICAL, leg)] = npl * cur * (ra * cur + kw * om)
            out[(L.EN_COPPER, leg)] = npl * ra * cur * cur
            out[(L.EN_CONVERSION, leg)] = npl * (kw - eta * kt) * cur * om
            out[(L.EN_GEAR_LOSS, leg)] = npl * (N * eta * kt * cur - tout) * om / N
            out[(L.EN_HIP_WORK, leg)] = npl * tout * om / N
            p_el += out[(L.EN_ELECTRICAL, leg)]
        if model == L.MODEL_II and mi[L.MI_MOTOR_B + leg] != L.STUCK:
            out[("joint", leg)] = npl * aux[o + L.A_HOLD] * om
        if mi[L.MI_CONTACT_B + leg] != L.STRUT:
            spring = npl * P[L.P_K + leg] * (P[L.P_L0 + leg] - s[L.IL_B + leg])
            out[("leg", leg)] = -(aux[o + L.A_FAX] - spring) * ds[L.IL_B + leg]
        out[(L.EN_TOE_SLIDE, leg)] = -aux[o + L.A_GT] * aux[o + L.A_SLIP_V]
    if model in (L.MODEL_I, L.MODEL_II) and P[L.P_RB] > 0.0:
        out[(L.EN_BATTERY_LOSS, None)] = P[L.P_RB] * (p_el / aux[L.A_VBATT]) ** 2
    return out


@pytest.mark.parametrize(
    "model, robot",
    [
        ("II", None),
        ("II", RobotParameters(battery_resistance=0.1, belt_backlash=0.01, leg_friction_force=6.0)),
        ("I", RobotParameters(battery_resistance=0.1)),
        ("ideal", None),
    ],
    ids=["II", "II_options", "I", "ideal"],
)
def test_a_stage_power_is_the_power_the_evaluation_outputs_give(model, robot):
    """An integrator stage is evaluated without its outputs, and its power flows are read
    from the evaluation's workspace (``add_stage``). They equal the flows computed from
    the outputs of a full evaluation at the same state (currents, motor speeds, delivered
    torques, friction torques, leg forces, ground forces, toe velocities, battery voltage)
    by the formulas of the balance, in every contact and motor-joint mode; the belt damper
    and the constraint work equal those read from the full evaluation."""
    P, cases = _sampled_evaluations(model, robot, 1.0)
    ew_full, ew_stage = eval_workspace(), eval_workspace()
    ds_full, ds_stage = np.zeros(L.NS), np.zeros(L.NS)
    aux_full, aux_stage = np.zeros(L.NAUX), np.full(L.NAUX, np.nan)
    p_full = np.zeros(L.NEN)
    en = _step_energy()
    compared = 0
    for s, mi, mf, cmd in cases:
        ok = evaluate_ws(s, P, mi, mf, cmd, ds_full, aux_full, ew_full, False, ew_full[3], True)
        if not ok:
            continue
        evaluate_ws(s, P, mi, mf, cmd, ds_stage, aux_stage, ew_stage, False, ew_stage[3], False)
        assert np.array_equal(ds_full, ds_stage)
        begin_step(0.0, en)
        add_stage(1.0, ds_stage, P, mi, ew_stage, en)
        p = en.quad
        sp = s.copy()
        project_state(sp, P, mi, mf)
        scale = 1.0 + np.max(np.abs(p))
        for (slot, leg), expected in _flows_from_outputs(P, mi, sp, ds_full, aux_full).items():
            if slot == "joint":
                got = (
                    p[leg * L.NEN_LEG + L.EN_JOINT_VISCOUS]
                    + p[leg * L.NEN_LEG + L.EN_JOINT_COULOMB]
                )
            elif slot == "leg":
                got = p[leg * L.NEN_LEG + L.EN_LEG_DAMPER] + p[leg * L.NEN_LEG + L.EN_LEG_FRICTION]
            elif leg is None:
                got = p[slot]
            else:
                got = p[leg * L.NEN_LEG + slot]
            assert abs(got - expected) <= 1e-12 * scale, (slot, leg, got, expected, mi)
            compared += expected != 0.0
        power_at(ds_full, P, mi, ew_full, p_full)
        for leg in range(2):
            for slot in (L.EN_BELT_DAMPER, L.EN_CONSTRAINT):
                i = leg * L.NEN_LEG + slot
                assert abs(p[i] - p_full[i]) <= 1e-12 * scale, (slot, leg)
    assert compared > 5 * len(cases)  # (there were flows to compare)


def test_a_taken_step_adds_its_quadrature_once():
    """begin_step / add_stage / take_step: the energy of a step is h sum_j b_j P_j, added to
    the run's energies when the step is taken, and the step's end becomes the next start."""
    en = _step_energy()
    rng = np.random.default_rng(3)
    p0, p1, p_end = (rng.normal(size=L.NEN) for _ in range(3))
    en.p_start[:] = p0
    en.p_end[:] = p_end
    begin_step(0.25, en)
    en.quad[:] += 0.75 * p1  # (what add_stage adds for a stage of weight 0.75)
    energy = np.ones(L.NEN)
    take_step(2e-3, en, energy)
    np.testing.assert_allclose(energy, 1.0 + 2e-3 * (0.25 * p0 + 0.75 * p1), rtol=1e-15)
    assert np.array_equal(en.p_start, p_end)


@pytest.mark.parametrize(
    "method, loose, tight",
    [
        ("ark3", (1e-5, 1e-6), (1e-7, 1e-9)),
        ("ark4", (1e-5, 1e-6), (1e-7, 1e-9)),
        ("dopri5", (1e-6, 1e-7), (1e-8, 1e-9)),
    ],
)
def test_the_residual_is_integration_error_and_converges(method, loose, tight):
    """The residual of the balance over 1 s of Model II bounding is the integration error:
    small at the looser tolerance and at least 30 x smaller at 100 x tighter ones
    (measured: ARK3 8.5e-7 -> 5.2e-9, ARK4 2.5e-6 -> 6.8e-9, DOPRI5 1.2e-8 -> 6.7e-11 of
    the input)."""
    res = []
    for rtol, atol in (loose, tight):
        r = scoutsim.simulate(
            duration=1.0,
            model="II",
            energy=True,
            integrator=IntegratorSettings(method=method, rtol=rtol, atol=atol),
        )
        res.append(abs(r.energy_balance().relative_residual))
    assert res[0] < (1e-5 if method != "dopri5" else 1e-7), res
    assert res[1] < res[0] / 30.0, res


@pytest.mark.parametrize("model", ["I", "II"])
def test_rejected_and_redone_steps_count_once(model):
    """On the no-slip floor (touchdown impacts: events whose step is redone to their
    instant) with the default integrator, hundreds of steps are rejected by the error
    control; each would add about a step's energy if it counted (some 10 % of the input).
    The balance closes to 1e-5 of the input (measured 1.2e-6 for Model II, 4e-10 for
    Model I over 2 s)."""
    r = scoutsim.simulate(duration=2.0, model=model, energy=True, friction_coefficient=math.inf)
    assert r.outcome == "completed"
    assert r.stats["rejected_steps"] > 100 and r.stats["events"] > 20
    assert r.energy_flows["impacts"] > 1.0
    b = r.energy_balance()
    assert abs(b.relative_residual) < 1e-5, b.table()
