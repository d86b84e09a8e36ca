"""The work-energy balance (scoutsim.analysis.energy, scoutsim._core.model.power_flows).

Law checked: the energy the motors draw equals the change of mechanical energy plus every
loss (docs/model.md "Work-energy balance"). The energies are integrated alongside the
motion, so the balance closes to the integration error: a force that enters the equations
of motion with a power other than the one it is accounted with (a sign error in a damper,
a friction law or a transmission loss) leaves a residual of the size of that power.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import scoutsim
from scoutsim._core.model import layout as L
from scoutsim.simulation.integrator import IntegratorSettings
from scoutsim.validation.make_example import VIRTUAL_SCOUT_EFFECTS

#: every option beyond the paper's models switched on, and a battery with internal
#: resistance
OPTIONS = dict(VIRTUAL_SCOUT_EFFECTS, battery_resistance=0.1)
#: the reference integrator (DOPRI5, rtol 1e-8): residuals measured 2.7e-11 .. 4.9e-10 of
#: the input over these 12 runs (10 s each)
REFERENCE = IntegratorSettings(method="dopri5")
FLOORS = {"coulomb": None, "no_slip": math.inf}


def _run(model, robot=None, floor="coulomb", duration=10.0, integrator=REFERENCE, **kw):
    return scoutsim.simulate(
        robot,
        duration=duration,
        model=model,
        integrator=integrator,
        friction_coefficient=FLOORS[floor],
        energy=True,
        **kw,
    )


@pytest.mark.parametrize("options", [False, True], ids=["default_robot", "every_option"])
@pytest.mark.parametrize("floor", list(FLOORS))
@pytest.mark.parametrize("model", ["ideal", "I", "II"])
def test_balance_closes(model, floor, options):
    """Input = losses + change of mechanical energy, to 1e-6 of the input, over 10 s of
    bounding with the reference integrator, for every actuated model on both floors, with
    the default robot and with every option beyond the paper's models on."""
    robot = scoutsim.RobotParameters().replace(**OPTIONS) if options else None
    r = _run(model, robot, floor)
    assert r.outcome == "completed"
    b = r.energy_balance()
    assert b.input_J > 100.0  # the motors did work (about 30-60 W)
    assert abs(b.relative_residual) < 1e-6, b.table()
    # what each floor and option switches on is in the balance (and nothing else)
    assert (b.term("impacts") > 1.0) == (floor == "no_slip")
    assert (b.term("toe_sliding") > 1.0) == (floor == "coulomb")
    assert (b.term("leg_friction") > 1.0) == options
    assert (b.battery_loss_J > 1.0) == (options and model != "ideal")
    assert (b.term("joint_friction") > 1.0) == (model == "II")
    assert (b.term("belt_damper") > 1.0) == (model == "II")
    if model != "ideal":
        assert abs(b.term("transmission")) > 1.0
    # the constraint forces of the contact modes do no work
    assert abs(b.term("constraint_work")) < 1e-9 * b.input_J


def test_every_dissipation_dissipates():
    """Each damper and friction takes energy out of the motion (positive term), and the
    battery gives the motors' energy plus its own loss."""
    r = _run("II", scoutsim.RobotParameters().replace(**OPTIONS))
    b = r.energy_balance()
    for name in (
        "copper",
        "joint_friction",
        "belt_damper",
        "leg_damper",
        "leg_friction",
        "toe_sliding",
    ):
        assert b.term(name) > 0.0, name
    assert b.battery_J == pytest.approx(b.input_J + b.battery_loss_J, rel=1e-12)


def test_passive_massless_legs_conserve_energy():
    """The massless-leg passive model is conservative: no flow, no loss, no change of
    mechanical energy (docs/specification.md section 2)."""
    robot = scoutsim.RobotParameters().replace(leg_mass=0.0, leg_inertia=0.0, leg_damping=0.0)
    r = scoutsim.simulate(
        robot, duration=2.0, model="passive", energy=True, passive_touchdown_angles=(0.25, 0.25)
    )
    b = r.energy_balance()
    assert b.input_J == 0.0
    for name, e, _ in b.terms:
        assert abs(e) < 1e-6, (name, e)


def test_passive_massive_legs_lose_what_the_dampers_take():
    """Without actuators, the mechanical energy drops by exactly what the leg dampers,
    the floor and the impacts take."""
    r = _run("passive", floor="no_slip", duration=1.0)
    b = r.energy_balance()
    lost = -b.term("mechanical_change")
    assert lost > 1.0
    taken = b.term("leg_damper") + b.term("impacts") + b.term("toe_sliding")
    assert taken == pytest.approx(lost, rel=1e-7)


def test_accounting_leaves_the_motion_unchanged():
    """The accounting only reads the integrator's own evaluations: the run is the same bit
    for bit with and without it (default Model II integrator, and the reference)."""
    for integ in (IntegratorSettings(), REFERENCE):
        a = scoutsim.simulate(duration=2.0, integrator=integ)
        b = scoutsim.simulate(duration=2.0, integrator=integ, energy=True)
        assert a.energy_flows is None and b.energy_flows is not None
        assert np.array_equal(a.state, b.state)
        assert np.array_equal(a.aux, b.aux)
        assert np.array_equal(a.events, b.events, equal_nan=True)


def test_residual_converges_with_the_tolerance():
    """The residual is integration error: with the default Model II integrator (ARK3) it
    shrinks as the tolerances are tightened (measured over 3 s: 8.8e-7 of the input at
    the default rtol 1e-5 / atol 1e-6, 4.4e-9 at 1e-7 / 1e-9, 4.5e-11 at 1e-9 / 1e-11)."""
    res = []
    for rtol, atol in ((1e-5, None), (1e-7, 1e-9)):
        r = _run(
            "II", duration=3.0, integrator=IntegratorSettings(method="ark3", rtol=rtol, atol=atol)
        )
        res.append(abs(r.energy_balance().relative_residual))
    assert res[0] < 1e-3
    assert res[1] < res[0] / 30.0


def test_copper_loss_and_electrical_power_from_the_time_series():
    """An independent check of two accumulated terms: R_A i^2 and i (R_A i + K_w w_m)
    integrated from the recorded 1 ms samples (trapezoid; the current jumps at the
    samples, so agreement to 2 %) equal the integrals taken on the integrator's steps."""
    robot = scoutsim.RobotParameters()
    r = _run("I", robot, duration=3.0)
    npl = robot.legs_per_virtual_leg
    for leg in L.LEG_NAMES:
        i = r.motor_current(leg)
        w = r.motor_speed(leg)
        copper = npl * robot.armature_resistance * np.trapezoid(i * i, r.t)
        elec = npl * np.trapezoid(
            i * (robot.armature_resistance * i + robot.speed_constant * w), r.t
        )
        assert r.energy_flows[f"copper_{leg}"] == pytest.approx(copper, rel=0.02)
        assert r.energy_flows[f"electrical_{leg}"] == pytest.approx(elec, rel=0.02)


def test_back_driving_is_a_source_in_the_transmission_term():
    """The paper's constant efficiency applied in both directions: while a leg back-drives
    its motor (i w_m < 0) the transmission term is negative, a source. Measured on the
    recorded samples over 3 s of Model I: the legs back-drive their motors 43-51 % of the
    time, worth -48 and -80 J against +117 and +159 J motoring. The accumulated term is
    the signed integral (the sample-based integral is within 4 % of it: the current jumps
    at the samples), not the motoring part alone nor the magnitude, which differ from it
    by the whole back-driven part."""
    robot = scoutsim.RobotParameters()
    r = _run("I", robot, duration=3.0)
    npl = robot.legs_per_virtual_leg
    eta, kt = robot.efficiency, robot.torque_constant
    for leg in L.LEG_NAMES:
        p = npl * (1.0 - eta) * kt * r.motor_current(leg) * r.motor_speed(leg)
        back_driven = np.trapezoid(np.minimum(p, 0.0), r.t)
        assert back_driven < -10.0  # the legs do back-drive their motors
        signed = np.trapezoid(p, r.t)
        assert abs(r.energy_flows[f"conversion_{leg}"] - signed) < 0.1 * abs(back_driven)


def test_balance_needs_the_accounting():
    r = scoutsim.simulate(duration=0.05)
    with pytest.raises(ValueError, match="energy=True"):
        r.energy_balance()


def test_energy_flows_saved_and_loaded(tmp_path):
    r = _run("I", duration=0.5)
    r.save(tmp_path / "run.npz")
    r.save_tables(tmp_path / "tables")
    for path in (tmp_path / "run.npz", tmp_path / "tables"):
        back = scoutsim.SimulationResult.load(path)
        assert back.energy_flows == r.energy_flows
        assert back.energy_balance().residual_J == r.energy_balance().residual_J


def test_transition_audit_reports_the_balance():
    """The transition audit of a run that accounted for its energy includes the whole
    run's balance, and reports a balance that does not close."""
    import dataclasses

    from scoutsim.analysis.transition_audit import audit_transitions

    r = scoutsim.simulate(duration=2.0, energy=True)
    audit = audit_transitions(r)
    assert audit.balance is not None and audit.ok, audit.problems()
    assert audit.balance_tol == pytest.approx(100 * r.provenance["integrator"]["rtol"])
    # ten joules (1 % of the input) too many in the leg damper: the balance no longer closes
    flows = dict(r.energy_flows, leg_damper_back=r.energy_flows["leg_damper_back"] + 10.0)
    bad = audit_transitions(dataclasses.replace(r, energy_flows=flows, _cache={}))
    assert not bad.ok
    assert any("work-energy balance" in p for p in bad.problems())
    assert audit_transitions(scoutsim.simulate(duration=0.1)).balance is None


def test_cost_of_transport_from_its_definition():
    """Cost of transport E_in / (m g d) from the run's distance and the robot's mass."""
    r = _run("I", duration=2.0)
    b = r.energy_balance()
    robot = scoutsim.RobotParameters()
    d = r.x[-1] - r.x[0]
    assert d > 1.0
    assert b.cost_of_transport == pytest.approx(
        b.input_J / (robot.total_mass * robot.gravity * d), rel=1e-12
    )
    assert b.mean_input_power_W == pytest.approx(b.input_J / 2.0, rel=1e-12)


def test_cli_run_energy_prints_and_saves_the_balance(tmp_path, capsys):
    """``scoutsim run --energy`` prints the balance table and writes it to summary.json,
    with the same numbers as the library."""
    import json

    from scoutsim.cli import main

    assert (
        main(
            [
                "run",
                "--duration",
                "0.5",
                "--model",
                "I",
                "--energy",
                "--out",
                str(tmp_path),
                "--no-progress",
            ]
        )
        == 0
    )
    printed = capsys.readouterr().out
    assert "work-energy balance" in printed and "| residual |" in printed
    saved = json.loads((tmp_path / "summary.json").read_text())["energy_balance"]
    b = _run("I", duration=0.5, integrator=IntegratorSettings()).energy_balance()
    assert saved["input_J"] == b.input_J
    assert saved["residual_J"] == b.residual_J
