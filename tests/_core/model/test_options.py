"""The effects beyond the paper's models (docs/model.md "Effects beyond the paper's
models"), each against a special case derived by hand from its definition there. Each is
also in the work-energy balance with every option on (tests/analysis/test_energy.py) and
in the reference-evaluator parity (tests/_core/model/test_evaluate.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import scoutsim
from scoutsim._core.model import layout as L
from scoutsim.identification.rigs import Stall, stall_deflection

ROBOT = scoutsim.RobotParameters()
N = ROBOT.planetary_ratio * ROBOT.sprocket_ratio
ETA = ROBOT.gearbox_efficiency * ROBOT.sprocket_efficiency


@pytest.mark.parametrize("play_deg", [1.5, 4.0])
def test_backlash_adds_half_the_play_to_the_stall_deflection(play_deg):
    """belt_backlash b: the spring acts on the deflection beyond the dead zone |delta| <=
    b / 2, so the held hip unit settles at (tau - N tau_s) / k_b + b / 2 (the lower edge of
    the stiction band, as without play)."""
    b = math.radians(play_deg)
    robot = ROBOT.replace(belt_backlash=b)
    tau = N * ETA * ROBOT.torque_constant * ROBOT.current_limit
    expected = (tau - N * ROBOT.joint_stiction) / ROBOT.belt_stiffness + b / 2.0
    d = stall_deflection(robot, Stall(duration=8.0))
    assert d["deflection_final_rad"] == pytest.approx(expected, rel=2e-3)


def test_leg_friction_shifts_the_flight_leg_rest_to_fc_over_k():
    """leg_friction_force F_c: in flight the massless toe's force balance
    k (l0 - l) = c l' + F_c (regularised linearly below v_r = 1 mm/s) makes the leg
    re-extend towards a compression of F_c / k instead of 0: while the spring beats the
    friction by more than c v_r, (l0 - l) - F_c / k decays as exp(-k t / c); after that the
    leg creeps, at less than v_r, and stays above F_c / k less the creep."""
    fc = 10.0
    robot = ROBOT.replace(leg_friction_force=fc)
    r = scoutsim.simulate(robot, duration=3.0, model="I")
    dt = r.provenance["control_period_s"]
    v_r = 1e-3
    rest = fc / ROBOT.leg_stiffness  # 2.84 mm
    upper = (fc + ROBOT.leg_damping * v_r) / ROBOT.leg_stiffness  # 2.857 mm
    fast, creep = [], []
    for k, leg in enumerate(L.LEG_NAMES):
        flight = r.modes[:, L.RM_CONTACT_B + k] == L.FLIGHT
        comp = ROBOT.leg_rest_length - r.leg_length(leg)
        i = np.nonzero(flight[:-1] & flight[1:] & (comp[:-1] > 0.0))[0]
        f = i[comp[i + 1] > 1.01 * upper]
        fast.append(-np.log((comp[f + 1] - rest) / (comp[f] - rest)) / dt)
        c = i[comp[i] <= upper]
        creep.append((comp[c] - comp[c + 1]) / dt)
    fast, creep = np.concatenate(fast), np.concatenate(creep)
    assert len(fast) > 100 and len(creep) > 50
    # measured: within 3.6e-10 of k / c
    assert np.allclose(fast, ROBOT.leg_stiffness / ROBOT.leg_damping, rtol=1e-8)
    # the creep rate is at most v_r by construction (measured up to 0.99982 v_r)
    assert np.all(creep >= 0.0) and np.all(creep <= v_r * (1.0 + 1e-9))


def test_angle_dependent_damping_sets_the_flight_relaxation_rate():
    """leg_damping_angle_coefficient a: the damper is c (1 + a phi^2), so a massive leg's
    toe relaxes in flight as l' = k (l0 - l) / (c (1 + a phi^2)): over one 1 ms sample
    ln of the compression falls by k dt / (c (1 + a phi^2)) at the sample's mid angle."""
    a = 0.5 / math.radians(30.0) ** 2
    robot = ROBOT.replace(leg_damping_angle_coefficient=a)
    r = scoutsim.simulate(robot, duration=2.0, model="I")
    dt = r.provenance["control_period_s"]
    rates, expected = [], []
    for k, leg in enumerate(L.LEG_NAMES):
        flight = r.modes[:, L.RM_CONTACT_B + k] == L.FLIGHT
        comp = ROBOT.leg_rest_length - r.leg_length(leg)
        phi = r.leg_angle(leg)
        both = flight[:-1] & flight[1:] & (comp[:-1] > 1e-4) & (comp[1:] > 1e-4)
        i = np.nonzero(both)[0]
        rates.append(-np.log(comp[i + 1] / comp[i]) / dt)
        mid = 0.5 * (phi[i] + phi[i + 1])
        expected.append(ROBOT.leg_stiffness / (ROBOT.leg_damping * (1.0 + a * mid * mid)))
    rates, expected = np.concatenate(rates), np.concatenate(expected)
    assert len(rates) > 50
    # the angle matters here: the damping factor varies by more than 5 % over the samples
    assert expected.max() / expected.min() > 1.05
    # measured: within 2.9e-5 (the mid-sample angle stands for the angle over the sample)
    assert np.allclose(rates, expected, rtol=3e-4)


def test_gearbox_losses_oppose_the_power_flow():
    """gearbox_idle_loss_torque tau_i, gearbox_load_loss_coefficient c (docs/model.md
    "Transmission losses"): away from the blending band (|w_m| >= 1 rad/s), motoring
    (tau_0 w_m > 0) delivers |tau_out| = max(|tau_0| - tau_i, 0) / (1 + c) with the sign of
    tau_0, and back-driven the output must carry (|tau_0| + tau_i) / (1 - c) against the
    motion, tau_out = -sign(w_m) (|tau_0| + tau_i) / (1 - c); tau_0 = N eta K_T i."""
    ti, c = 0.3, 0.05
    robot = ROBOT.replace(gearbox_idle_loss_torque=ti, gearbox_load_loss_coefficient=c)
    r = scoutsim.simulate(robot, duration=2.0, model="I")
    n_motor = n_back = 0
    for leg in L.LEG_NAMES:
        tau0 = N * ETA * ROBOT.torque_constant * r.motor_current(leg)
        w = r.motor_speed(leg)
        out = r.hip_torque_applied(leg)
        away = np.abs(w) >= 1.0
        motoring = away & (tau0 * w > 0.0)
        back = away & (tau0 * w <= 0.0)
        mag = np.maximum(np.abs(tau0) - ti, 0.0) / (1.0 + c)
        assert np.allclose(out[motoring], (np.sign(tau0) * mag)[motoring], rtol=1e-12, atol=1e-12)
        assert np.allclose(
            out[back], (-np.sign(w) * (np.abs(tau0) + ti) / (1.0 - c))[back], rtol=1e-12
        )
        n_motor += motoring.sum()
        n_back += back.sum()
    assert n_motor > 100 and n_back > 100
