"""Periodic orbits of the passive model and the controlled cycle (scoutsim.analysis.orbits
and the modules it re-exports)."""

import json
import math

import numpy as np
import pytest

import scoutsim
from scoutsim.analysis import orbits as O
from scoutsim.analysis import passive_reference, stride_map
from scoutsim.cli import main
from scoutsim.simulation.integrator import IntegratorSettings
from scoutsim.state import InitialState


@pytest.fixture(scope="module")
def orbit50():
    return O.passive_bounding_orbit(1.3, 0.35, math.radians(50.0))


def test_passive_fixed_point_residual_below_1e9(orbit50):
    assert orbit50.residual < 1e-9
    m = O.passive_apex_map(orbit50.z, orbit50.touchdown_angles)
    assert np.max(np.abs(m.z - orbit50.z)) < 1e-9
    assert m.period == pytest.approx(orbit50.period, abs=1e-12)


def test_energy_conservation_gives_multiplier_one(orbit50):
    assert orbit50.unit_multiplier_error < 1e-6


def test_zero_pitch_rate_gives_equal_touchdown_angles():
    o = O.passive_bounding_orbit(1.3, 0.35, 0.0)
    assert o.residual < 1e-9
    assert abs(o.touchdown_angles[0] - o.touchdown_angles[1]) < 1e-8
    assert o.unit_multiplier_error < 1e-6


def test_orbit_converges_under_tighter_tolerance(orbit50):
    loose = O.passive_bounding_orbit(
        1.3, 0.35, math.radians(50.0), rtol=1e-10, guess=orbit50.touchdown_angles
    )
    assert np.max(np.abs(np.subtract(loose.touchdown_angles, orbit50.touchdown_angles))) < 1e-7
    assert abs(loose.period - orbit50.period) < 1e-8


def test_apex_map_agrees_with_simulate(orbit50):
    """The orbit module's passive integration is the simulator's passive model: the apex
    state after one stride agrees with a simulate() run (ballistic apex from a 1 kHz sample)."""
    z = orbit50.z
    r = scoutsim.simulate(
        O.passive_robot(),
        None,
        InitialState(y=z[0], theta=0.0, dx=z[2], dy=0.0, dtheta=z[3]),
        0.5,
        model="passive",
        integrator=IntegratorSettings(rtol=1e-12, atol=1e-12),
        passive_touchdown_angles=orbit50.touchdown_angles,
    )
    assert not passive_reference._glitched(r)
    t_lo = max(r.event_times("liftoff", "back")[0], r.event_times("liftoff", "front")[0])
    k = int(np.searchsorted(r.t, t_lo, side="right"))
    s = r.state[k]
    g = O.passive_robot().gravity
    dy = s[8]
    sim = np.array([s[1] + dy * dy / (2 * g), s[2] + s[9] * dy / g, s[7], s[9]])
    assert np.max(np.abs(sim - z)) < 1e-8


def test_continuation_follows_the_family():
    fam = O.continue_passive_family(1.3, 0.35, np.radians([0.0, 25.0, 50.0]), linearise=False)
    assert all(o.residual < 1e-9 for o in fam)
    # the back leg touches down further forward as the pitch rate grows
    assert fam[0].touchdown_angles[0] < fam[1].touchdown_angles[0] < fam[2].touchdown_angles[0]


def test_cli_orbit_passive_json_has_exactly_the_keys(capsys):
    code = main(
        [
            "orbit",
            "--passive",
            "--speed",
            "1.3",
            "--apex-height",
            "0.35",
            "--pitch-rate",
            "50",
            "--json",
        ]
    )
    assert code == 0
    d = json.loads(capsys.readouterr().out)
    assert set(d) == {
        "touchdown_angle_back_deg",
        "touchdown_angle_front_deg",
        "period_s",
        "eigenvalues",
        "residual",
        "jacobian_method",
    }
    assert d["residual"] < 1e-9
    assert d["jacobian_method"] == "exact"
    assert len(d["eigenvalues"]) == 4 and all(len(e) == 2 for e in d["eigenvalues"])


def test_controlled_cycle_converges():
    c = O.controlled_cycle()
    assert c.outcome == "completed"
    assert 0.15 < c.period < 0.4
    assert np.all(c.spread < 0.05)


# -----------------------------------------------------------------------------------------
# controlled robot: Newton on the sampled stride map
# -----------------------------------------------------------------------------------------
#: progress messages of the controlled fixed point below
_MESSAGES = []


@pytest.fixture(scope="module")
def controlled():
    return O.controlled_fixed_point(progress=_MESSAGES.append)


def test_controlled_fixed_point_reports_its_progress(controlled):
    assert _MESSAGES[0].startswith("settling: 12 s of model II")
    # (the messages of the Newton run that gave the orbit: the last ones)
    iterations = [m for m in _MESSAGES if m.startswith("Newton iteration")]
    iterations = iterations[-len(controlled.history) :]
    assert iterations[0].startswith("Newton iteration 0:")
    assert iterations[-1].endswith(f"{controlled.history[-1]:.2e}")


@pytest.fixture(scope="module")
def long_run():
    # the reference integrator: the run must settle onto the orbit far below the default
    # tolerance's own noise (ARK3 at rtol 1e-5 keeps the section state ~4e-4 from it)
    # (on the default floor, as controlled_fixed_point())
    return scoutsim.simulate(
        duration=20.0, model="II", integrator=IntegratorSettings(method="dopri5")
    )


def test_controlled_fixed_point_residual_below_1e9(controlled):
    assert controlled.residual < 1e-9
    # the map evaluated afresh at the reported orbit returns to it
    z0, z1, h1, T = O.controlled_stride_map(
        controlled.state, integrator=IntegratorSettings(rtol=1e-11, atol=1e-12)
    )
    assert np.max(np.abs(z1 - z0)) < 1e-9
    assert T == controlled.period
    # a sampled-data orbit lasts a whole number of control periods
    assert controlled.period * 1000 == pytest.approx(round(controlled.period * 1000), abs=1e-9)


def test_controlled_orbit_is_where_the_simulation_converges(controlled, long_run):
    """Independent of Newton: a long run from the default start settles onto the orbit
    (stride length, section state), approaching it at the rate of the largest multiplier."""
    r = long_run
    dt = 1e-3
    te = r.event_times("controller_liftoff", "back")
    # the section: the control sample after the controller detects each lift-off
    k = np.round(te / dt).astype(int) + 1
    assert np.all(np.diff(k[-20:]) * dt == pytest.approx(controlled.period))
    m = stride_map.StrideMap()
    dist = np.array(
        [np.max(np.abs(m.z_of(r.hybrid_state(int(kk))) - controlled.z)) for kk in k[-40:-1]]
    )
    assert dist[-1] < 1e-3
    assert dist[-1] < 0.2 * dist[0]
    # the plant's lift-off intervals approach the period alternately, with the ratio of the
    # dominant multiplier
    lam = controlled.multipliers[np.argmax(np.abs(controlled.multipliers))]
    d = np.diff(r.event_times("liftoff", "back"))[-25:] - controlled.period
    ratios = d[1:] / d[:-1]
    assert abs(lam.imag) < 1e-9
    assert np.median(ratios) == pytest.approx(lam.real, abs=0.05)


def test_controlled_orbit_is_stable_and_converges_under_tighter_tolerance(controlled):
    assert controlled.stable
    tight = O.controlled_fixed_point(
        controlled.state, integrator=IntegratorSettings(rtol=1e-12, atol=1e-13)
    )
    assert tight.period == controlled.period
    assert np.max(np.abs(tight.z - controlled.z)) < 1e-8
    assert (
        np.max(np.abs(np.sort(np.abs(tight.multipliers)) - np.sort(np.abs(controlled.multipliers))))
        < 1e-3
    )


def test_resumed_run_continues_the_original():
    tight = IntegratorSettings(rtol=1e-10, atol=1e-11)
    r = scoutsim.simulate(duration=2.5, model="II", friction_coefficient=0.8, integrator=tight)
    k = 2000
    r2 = scoutsim.simulate(
        initial_state=r.hybrid_state(k),
        duration=0.5,
        model="II",
        friction_coefficient=0.8,
        integrator=tight,
    )
    n = len(r2.t)
    assert np.array_equal(r2.modes, r.modes[k : k + n])
    assert np.max(np.abs(r2.state - r.state[k : k + n])) < 1e-8


def test_cli_orbit_controlled_json(capsys):
    assert main(["orbit", "--json", "--duration", "8"]) == 0
    d = json.loads(capsys.readouterr().out)
    for key in (
        "touchdown_angle_back_deg",
        "touchdown_angle_front_deg",
        "period_s",
        "eigenvalues",
        "residual",
    ):
        assert key in d
    assert d["residual"] < 1e-9
    # the touchdown angles from the world vertical are the commanded angles relative to
    # the torso plus the pitch at touchdown: within the range of Table I +- the pitch range
    assert 5.0 < d["touchdown_angle_back_deg"] < 35.0
    assert 5.0 < d["touchdown_angle_front_deg"] < 35.0


def test_apex_map_agrees_with_simulate_for_unequal_legs():
    """The same agreement (two independent formulations of the passive model: SciPy here,
    the compiled simulator) for a robot whose legs differ in stiffness and rest length and
    whose torso COM is 2 cm ahead of the hips' midpoint, over one stride from an apex."""
    robot = O.passive_robot(
        scoutsim.RobotParameters(
            com_offset=0.02, leg_stiffness=(3520.0, 3900.0), leg_rest_length=(0.323, 0.31)
        )
    )
    z = np.array([0.35, 0.0, 1.3, 0.8])
    td = (0.3, 0.25)
    m = O.passive_apex_map(z, td, robot=robot)
    r = scoutsim.simulate(
        robot,
        None,
        InitialState(y=z[0], theta=z[1], dx=z[2], dy=0.0, dtheta=z[3]),
        0.5,
        model="passive",
        integrator=IntegratorSettings(rtol=1e-12, atol=1e-12),
        passive_touchdown_angles=td,
    )
    assert not passive_reference._glitched(r)
    t_lo = max(r.event_times("liftoff", "back")[0], r.event_times("liftoff", "front")[0])
    k = int(np.searchsorted(r.t, t_lo, side="right"))
    s = r.state[k]
    g = robot.gravity
    dy = s[8]
    # ballistic flight from sample k (after the last lift-off) to the apex
    sim = np.array([s[1] + dy * dy / (2 * g), s[2] + s[9] * dy / g, s[7], s[9]])
    assert np.max(np.abs(sim - m.z)) < 1e-8
    # and the asymmetry matters: the map of the symmetric robot is elsewhere
    sym = O.passive_apex_map(z, td, robot=O.passive_robot())
    assert np.max(np.abs(sym.z - m.z)) > 1e-3


def test_passive_orbit_of_an_asymmetric_robot_says_what_breaks_the_symmetry():
    """The level-apex orbits rely on the back-front mirror symmetry; a robot with its COM
    off centre has none, and the refusal names why rather than only the residual."""
    import dataclasses

    robot = dataclasses.replace(O.passive_robot(), com_offset=0.015)
    with pytest.raises(O.MapError, match=r"mirror symmetry.*com_offset = 0.015 m"):
        O.passive_bounding_orbit(1.3, 0.35, 0.0, robot=robot)
