"""Failure reasons that point at the cause ("nothing silently wrong": scoutsim/result/failure.py).

* Parameter values no legged robot has (1e308 kg, lengths in kilometres, ...) are refused
  before a run, naming the field and its allowed range.
* A run that fails numerically says why (``SimulationResult.failure``, the summary's
  ``"failure"``, the ``scoutsim run`` message): a parameter far from the Scout II defaults,
  singular dynamics, a blown-up state, or the integrator tolerance.
* The passive model runs from its own default start (legs at the passive touchdown angles,
  toes as far above the ground as those of the controlled start).
"""

import dataclasses
import json
import math

import numpy as np
import pytest

from scoutsim import RobotParameters, SimulationResult, simulate
from scoutsim._core.model import layout as L
from scoutsim.analysis.transition_audit import audit_transitions
from scoutsim.cli import main
from scoutsim.parameters import ParameterError, load_robot, physical_limit
from scoutsim.simulation.initial_conditions import default_initial_state


def _write(tmp_path, text, name="robot.toml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


# -- (a) physical bounds of the parameters ------------------------------------------------------


@pytest.mark.parametrize(
    "name, value, label, allowed",
    [
        ("torso_mass", 1e308, "robot.torso_mass", "in (0, 100000] kg"),
        ("leg_mass", 2e5, "robot.leg_mass", "in [0, 100000] kg"),
        ("torso_inertia", 1e300, "robot.torso_inertia", "in (0, 1e+09] kg m^2"),
        ("hip_spacing", 5.52e5, "robot.hip_spacing", "in (0, 100] m"),
        ("leg_rest_length", 1e300, "robot.leg_rest_length", "in (0, 100] m"),
        ("gravity", 1e300, "robot.gravity", "in (0, 1000] m/s^2"),
        ("leg_stiffness", 1e300, "robot.leg_stiffness", "in (0, 1e+10] N/m"),
        ("leg_damping", 1e300, "robot.leg_damping", "in [0, 100000000] N s/m"),
        ("planetary_ratio", 1e300, "transmission.planetary_ratio", "in (0, 10000]"),
        ("belt_damping", 1e300, "transmission.belt_damping", "in [0, 174532925] N m/(deg/s)"),
        ("speed_constant", 3.89e4, "motor.speed_constant", "in (0, 1000] V s/rad"),
        ("battery_voltage", 1e300, "motor.battery_voltage", "in (0, 10000] V"),
    ],
)
def test_absurd_parameter_values_are_refused_naming_field_and_range(name, value, label, allowed):
    with pytest.raises(ParameterError) as err:
        load_robot(overrides={name: value})
    msg = str(err.value)
    assert msg.startswith(f"{label} = ") and f"must be {allowed} (" in msg
    assert err.value.field == name


def test_integer_beyond_the_float_range_is_refused_naming_the_field():
    for name in ("planetary_ratio", "legs_per_virtual_leg"):
        with pytest.raises(
            ParameterError,
            match=rf"\.{name} = an integer of 401 digits .*"
            r"must be finite",
        ) as err:
            load_robot(overrides={name: 10**400})
        assert err.value.field == name


def test_physical_bounds_admit_every_value_the_package_uses():
    """The bounds lie far above Scout II (two decades at least) and admit the values the
    package's studies use: the identification search boxes, the rigid-transmission limit,
    the virtual Scout's effects, the efficiency example's current limit."""
    from scoutsim.identification.example import EXAMPLE_FACTORS
    from scoutsim.identification.parameter_vector import default_bounds
    from scoutsim.identification.rigs import HIP_PARAMETERS
    from scoutsim.validation.make_example import VIRTUAL_SCOUT_EFFECTS

    base = RobotParameters()
    limited = [f.name for f in dataclasses.fields(base) if physical_limit(f.name) is not None]
    assert "torso_mass" in limited and "battery_voltage" in limited
    for name in limited:
        default = getattr(base, name)
        assert physical_limit(name) >= 100 * default, name
    used = [{n: default_bounds(n, getattr(base, n))[1]} for n in HIP_PARAMETERS]
    used += [{n: f * getattr(base, n)} for n, f in EXAMPLE_FACTORS.items()]
    used += [
        VIRTUAL_SCOUT_EFFECTS,
        {"current_limit": 400.0},
        {
            "belt_stiffness": 100 * base.belt_stiffness,
            "drive_gear_inertia": base.drive_gear_inertia / 100,
        },
    ]
    for overrides in used:
        load_robot(overrides=overrides)


def test_absurd_mass_in_a_robot_file_is_refused_before_the_run(tmp_path, capsys):
    path = _write(tmp_path, "[robot]\ntorso_mass = 1e308\n")
    out = tmp_path / "out"
    assert (
        main(["run", "--duration", "1", "--robot", str(path), "--out", str(out), "--no-progress"])
        == 2
    )
    err = capsys.readouterr().err
    for piece in ("robot.torso_mass = 1e+308 kg", "must be in (0, 100000] kg", str(path)):
        assert piece in err
    assert not (out / "summary.json").exists()


# -- (b) the diagnosis of a numerical failure ---------------------------------------------------


def test_failure_caused_by_a_parameter_names_the_parameter():
    """A torso inertia of 1.3e6 kg m^2 (a radius of gyration of 250 m for 21 kg: within
    the bounds, but 1e6 x Scout II) makes the constrained dynamics unsolvable at the start."""
    r = simulate(load_robot(overrides={"torso_inertia": 1.3e6}), duration=0.05, model="I")
    assert r.outcome == "numerical_failure"
    f = r.failure
    assert f.kind == "singular_dynamics" and f.t == r.t_end
    assert [p.name for p in f.parameters] == ["robot.torso_inertia"]
    assert f.parameters[0].value == 1.3e6 and f.parameters[0].default == 1.3
    assert "equations of motion could not be solved" in f.what
    assert "robot.torso_inertia = 1.3e+06 kg m^2 (default 1.3 kg m^2)" in f.message()
    assert "rtol" not in f.message()
    s = r.summary()
    assert s["failure"]["kind"] == "singular_dynamics"
    assert s["failure"]["parameters"][0]["name"] == "robot.torso_inertia"
    json.dumps(s, allow_nan=False)


def test_step_size_collapse_caused_by_a_parameter_names_the_parameter():
    """A 1e-300 ohm winding: the motor's torque-speed line is vertical, the steps collapse;
    the integrator stopped, and the diagnosis names the parameter."""
    robot = load_robot(overrides={"armature_resistance": 1e-300})
    r = simulate(robot, duration=0.3, model="II")
    assert r.outcome == "numerical_failure"
    f = r.failure
    assert f.kind == "integrator"
    assert [p.name for p in f.parameters] == ["motor.armature_resistance"]
    assert f"smallest accepted step {r.stats['min_step_s']:.3g} s" in f.what
    assert "check them" in f.advice(cli=True)


def _forced_failure(r, **changes):
    """``r`` as if its run had failed numerically (its data possibly changed)."""
    return dataclasses.replace(r, outcome="numerical_failure", _cache={}, **changes)


@pytest.fixture(scope="module")
def short_run():
    return simulate(duration=0.05, model="I")


def test_integrator_stop_with_scout_parameters_points_at_the_tolerance(short_run):
    """Finite, plausible state and forces, Scout II parameters: the tolerance is the
    suspect; a smaller one, unless it is already near round-off."""
    f = _forced_failure(short_run).failure
    assert f.kind == "integrator" and f.parameters == ()
    assert "the integrator (dopri5, rtol 1e-08, atol 1e-09) could not go on" in f.what
    assert "stayed finite" in f.what
    assert "try a smaller --rtol" in f.advice(cli=True)
    assert "IntegratorSettings(rtol=...)" in f.advice()
    prov = dict(
        short_run.provenance, integrator=dict(short_run.provenance["integrator"], rtol=1e-13)
    )
    tight = _forced_failure(short_run, provenance=prov).failure
    assert "try a larger --rtol" in tight.advice(cli=True)


def test_blown_up_energy_and_non_finite_values_are_named(short_run):
    aux = short_run.aux.copy()
    aux[20:, L.A_ENERGY] = 1e7
    f = _forced_failure(short_run, aux=aux).failure
    assert f.kind == "energy"
    e0 = short_run.energy[0]
    assert f.what == f"the mechanical energy rose from {e0:.4g} J to 1e+07 J by t = 0.02 s"
    state = short_run.state.copy()
    state[30:, L.IY] = np.nan
    f = _forced_failure(short_run, state=state).failure
    assert f.kind == "non_finite"
    assert f.what == "at t = 0.03 s these values are not finite: y"
    assert "no parameter is far from its Scout II default" in f.advice()
    events = short_run.events.copy()
    k = int(np.flatnonzero(events[:, L.EVR_KIND] == L.EK_TOUCHDOWN)[0])
    events[k, L.EVR_T] = short_run.t_end
    events[k, L.EVR_VIOLATIONS] = L.V_SINGULAR
    f = _forced_failure(short_run, events=events).failure
    assert f.kind == "singular_dynamics"
    assert "(at the touchdown of the back leg)" in f.what


def test_a_run_that_did_not_fail_has_no_failure(short_run):
    assert short_run.failure is None
    assert "failure" not in short_run.summary()


def test_scoutsim_run_prints_the_diagnosis_not_a_fixed_rtol_hint(tmp_path, capsys):
    path = _write(tmp_path, "[robot]\ntorso_inertia = 1.3e6\n")
    out = tmp_path / "out"
    assert (
        main(
            [
                "run",
                "--duration",
                "0.1",
                "--robot",
                str(path),
                "--out",
                str(out),
                "--no-progress",
                "--model",
                "I",
            ]
        )
        == 1
    )
    err = capsys.readouterr().err
    assert "the integration failed numerically" in err
    assert "equations of motion could not be solved" in err
    assert "robot.torso_inertia = 1.3e+06 kg m^2 (default 1.3 kg m^2)" in err
    assert "rtol" not in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["failure"]["kind"] == "singular_dynamics"


# -- the passive model's default start -------------------------------------------------------


def _start_toe_heights(r):
    cols = r.columns()
    return cols["toe_y_back"][0], cols["toe_y_front"][0]


def test_passive_default_start_clears_the_ground_by_the_controlled_margin():
    """The controlled start's lower toe (back leg at 19 deg) clears the ground by 24.6 mm;
    the passive start's legs are vertical, and its toes clear the ground by the same."""
    controlled = min(_start_toe_heights(simulate(duration=1e-3, model="I")))
    assert controlled == pytest.approx(0.33 - 0.323 * math.cos(math.radians(19.0)), abs=1e-12)
    back, front = _start_toe_heights(simulate(duration=1e-3, model="passive"))
    assert back == pytest.approx(controlled, abs=1e-12)
    assert front == pytest.approx(controlled, abs=1e-12)


def test_passive_default_start_follows_the_robot_and_the_leg_placement():
    robot = RobotParameters(leg_rest_length=0.30, leg_com_distance=0.15)
    angles = (0.1, -0.2)
    init = default_initial_state("passive", robot, angles)
    assert init.theta == 0.0 and init.dx == 1.0
    controlled = min(_start_toe_heights(simulate(robot, duration=1e-3, model="I")))
    passive = simulate(robot, duration=1e-3, model="passive", passive_touchdown_angles=angles)
    assert min(_start_toe_heights(passive)) == pytest.approx(controlled, abs=1e-12)
    assert passive.provenance["initial_state"]["y"] == init.y


def _lands_from_flight(r):
    assert r.outcome in ("completed", "fell")
    assert np.all(r.modes[0, L.RM_CONTACT_B : L.RM_CONTACT_B + 2] == L.FLIGHT)
    assert min(_start_toe_heights(r)) > 0.0
    assert len(r.event_times("touchdown")) >= 1
    audit = audit_transitions(r)
    assert audit.ok, audit.problems()


def test_simulate_passive_runs_from_its_default_start():
    r = simulate(model="passive", duration=1.0)
    _lands_from_flight(r)
    assert r.provenance["initial_state"] == dataclasses.asdict(default_initial_state("passive"))
    assert min(_start_toe_heights(r)) == pytest.approx(
        0.33 - 0.323 * math.cos(math.radians(19.0)), abs=1e-12
    )


def test_scoutsim_run_passive_runs_from_its_default_start(tmp_path):
    out = tmp_path / "out"
    assert (
        main(["run", "--model", "passive", "--duration", "1", "--out", str(out), "--no-progress"])
        == 0
    )
    _lands_from_flight(SimulationResult.load(out))
