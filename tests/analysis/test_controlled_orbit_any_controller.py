"""Periodic orbits of the controlled robot for controllers other than the built-in Table I
law (scoutsim.analysis.controlled_orbit, scoutsim.analysis.stride_map): the section every
run has (the first sample after the back leg's lift-off), the controller's own state as
part of the section state, and cycles of several strides.

Laws checked: the fixed point returns to itself under the stride map and under
simulate() resumed from it (its controller state included); the same law run as Python
and compiled into the loop has the same orbit and multipliers (two independent paths
through the controller dispatch); the multipliers of a cycle of k strides are those of
the k-th iterate.
"""

import json

import numpy as np
import pytest

import scoutsim
from scoutsim.analysis.controlled_orbit import (
    NOISE_MULTIPLE,
    NewtonError,
    NewtonSettings,
    controlled_fixed_point,
    map_noise,
)
from scoutsim.analysis.poincare import MapError
from scoutsim.analysis.stride_map import StrideMap
from scoutsim.cli import main
from scoutsim.control.bounding import BoundingController
from scoutsim.control.dispatch import ControllerStateError
from scoutsim.control.pitch_feedback import PitchFeedbackController
from scoutsim.parameters import ControllerParameters
from scoutsim.simulation.integrator import IntegratorSettings
from scoutsim.state import HybridState

from .user_controllers import filtered


class PythonTableI(BoundingController):
    """The Table I law run as a Python controller (command overridden), offering its leg
    states as its state."""

    def command(self, t, sensors):
        return super().command(t, sensors)

    def get_state(self):
        return tuple(float(v) for v in self.leg_states)

    def set_state(self, values):
        self.leg_states[:] = np.round(values).astype(np.int64)


class Stateless(BoundingController):
    def command(self, t, sensors):
        return super().command(t, sensors)


@pytest.fixture(scope="module")
def table_i():
    return controlled_fixed_point(settle_duration=8.0, section="plant")


def test_a_python_controller_has_the_orbit_of_the_same_law_compiled(table_i):
    py = controlled_fixed_point(controller=PythonTableI(), settle_duration=8.0)
    assert py.residual < 1e-9
    assert py.period == table_i.period and py.strides == table_i.strides == 1
    n = len(table_i.z)
    assert np.max(np.abs(py.z[:n] - table_i.z)) < 1e-8
    # the same nonzero multipliers; the Python controller's extra coordinates (its leg
    # states, the held torques) add only zero multipliers
    big = np.sort(np.abs(table_i.multipliers))[-6:]
    assert np.max(np.abs(np.sort(np.abs(py.multipliers))[-6:] - big)) < 1e-4
    assert "held_torque_back" in py.z_names and "controller_state_0" in py.z_names


def test_a_compiled_controller_state_is_part_of_the_orbit():
    ctrl = filtered()
    o = controlled_fixed_point(controller=ctrl, settle_duration=8.0)
    assert o.residual < 1e-9
    i = o.z_names.index("controller_state_0")
    # the filter's state on the orbit is the low-passed pitch rate: a real rate [rad/s]
    assert 0.0 < abs(o.z[i]) < 10.0
    assert o.state.controller_state == (o.z[i],)
    # the state matters: the map's Jacobian has a column for it
    assert np.max(np.abs(o.jacobian[:, i])) > 1e-6
    # the map from the orbit returns to it (at the orbit's integrator) ...
    tight = IntegratorSettings(rtol=1e-11, atol=1e-12)
    m = StrideMap(controller=ctrl, integrator=tight)
    c = m.crossing(o.state, strides=o.strides)
    assert c.period_s == pytest.approx(o.period)
    assert np.max(np.abs(m.z_of(c.state) - o.z)) < 1e-9
    # ... and so does simulate() resumed from the orbit's HybridState, whose controller
    # state it puts back after the controller's reset
    r = scoutsim.simulate(
        initial_state=o.state, duration=o.period, controller=ctrl, model="II", integrator=tight
    )
    assert np.max(np.abs(r.state[-1] - np.asarray(c.state.state))) < 1e-9
    # without its state (the filter restarting from 0) the stride lands elsewhere
    cold = m.crossing(HybridState(**{**o.state.__dict__, "controller_state": (0.0,)}))
    assert np.max(np.abs(m.z_of(cold.state) - o.z)) > 1e-3


def test_a_cycle_of_several_strides_is_a_fixed_point_of_the_iterate(capsys):
    """Pitch feedback at its defaults locks into a cycle of 6 strides of different whole
    numbers of control periods: the orbit is the fixed point of the 6th iterate, and the
    CLI says so."""
    assert main(["orbit", "--controller", "pitch-feedback", "--json", "--duration", "8"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["jacobian_method"] == "exact"
    assert d["residual"] < 1e-9
    k = d["strides_per_period"]
    assert k > 1
    # the cycle's strides have different lengths, and their sum is the period
    assert d["period_s"] * 1000 == pytest.approx(round(d["period_s"] * 1000), abs=1e-9)
    assert 0.0 < d["section_margin_s"] <= 0.5e-3


def test_the_iterate_of_a_period_one_orbit_has_the_multipliers_squared(table_i):
    two = controlled_fixed_point(table_i.state, strides=2, section="plant")
    assert two.period == pytest.approx(2 * table_i.period)
    assert np.max(np.abs(two.z - table_i.z)) < 1e-8
    lam = np.sort(np.abs(table_i.multipliers))[-4:] ** 2
    assert np.max(np.abs(np.sort(np.abs(two.multipliers))[-4:] - lam)) < 1e-4


def test_the_orbit_does_not_depend_on_the_section(table_i):
    """The built-in law's own section (the sample after it detects lift-off) gives the
    same orbit: the same period and nonzero multipliers."""
    own = controlled_fixed_point(settle_duration=8.0)
    assert "detects" in own.section_label and "plant" in table_i.section_label
    assert own.period == table_i.period
    big = np.sort(np.abs(table_i.multipliers))[-6:]
    assert np.max(np.abs(np.sort(np.abs(own.multipliers))[-6:] - big)) < 1e-4
    with pytest.raises(ValueError, match="section"):
        StrideMap(controller=PitchFeedbackController(), section="controller")


def test_a_newton_stopped_by_the_maps_own_noise_finds_the_orbit(table_i):
    """A tolerance below what the map can resolve (1e-15 on a stride integrated at rtol
    1e-11): Newton cannot meet it, and the orbit is accepted because its residual is
    within NOISE_MULTIPLE times the map's rounding noise, measured at the point and
    reported. The noise is what it says: the map's residual moves by about that much
    under perturbations of the start far below it, once their linear effect is removed
    (checked here along perturbations map_noise does not use); and the orbit is the one
    found at the ordinary tolerance."""
    o = controlled_fixed_point(
        table_i.state, strides=1, section="plant", newton=NewtonSettings(tol=1e-15)
    )
    assert o.residual >= 1e-15 and o.residual <= NOISE_MULTIPLE * o.residual_noise
    assert 1e-14 < o.residual_noise < 1e-10
    assert np.max(np.abs(o.z - table_i.z)) < 1e-9
    assert o.to_dict()["residual_noise"] == o.residual_noise
    m = StrideMap(section="plant", integrator=IntegratorSettings(rtol=1e-11, atol=1e-12))
    base = m.crossing(o.state)
    F0 = m.z_of(base.state) - o.z
    A = o.jacobian - np.eye(o.z.size)
    rng = np.random.default_rng(7)
    moved = []
    for _ in range(4):
        d = rng.uniform(-1.0, 1.0, o.z.size) * 1e-12 * np.maximum(1.0, np.abs(o.z))
        c = m.crossing(m.hs_of(o.z + d, o.state))
        z0 = m.z_of(c.start)
        moved.append(np.max(np.abs(m.z_of(c.state) - z0 - F0 - A @ (z0 - o.z))))
    assert max(moved) < 30.0 * o.residual_noise
    assert map_noise(m, o.z, o.state, base, o.jacobian, 1) == pytest.approx(o.residual_noise)


def test_a_newton_that_stalls_above_the_noise_is_reported_with_both(table_i, monkeypatch):
    """A stall far above the map's noise is not accepted: the error carries the
    smallest residual reached and the noise measured there."""
    import scoutsim.analysis.controlled_orbit as C

    def stall(m, z, dz, like, res, disc, hist, strides):
        raise NewtonError(f"Newton stalled at {res:.1e}", min(hist))

    monkeypatch.setattr(C, "_globalised_step", stall)
    m = StrideMap(section="plant")
    off = m.crossing(table_i.state).state  # one stride on: off the orbit by rounding only
    start = m.hs_of(m.z_of(off) + 1e-4, off)
    with pytest.raises(NewtonError, match="rounding noise here") as info:
        controlled_fixed_point(start, strides=1, section="plant")
    assert info.value.residual > 1e-6 and info.value.noise < 1e-9


def test_a_python_controller_without_state_is_refused_by_name(capsys):
    with pytest.raises(ControllerStateError, match="get_state"):
        controlled_fixed_point(controller=Stateless(), settle_duration=2.0)


def test_hybrid_state_controller_fields_are_checked():
    with pytest.raises(ValueError, match="controller_state"):
        HybridState(state=np.zeros(16), controller_state=(np.nan,))
    with pytest.raises(ValueError, match="held_torques"):
        HybridState(state=np.zeros(16), held_torques=(1.0,))


def test_a_fall_is_reported_not_counted():
    m = StrideMap(max_period=0.3)
    hs = HybridState(state=np.r_[0.0, 0.05, np.zeros(14)])
    with pytest.raises(MapError):
        m.crossing(hs)


def test_a_period_doubled_gait_is_found_as_a_two_stride_orbit():
    """A soft belt (200 N m/rad) and a 19 deg front touchdown angle: the run settles on a
    gait that repeats only every other stride, its strides of equal length (229 control
    periods). The orbit is the fixed point of the 2-stride map, and not one of the
    1-stride map: one stride from it lands 1e-3 or more away."""
    import dataclasses
    import math

    robot = dataclasses.replace(scoutsim.RobotParameters(), belt_stiffness=200.0)
    params = dataclasses.replace(ControllerParameters(), touchdown_angle_front=math.radians(19.0))
    o = controlled_fixed_point(
        robot=robot,
        controller=params,
        settle_duration=6.0,
        integrator=IntegratorSettings(rtol=1e-9, atol=1e-10),
        newton=NewtonSettings(tol=1e-7),
    )
    assert o.strides == 2 and o.residual < 1e-7
    m = StrideMap(
        robot=robot, controller=params, integrator=IntegratorSettings(rtol=1e-9, atol=1e-10)
    )
    one = m.crossing(o.state)
    assert 2 * one.samples * 1e-3 == pytest.approx(o.period)
    assert np.max(np.abs(m.z_of(one.state) - o.z)) > 1e-3


def test_a_gait_without_a_cycle_is_reported_with_its_closest_recurrence(monkeypatch):
    """Where Newton finds no orbit of the likely numbers of strides, the report says how
    closely the settled section states repeat (measured on Table I with the front touchdown
    angle at 21.035 deg: every stride 234 control periods, the states closest to repeating
    every 5 strides, within 1.2e-2, and no closer over 44 strides: no cycle, a gait that
    looks quasi-periodic). Here the search itself is replaced, so the report is checked
    alone."""
    import scoutsim.analysis.controlled_orbit as C

    def likely(m, start):
        return [1, 2, 3], [234] * 48, start, {1: 0.05, 2: 0.04, 3: 0.03, 5: 0.012}

    def stalled(m, start, k, *args):
        raise MapError(f"Newton stalled for {k}")

    monkeypatch.setattr(C, "likely_strides", likely)
    monkeypatch.setattr(C, "_newton", stalled)
    start = StrideMap().crossing(None).state
    with pytest.raises(MapError, match="closest to repeating every 5 stride.s., within 0.012"):
        controlled_fixed_point(start)
    with pytest.raises(MapError, match="does not repeat within 16 strides"):
        controlled_fixed_point(start)

    # a Newton that got close says so: the gait repeats, it is not "still settling"
    # (as on a per-leg robot's 14-stride cycle, whose settled states repeat only to
    # 3.7e-5 while Newton reaches 1e-9)
    def close(m, start, k, *args):
        raise NewtonError(f"Newton stalled for {k}", 1.6e-10 if k == 1 else 1e-3)

    monkeypatch.setattr(C, "_newton", close)
    with pytest.raises(MapError, match=r"repeats, but Newton .*smallest residual 1.6e-10"):
        controlled_fixed_point(start)
