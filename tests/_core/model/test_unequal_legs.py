"""Robots whose back and front legs differ, and whose torso COM is not midway between the hips.

Laws checked, for such a robot (every leg, hip-unit and motor quantity different, COM ahead
of the hips' midpoint):

- the work-energy balance closes in every actuated model (docs/model.md "Work-energy
  balance"), and the passive massless-leg model conserves energy;
- mirror symmetry: the robot mirrored front to back (back and front values exchanged, the
  COM offset negated), started from the mirrored state, moves as the mirror image of the
  original (x -> -x, pitch and leg angles negated, back and front exchanged);
- the standing state is a static equilibrium (the torso pitched so that both toes reach
  the ground, the springs sharing the weight by the moments about the robot's COM);
- a robot given per leg with equal values is the robot given by one value, bit for bit.

The equations of motion of such a robot are checked against the SymPy derivation in
``test_eom_independent.py`` and against the reference evaluator in ``test_evaluate.py``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import scoutsim
from scoutsim._core.model import evaluate as ev
from scoutsim._core.model import layout as L
from scoutsim._core.model.packing import robot_array
from scoutsim.parameters import PER_LEG_FIELDS, ParameterError, load_robot
from scoutsim.simulation.integrator import IntegratorSettings
from scoutsim.state import InitialState, standing_leg_compressions, standing_state

#: every per-leg quantity different between the legs, the torso COM 3 cm ahead of midway
UNEQUAL = dict(
    com_offset=0.03,
    leg_mass=(1.0, 0.75),
    leg_inertia=(0.0052, 0.0036),
    leg_com_distance=(0.16, 0.13),
    leg_rest_length=(0.323, 0.305),
    leg_stiffness=(3520.0, 3950.0),
    leg_damping=(55.0, 62.0),
    planetary_ratio=(5.0, 4.6),
    sprocket_ratio=(20.4, 21.0),
    gearbox_efficiency=(0.8, 0.77),
    sprocket_efficiency=(0.816, 0.84),
    drive_gear_inertia=(2.4e-6, 2.1e-6),
    driven_gear_inertia=(0.0118, 0.013),
    joint_stiction=(0.021, 0.028),
    joint_damping=(3.5e-5, 4.6e-5),
    belt_stiffness=(401.0, 372.0),
    belt_damping=(0.23, 0.28),
    torque_constant=(0.0302, 0.0295),
    speed_constant=(0.0302, 0.0295),
    armature_resistance=(0.611, 0.66),
    current_limit=(12.0, 11.2),
)
ROBOT = scoutsim.RobotParameters(**UNEQUAL)
REFERENCE = IntegratorSettings(method="dopri5")


def _mirrored(robot: scoutsim.RobotParameters) -> scoutsim.RobotParameters:
    """The robot mirrored front to back: back and front values exchanged, COM offset
    negated (the front hip of the mirror image is where the back hip was)."""
    swapped = {n: robot.per_leg(n)[::-1] for n in PER_LEG_FIELDS}
    return robot.replace(com_offset=-robot.com_offset, **swapped)


def _mirror_states(s: np.ndarray) -> np.ndarray:
    """Mirror image of recorded states (rows): x, pitch and every angle negated, back and
    front exchanged; y and the leg lengths kept."""
    m = np.empty_like(s)
    for off in (0, L.NQ):
        m[:, off + L.IX] = -s[:, off + L.IX]
        m[:, off + L.IY] = s[:, off + L.IY]
        m[:, off + L.ITH] = -s[:, off + L.ITH]
        for a, b in ((L.IPHB, L.IPHF), (L.IALB, L.IALF)):
            m[:, off + a] = -s[:, off + b]
            m[:, off + b] = -s[:, off + a]
    m[:, L.IL_B] = s[:, L.IL_F]
    m[:, L.IL_F] = s[:, L.IL_B]
    return m


# --- the parameters ------------------------------------------------------------------------
def test_per_leg_values_read_back_and_name_the_leg():
    assert ROBOT.per_leg("leg_rest_length") == (0.323, 0.305)
    assert ROBOT.leg("front").leg_rest_length == 0.305
    assert ROBOT.leg(0).gear_ratio == pytest.approx(5.0 * 20.4, rel=1e-15)
    assert ROBOT.legs_differ and not scoutsim.RobotParameters().legs_differ
    with pytest.raises(ValueError, match="planetary_ratio differs"):
        _ = ROBOT.gear_ratio
    assert ROBOT.hip_offset("back") == pytest.approx(-0.276 - 0.03, abs=1e-15)
    assert ROBOT.hip_offset("front") == pytest.approx(0.276 - 0.03, abs=1e-15)
    with pytest.raises(ParameterError, match=r"leg_stiffness \(front leg\) = -1"):
        load_robot(overrides={"leg_stiffness": (3000.0, -1.0)})
    with pytest.raises(ParameterError, match="torso_mass.*one value for the whole robot"):
        load_robot(overrides={"torso_mass": (20.0, 21.0)})
    with pytest.raises(ParameterError, match="com_offset"):
        load_robot(overrides={"com_offset": 0.3})


def test_a_robot_file_gives_pairs_in_its_units(tmp_path):
    f = tmp_path / "robot.toml"
    f.write_text(
        "[robot]\nleg_rest_length = [0.323, 0.30]\n"
        'leg_mass = { value = [1000, 800], unit = "g" }\ncom_offset = 0.02\n'
        "[motor]\ncurrent_limit = [12.0, 12.0]\n"
    )
    r = load_robot(f)
    assert r.leg_rest_length == (0.323, 0.30)
    assert r.leg_mass == (1.0, 0.8)
    assert r.com_offset == 0.02
    assert r.current_limit == 12.0  # an equal pair is the one value


def test_equal_pairs_are_the_scalar_robot_bit_for_bit():
    """Every per-leg field given as an equal pair: the same run, bit for bit."""
    base = scoutsim.RobotParameters()
    pairs = base.replace(**{n: (getattr(base, n), getattr(base, n)) for n in PER_LEG_FIELDS})
    a = scoutsim.simulate(base, duration=1.0, model="II")
    b = scoutsim.simulate(pairs, duration=1.0, model="II")
    assert np.array_equal(a.state, b.state) and np.array_equal(a.aux, b.aux)


# --- energy ----------------------------------------------------------------------------------
@pytest.mark.parametrize("model", ["ideal", "I", "II"])
def test_balance_closes_for_unequal_legs(model):
    """Input = losses + change of mechanical energy over 4 s of bounding of the unequal
    robot (Coulomb floor, reference integrator), as for Scout II (test_energy.py)."""
    r = scoutsim.simulate(ROBOT, duration=4.0, model=model, integrator=REFERENCE, energy=True)
    assert r.outcome == "completed"
    b = r.energy_balance()
    assert b.input_J > 40.0
    assert abs(b.relative_residual) < 1e-6, b.table()
    assert abs(b.term("constraint_work")) < 1e-9 * b.input_J


def test_passive_massless_unequal_legs_conserve_energy():
    """Massless undamped legs of different stiffness and rest length under a torso whose
    COM is off centre: the passive model is conservative."""
    robot = ROBOT.replace(
        leg_mass=0.0, leg_inertia=0.0, leg_damping=0.0, leg_com_distance=(0.16, 0.13)
    )
    r = scoutsim.simulate(
        robot, duration=2.0, model="passive", energy=True, passive_touchdown_angles=(0.25, 0.2)
    )
    assert r.outcome in ("completed", "fell")  # (a fall ends the run; no loss before)
    assert len(r.event_times("touchdown")) >= 4
    e = r.energy
    assert np.max(np.abs(e - e[0])) < 1e-6 * abs(e[0])
    b = r.energy_balance()
    for name, value, _ in b.terms:
        assert abs(value) < 1e-6, (name, value)


# --- symmetry --------------------------------------------------------------------------------
@pytest.mark.parametrize("massless", [False, True], ids=["massive_legs", "massless_legs"])
def test_mirrored_robot_moves_as_the_mirror_image(massless):
    """The robot mirrored front to back, started from the mirrored state, gives the mirror
    image of the original passive trajectory, through touchdowns and lift-offs, to the
    integration tolerance."""
    robot = ROBOT.replace(leg_mass=0.0, leg_inertia=0.0) if massless else ROBOT
    start = InitialState(
        x=0.1,
        y=0.37,
        theta=0.06,
        dx=0.8,
        dy=-0.2,
        dtheta=0.7,
        phi_back=0.15,
        phi_front=-0.05,
        dphi_back=-1.0,
        dphi_front=2.0,
    )
    mirror_start = InitialState(
        x=-0.1,
        y=0.37,
        theta=-0.06,
        dx=-0.8,
        dy=-0.2,
        dtheta=-0.7,
        phi_back=0.05,
        phi_front=-0.15,
        dphi_back=-2.0,
        dphi_front=1.0,
    )
    td = (0.25, 0.15)
    integ = IntegratorSettings(method="dopri5", rtol=1e-10, atol=1e-11)
    kw = dict(duration=0.6, model="passive", integrator=integ, friction_coefficient=math.inf)
    a = scoutsim.simulate(robot, initial_state=start, passive_touchdown_angles=td, **kw)
    b = scoutsim.simulate(
        _mirrored(robot),
        initial_state=mirror_start,
        passive_touchdown_angles=(-td[1], -td[0]),
        **kw,
    )
    assert a.outcome == b.outcome == "completed"
    assert len(a.event_times("touchdown")) >= 2
    np.testing.assert_array_equal(a.t, b.t)
    np.testing.assert_allclose(b.state, _mirror_states(a.state), rtol=0, atol=1e-6)
    # and the robot is really asymmetric: its own mirror start moves otherwise
    c = scoutsim.simulate(
        robot, initial_state=mirror_start, passive_touchdown_angles=(-td[1], -td[0]), **kw
    )
    assert np.max(np.abs(c.state - _mirror_states(a.state))) > 1e-3


# --- standing --------------------------------------------------------------------------------
@pytest.mark.parametrize("model", ["ideal", "I", "II"])
def test_the_standing_state_is_a_static_equilibrium(model):
    """Vertical legs, toes pinned, no hip torque: every acceleration vanishes; the springs
    carry the weight (their forces sum to m g) with no moment about the robot's COM."""
    st = standing_state(ROBOT, model)
    s = np.array(st.state)
    assert abs(s[L.ITH]) > 1e-3  # the unequal robot stands pitched
    P = robot_array(ROBOT, model, friction_coefficient=math.inf)
    mi = np.zeros(L.NMI, dtype=np.int64)
    mi[L.MI_CONTACT_B : L.MI_CONTACT_B + 2] = L.STICK
    mf = np.array(st.toe_anchors, dtype=float)
    ds = np.zeros(L.NS)
    aux = np.zeros(L.NAUX)
    assert ev.evaluate(s, P, mi, mf, np.zeros(2), ds, aux)
    assert np.max(np.abs(ds[L.NQ : 2 * L.NQ])) < 1e-9
    gn = [aux[leg * L.NAUX_LEG + L.A_GN] for leg in range(2)]
    assert sum(gn) == pytest.approx(ROBOT.total_mass * ROBOT.gravity, rel=1e-12)
    comps = standing_leg_compressions(ROBOT)
    for leg in range(2):
        n, k = ROBOT.legs_per_virtual_leg, ROBOT.per_leg("leg_stiffness")[leg]
        assert gn[leg] == pytest.approx(n * k * comps[leg], rel=1e-12)
        toe_x = aux[leg * L.NAUX_LEG + L.A_TOE_X]
        assert toe_x == pytest.approx(st.toe_anchors[leg], abs=1e-12)


def test_unequal_robot_starts_from_standing_and_bounds():
    """The start-up from standing holds the pitched robot (its COM ahead, its front legs
    lighter) at rest at its standing leg angles, then steps and pushes it into the bound
    (the start-up's set-points are Scout II's: the robot above, whose every leg quantity
    differs, starts but does not reach its bound within 4 s)."""
    robot = scoutsim.RobotParameters(
        com_offset=0.015,
        leg_mass=(1.0, 0.9),
        leg_inertia=(0.0052, 0.0045),
        leg_com_distance=(0.16, 0.15),
    )
    assert abs(standing_state(robot).state[L.ITH]) > 1e-3
    r = scoutsim.simulate(robot, duration=4.0, model="II", initial_state="standing")
    assert r.outcome == "completed"
    stand = r.t < 0.15
    assert np.max(np.abs(r.state[stand, L.NQ : 2 * L.NQ])) < 1e-6  # at rest while it stands
    late = r.t > 2.0
    for leg in ("back", "front"):  # bounding: each leg lands every stride
        assert np.count_nonzero(r.event_times("touchdown", leg) > 2.0) >= 4
    assert np.min(r.state[late, L.NQ + L.IX]) > 0.0
