"""Tests of the simulate() entry point: equivalences, limits, stiction, outcomes, persistence."""

import dataclasses
import inspect
import math
import re

import numpy as np
import pytest

import scoutsim
from scoutsim import (
    BoundingController,
    ControllerParameters,
    InitialState,
    IntegratorSettings,
    RobotParameters,
    SimulationResult,
)
from scoutsim._core.model import layout as L
from scoutsim.simulation.engine import RETUNABLE, start_engine
from scoutsim.simulation.simulator import PLANT_OPTIONS

TIGHT = IntegratorSettings(rtol=1e-10, atol=1e-10)


def lumped(robot: RobotParameters) -> RobotParameters:
    """One 'physical' leg per virtual leg carrying the doubled per-leg values; two motors
    in parallel = one motor with half the resistance and twice the current limit."""
    n = robot.legs_per_virtual_leg
    return dataclasses.replace(
        robot,
        legs_per_virtual_leg=1,
        leg_mass=n * robot.leg_mass,
        leg_inertia=n * robot.leg_inertia,
        leg_stiffness=n * robot.leg_stiffness,
        leg_damping=n * robot.leg_damping,
        drive_gear_inertia=n * robot.drive_gear_inertia,
        driven_gear_inertia=n * robot.driven_gear_inertia,
        joint_stiction=n * robot.joint_stiction,
        joint_damping=n * robot.joint_damping,
        belt_stiffness=n * robot.belt_stiffness,
        belt_damping=n * robot.belt_damping,
        armature_resistance=robot.armature_resistance / n,
        current_limit=n * robot.current_limit,
    )


def lumped_controller(c: ControllerParameters, n: int) -> ControllerParameters:
    g = {
        f: n * getattr(c, f)
        for f in (
            "flight_kp_front",
            "flight_kd_front",
            "flight_kp_back",
            "flight_kd_back",
            "brake_kp_front",
            "brake_kd_front",
            "brake_kp_back",
            "brake_kd_back",
        )
    }
    return dataclasses.replace(c, **g)


@pytest.mark.parametrize("model", ["I", "II"])
def test_virtual_leg_of_two_equals_one_with_lumped_parameters(model):
    robot = RobotParameters()
    ctrl = ControllerParameters()
    a = scoutsim.simulate(robot, ctrl, None, 0.6, model=model, integrator=TIGHT)
    b = scoutsim.simulate(
        lumped(robot), lumped_controller(ctrl, 2), None, 0.6, model=model, integrator=TIGHT
    )
    assert a.outcome == b.outcome
    assert len(a.event_times("touchdown")) >= 2
    assert np.allclose(a.state, b.state, rtol=0, atol=1e-7)
    # per-physical-leg torque is half the lumped one
    assert np.allclose(a.hip_torque_applied("back") * 2, b.hip_torque_applied("back"), atol=1e-5)


def test_model_II_approaches_model_I_in_the_rigid_limit():
    """Belt stiffer and gear inertia smaller -> Model II -> Model I (no joint friction).

    Both models at converged tolerances (a model limit, not an integrator test): at the
    stiffest setting the run ends with a grazing lift-off whose time moves by 2.6 ms for
    state differences of 2e-5 (measured with the default ARK3), which would hide the
    1.6e-4 model difference."""
    base = RobotParameters(joint_stiction=0.0, joint_damping=0.0)
    ctrl = ControllerParameters(sense_motor_angle=False)
    ref = scoutsim.simulate(base, ctrl, None, 0.25, model="I", integrator=TIGHT)
    errs = []
    for f in (1.0, 10.0, 100.0):
        rob = dataclasses.replace(
            base,
            belt_stiffness=base.belt_stiffness * f,
            driven_gear_inertia=base.driven_gear_inertia / f,
            drive_gear_inertia=base.drive_gear_inertia / f,
        )
        r = scoutsim.simulate(
            rob, ctrl, None, 0.25, model="II", integrator=IntegratorSettings(method="dopri5")
        )
        n = min(len(r.t), len(ref.t))
        errs.append(np.max(np.abs(r.state[:n, :3] - ref.state[:n, :3])))
    assert errs[2] < errs[1] < errs[0]
    assert errs[2] < 0.1 * errs[0]


class ConstantTorque:
    """User controller: constant hip torque on both legs (per physical leg, N m)."""

    def __init__(self, tau):
        self.tau = tau

    def command(self, t, sensors):
        return (self.tau, self.tau)


@pytest.mark.parametrize("tau_leg, moves", [(0.4, False), (0.8, True)])
def test_stiction_holds_below_breakaway_and_releases_above(tau_leg, moves):
    """Model II in free fall (no gravity torques between bodies): a motor torque below the
    motor-joint stiction (N * 5.5e-3 = 0.56 N m at the leg) leaves the leg still, above it
    the gear train breaks away."""
    robot = RobotParameters()
    breakaway_leg = robot.gear_ratio * robot.joint_stiction
    assert (tau_leg < breakaway_leg) != moves
    init = InitialState(y=5.0, theta=0.0, dx=0.0, dtheta=0.0)
    r = scoutsim.simulate(robot, ConstantTorque(tau_leg), init, 0.2, model="II", integrator=TIGHT)
    travel = np.max(np.abs(r.motor_angle("back") - r.motor_angle("back")[0]))
    if moves:
        assert travel > 1e-3
    else:
        assert travel < 1e-12
        assert np.all(r.modes[:, L.RM_MOTOR_B] == L.STUCK)  # stuck all along


def test_without_stiction_a_small_torque_turns_the_gear_train_as_its_inertia_says(symbolic_model):
    """joint_stiction = 0: the motor joint is never stuck, so a torque far below the
    breakaway one (0.05 N m per physical leg at the leg, 0.56 N m breakaway) turns it, and
    as Newton's law says: in free fall (uniform gravity drives no relative motion) from
    rest, the gear angles alpha, leg angles phi and pitch follow M q'' + C q' + K q = F,
    with M the mass matrix at the start from the independent SymPy derivation, K and C the
    belt spring and damper between alpha and phi, the motor joint's viscous damping
    N^2 b_j on alpha and F the motor torque on alpha (n_p per virtual leg; docs/model.md,
    "Generalized forces"). The motion stays below 1e-3 rad, so the linear equations hold to
    the measured 7.6e-6 of the travel (1.5e-5 for the pitch, the torso's small reaction);
    bounds ten times those. (Leaving out the joint damping would be 8.6 % off, the
    gearbox efficiency applied once more 53 %.)"""
    from scipy.linalg import expm

    robot = RobotParameters().replace(joint_stiction=0.0)
    tau = 0.05
    init = InitialState(y=5.0, theta=0.0, dx=0.0, dtheta=0.0)
    r = scoutsim.simulate(robot, ConstantTorque(tau), init, 0.05, model="II", integrator=TIGHT)
    assert np.all(r.modes[:, L.RM_MOTOR_B] != L.STUCK)
    assert np.all(r.hip_torque_applied("back") == tau)
    q0 = r.state[0, : L.NQ]
    assert np.all(r.state[0, L.NQ : 2 * L.NQ] == 0.0)
    n, N = robot.legs_per_virtual_leg, robot.gear_ratio
    M = symbolic_model.mass_matrix(q0, symbolic_model.params_from_robot(robot))
    K, C, F = np.zeros((L.NQ, L.NQ)), np.zeros((L.NQ, L.NQ)), np.zeros(L.NQ)
    for phi, alpha in ((L.IPHB, L.IALB), (L.IPHF, L.IALF)):
        # the belt torque k_b (alpha - phi) + c_b (dalpha - dphi) acts on phi, its
        # reaction on alpha
        pair = np.ix_([phi, alpha], [phi, alpha])
        K[pair] += n * robot.belt_stiffness * np.array([[1.0, -1.0], [-1.0, 1.0]])
        C[pair] += n * robot.belt_damping * np.array([[1.0, -1.0], [-1.0, 1.0]])
        C[alpha, alpha] += n * N * N * robot.joint_damping
        F[alpha] = n * tau
    # z = (q - q0, dq, 1): dz/dt = [[0, I, 0], [-M^-1 K, -M^-1 C, M^-1 F], [0, 0, 0]] z
    A = np.zeros((2 * L.NQ + 1, 2 * L.NQ + 1))
    A[: L.NQ, L.NQ : 2 * L.NQ] = np.eye(L.NQ)
    A[L.NQ : 2 * L.NQ, : L.NQ] = -np.linalg.solve(M, K)
    A[L.NQ : 2 * L.NQ, L.NQ : 2 * L.NQ] = -np.linalg.solve(M, C)
    A[L.NQ : 2 * L.NQ, -1] = np.linalg.solve(M, F)
    expected = np.array([expm(A * t)[: L.NQ, -1] for t in r.t])
    moved = r.state[:, : L.NQ] - q0
    for i, bound in (
        (L.IALB, 7.6e-5),
        (L.IALF, 7.6e-5),
        (L.IPHB, 7.6e-5),
        (L.IPHF, 7.6e-5),
        (L.ITH, 1.5e-4),
    ):
        travel = np.max(np.abs(expected[:, i]))
        assert travel > 0.0
        assert np.max(np.abs(moved[:, i] - expected[:, i])) <= bound * travel, L.STATE_NAMES[i]


def test_python_controller_path_matches_compiled():
    """The Table I law called from Python at every sample (a subclass overriding
    ``command``) runs the same run as the compiled law, bit for bit; an empty subclass runs
    compiled."""

    class Same(BoundingController):
        def command(self, t, sensors):
            return super().command(t, sensors)

    class Empty(BoundingController):
        pass

    a = scoutsim.simulate(None, ControllerParameters(), None, 0.4, model="II")
    b = scoutsim.simulate(None, Same(), None, 0.4, model="II")
    assert b.provenance["controller_kind"] == "Same"
    assert np.array_equal(a.state, b.state)
    assert np.array_equal(a.leg_state("back"), b.leg_state("back"))
    c = scoutsim.simulate(None, Empty(), None, 0.4, model="II")
    assert c.provenance["controller_kind"] == "builtin"


def test_fall_returns_data_up_to_the_fall():
    r = scoutsim.simulate(
        None,
        None,
        InitialState(dx=0.0, dtheta=math.radians(-200)),
        5.0,
        model="ideal",
        pitch_limit_deg=10.0,
    )
    assert r.outcome == "fell"
    assert r.t_end < 5.0
    assert r.t[-1] == pytest.approx(r.t_end)
    assert len(r.event_times("fall")) == 1
    assert abs(math.degrees(r.pitch[-1])) == pytest.approx(10.0, abs=1e-6)


def test_save_load_lossless(tmp_path):
    r = scoutsim.simulate(duration=0.3, model="II")
    p = r.save(tmp_path / "run.npz")
    q = SimulationResult.load(p)
    for name in ("t", "state", "aux", "modes", "events"):
        assert np.array_equal(getattr(r, name), getattr(q, name), equal_nan=True)
    assert q.provenance == r.provenance and q.outcome == r.outcome


@pytest.mark.parametrize(
    "kw, field",
    [
        ({"duration": -1.0}, "duration"),
        ({"model": "III"}, "model"),
        ({"initial_state": InitialState(y=0.2)}, "initial_state.y"),
        ({"initial_state": InitialState(theta=math.nan)}, "initial_state.theta"),
        ({"integrator": None, "friction_coefficient": -0.5}, "friction_coefficient"),
    ],
)
def test_bad_simulation_input_names_the_field(kw, field):
    with pytest.raises(ValueError, match=field.replace(".", r"\.")):
        scoutsim.simulate(**kw)


def test_bad_integrator_settings():
    with pytest.raises(ValueError, match="rtol"):
        IntegratorSettings(rtol=0.0)


def test_experimental_ark4_method_agrees_with_reference():
    ref = scoutsim.simulate(
        duration=2.0,
        model="II",
        friction_coefficient=0.8,
        integrator=IntegratorSettings(rtol=1e-10, atol=1e-10),
    )
    ark = scoutsim.simulate(
        duration=2.0,
        model="II",
        friction_coefficient=0.8,
        integrator=IntegratorSettings(method="ark4", rtol=1e-8, atol=1e-9),
    )
    assert len(ref.event_times("touchdown")) >= 4
    assert np.max(np.abs(ark.state[:, :3] - ref.state[:, :3])) < 1e-5
    with pytest.raises(ValueError, match="integrator.method"):
        IntegratorSettings(method="euler")


def test_default_integrator_gait_metrics_agree_with_reference():
    """The default settings (ARK3, rtol 1e-5 / atol 1e-6, velocities 1e-5): steady gait
    metrics within 1e-4 of the reference."""
    keys = (
        "mean_speed_m_s",
        "stride_frequency_hz",
        "duty_factor_back",
        "duty_factor_front",
        "pitch_max_deg",
        "pitch_min_deg",
        "height_max_m",
        "height_min_m",
    )
    ref = scoutsim.simulate(
        duration=10.0,
        model="II",
        friction_coefficient=0.8,
        integrator=IntegratorSettings(rtol=1e-10, atol=1e-10),
    ).summary()
    default = IntegratorSettings().resolve("II")
    assert default.method == "ark3"
    ark = scoutsim.simulate(duration=10.0, model="II", friction_coefficient=0.8).summary()
    assert ref["n_steady_strides"] >= 7 and ark["n_steady_strides"] >= 7
    for k in keys:
        assert ark[k] == pytest.approx(ref[k], rel=1e-4), k


@pytest.mark.parametrize(
    "method, bound_state, bound_pitch", [("auto", 1.37e-2, 3.52e-7), ("dopri5", 3.60e-7, 1.80e-12)]
)
def test_resuming_at_a_sample_continues_the_run_to_the_tolerance(method, bound_state, bound_pitch):
    """What HybridState resumption guarantees (its docstring, docs/how-to/resume-a-run.md): the state and
    modes of the sample, not the integrator's own state, so the continuation follows the
    original to the integration tolerance. Measured over the continued second, largest
    difference of any state component (a leg rate) / of the pitch: ARK3 (the default)
    1.37e-3 rad/s / 3.52e-8 rad, DOPRI5 3.60e-8 rad/s / 1.80e-13 rad; bounds ten times
    these."""
    integ = scoutsim.IntegratorSettings(method=method)
    r = scoutsim.simulate(duration=3.0, integrator=integ)
    k = 1500
    r2 = scoutsim.simulate(initial_state=r.hybrid_state(k), duration=1.0, integrator=integ)
    d = np.abs(r2.state - r.state[k : k + len(r2.t)])
    assert d.max() < bound_state
    assert d[:, L.ITH].max() < bound_pitch


def test_a_run_too_long_for_memory_is_refused_before_anything_is_allocated():
    from scoutsim.simulation.budgets import check_run_memory

    # per control sample: time, state (16), outputs (31) as float64 and 6 mode bytes = 390
    # bytes, plus the event buffer's 0.2 rows of 41 float64 = 65.6 bytes: 455.6 bytes;
    # 60 s = 60 002 rows: 27 336 911 bytes; half of 100 MB holds 109 745 samples, 109.7 s
    assert check_run_memory(60.0, memory_bytes=10**12) == 27_336_911
    with pytest.raises(
        ValueError,
        match=r"duration = 1000 s is not allowed on this machine"
        r".*at most about 109\.7 s per run",
    ):
        check_run_memory(1000.0, memory_bytes=100_000_000)
    with pytest.raises(ValueError, match="duration = 1e\\+09 s is not allowed"):
        scoutsim.simulate(duration=1e9)


def test_cli_streams_a_run_too_long_for_memory_and_refuses_one_too_long_for_the_disk(
    tmp_path, capsys
):
    from scoutsim.cli import main

    out = tmp_path / "out"
    out.mkdir()
    (out / "earlier.txt").write_text("kept")
    assert main(["run", "--duration", "1e9", "--no-progress", "--out", str(out)]) == 2
    assert "would take about 3.61e+03 h" in capsys.readouterr().err  # 1e9 s at 13 ms/s
    assert (
        main(["run", "--duration", "1e9", "--no-progress", "--out", str(out), "--max-hours", "1e9"])
        == 2
    )
    err = capsys.readouterr().err
    assert "more than the memory budget of 1 GB: streaming" in err
    assert "1e+09 s is not allowed here" in err and "on disk" in err
    assert [p.name for p in out.iterdir()] == ["earlier.txt"]  # refused before touching it


def test_event_records_that_overflow_one_period_are_counted_not_left_as_empty_rows():
    """A motor speed constant 1e4 times Scout II's (0.0389 -> 389 V s/rad, within the
    allowed range) makes the motor joints chatter: some control periods log more event
    records than the buffer has left. They used to become rows of zeros in the events
    table; now none is empty, they stay in time order, and the loss is counted."""
    import dataclasses

    robot = scoutsim.RobotParameters()
    robot = dataclasses.replace(robot, speed_constant=robot.speed_constant * 1e4)
    r = scoutsim.simulate(robot, duration=1.0)
    assert not np.any(np.all(r.events == 0.0, axis=1))
    assert np.all(np.diff(r.events[:, L.EVR_T]) >= 0.0)
    assert r.stats["event_records_lost"] > 0
    assert "event_records_lost" not in scoutsim.simulate(duration=1.0).stats


def test_provenance_records_every_parameter_as_given():
    """The run's provenance holds each parameter set field by field, as
    ``dataclasses.asdict`` gives it (a per-leg robot's pairs included)."""
    robot = scoutsim.RobotParameters(leg_rest_length=(0.323, 0.30), leg_mass=(1.0, 1.2))
    r = scoutsim.simulate(robot, duration=0.01, model="II")
    assert r.provenance["robot"] == dataclasses.asdict(robot)
    assert r.provenance["controller"] == dataclasses.asdict(ControllerParameters())
    assert r.provenance["integrator"] == dataclasses.asdict(
        scoutsim.IntegratorSettings().resolve("II")
    )


@pytest.mark.parametrize(
    "model,play,unit",
    [
        ("II", 0.0, "belt"),
        ("II", 0.01, "belt with backlash"),
        ("I", 0.01, "rigid"),
        ("ideal", 0.0, "rigid"),
    ],
)
def test_provenance_names_the_hip_unit_the_run_had(model, play, unit):
    r = scoutsim.simulate(scoutsim.RobotParameters(belt_backlash=play), duration=0.01, model=model)
    assert r.provenance["hip_unit"] == unit


def _documented_keywords(func) -> list[str]:
    """The parameter names of a numpydoc "Parameters" section (``name : type`` lines)."""
    doc = inspect.getdoc(func)
    section = doc.split("Parameters\n----------\n", 1)[1].split("\n\n", 1)[0]
    section = re.split(r"\n(?=Returns\n|Raises\n)", section)[0]
    return [m.group(1) for m in re.finditer(r"^([a-z_]+) : ", section, re.M)]


def test_every_documented_keyword_is_in_the_signature_and_back():
    """simulate() spells out its keywords: what its docstring documents is what
    inspect.signature shows (no ``**options``), each beyond the four positional ones
    keyword-only, with a default and a type annotation."""
    params = inspect.signature(scoutsim.simulate).parameters
    documented = _documented_keywords(scoutsim.simulate)
    assert len(documented) == len(set(documented))
    assert set(documented) == set(params)
    assert all(p.kind not in (p.VAR_KEYWORD, p.VAR_POSITIONAL) for p in params.values())
    for name, p in list(params.items())[4:]:
        assert p.kind is p.KEYWORD_ONLY, name
    for name, p in params.items():
        assert p.default is not p.empty and p.annotation is not p.empty, name
    # the plant keywords' defaults are those the assembly applies
    assert {k: params[k].default for k in PLANT_OPTIONS} == PLANT_OPTIONS


def test_an_unknown_keyword_is_refused_by_name():
    with pytest.raises(TypeError, match="pitch_limit_degrees"):
        scoutsim.simulate(duration=0.01, pitch_limit_degrees=30.0)


@pytest.mark.parametrize("bad", [0.0, 90.0, -10.0, math.nan, "60"])
def test_a_bad_pitch_limit_is_refused_naming_the_keyword_and_its_range(bad):
    for run in (
        lambda: scoutsim.simulate(duration=0.01, pitch_limit_deg=bad),
        lambda: start_engine(None, 0.01, pitch_limit_deg=bad),
    ):
        with pytest.raises(ValueError, match=r"pitch_limit_deg = .* must be .* \(0, 90\)"):
            run()


def test_a_recording_keyword_overrides_its_field_of_the_bundle():
    """``recording=`` sets what a run records; a keyword given as well wins over the
    bundle's field, and a keyword not given (None) leaves it."""
    bundle = scoutsim.Recording(record_steps=True)
    assert scoutsim.simulate(duration=0.01, recording=bundle).steps is not None
    assert scoutsim.simulate(duration=0.01, recording=bundle, record_steps=False).steps is None
    assert scoutsim.simulate(duration=0.01, record_steps=True).steps is not None
    assert scoutsim.simulate(duration=0.01).steps is None


def test_retuning_the_engine_at_the_start_is_starting_with_those_parameters():
    """HybridEngine.retune writes each retunable Table I field into its own slot: an
    engine started with the default parameters and retuned at sample 0 to another set runs
    bit for bit as one started with that set (the start's leg angles given, so the set
    does not place the legs)."""
    other = ControllerParameters().replace(
        **{name: 0.9 * getattr(ControllerParameters(), name) - 0.01 for name in RETUNABLE}
    )
    start = InitialState(phi_back=0.3, phi_front=0.35)
    ref = start_engine(start, 0.6, controller=other)
    eng = start_engine(start, 0.6)
    eng.retune(**{name: getattr(other, name) for name in RETUNABLE})
    assert np.array_equal(eng.C, ref.C)
    for e in (ref, eng):
        e.advance(e.k_last + 1)
    assert eng.n_out == ref.n_out == ref.k_last + 1  # (the whole run: no fall)
    assert np.array_equal(eng.out_s[: eng.n_out], ref.out_s[: ref.n_out])
    with pytest.raises(ValueError, match="flight_kp_back.*not allowed"):
        eng.retune(flight_kp_back=1.0)
