"""The controlled stride map's Jacobian carried with the run
(scoutsim.analysis.stride_map.StrideMap.crossing(exact=True), the default of
scoutsim.analysis.controlled_orbit.controlled_fixed_point).

Law checked: the derivative of the sampled closed loop's stride map at its fixed point.
The Jacobian carried through the run's steps, events (saltation matrices) and control
samples (zero-order hold, the controller differenced at each sample) must equal the limit
of central differences of whole strides (integrated more tightly than the orbit),
Richardson-extrapolated over two steps that keep every perturbed stride in the orbit's
sample-phase cell, for the three transmission
models, the built-in Table I law, the torso-feedback law and a user's compiled controller
with a state of its own; and so must the Floquet multipliers.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from scoutsim.analysis.controlled_orbit import cell_change, controlled_fixed_point
from scoutsim.analysis.poincare import floquet_multipliers
from scoutsim.analysis.stride_map import StrideMap
from scoutsim.control.pitch_feedback import PitchFeedbackController
from scoutsim.parameters import ControllerParameters

from .user_controllers import filtered


def _central(m: StrideMap, orbit, h: float) -> np.ndarray | None:
    """Central differences of the orbit's stride map (its ``strides``-th iterate) with
    relative step ``h``; None if a perturbed stride leaves the orbit's cell."""
    base = m.crossing(orbit.state, strides=orbit.strides)
    z = orbit.z
    J = np.zeros((z.size, z.size))
    for j in range(z.size):
        e = h * max(1.0, abs(z[j]))
        ends = []
        for sign in (1.0, -1.0):
            zp = z.copy()
            zp[j] += sign * e
            c = m.crossing(m.hs_of(zp, orbit.state), strides=orbit.strides)
            if cell_change(base, c):
                return None
            ends.append(m.z_of(c.state))
        J[:, j] = (ends[0] - ends[1]) / (2.0 * e)
    return J


def _extrapolated(m: StrideMap, orbit) -> np.ndarray:
    """Richardson's extrapolation of central differences at steps 2h and h, the largest
    h in 1e-5, 5e-6, ... that keeps every perturbed stride in the orbit's cell."""
    h = 1e-5
    while h > 1e-7:
        coarse, fine = _central(m, orbit, 2.0 * h), _central(m, orbit, h)
        if coarse is not None and fine is not None:
            return (4.0 * fine - coarse) / 3.0
        h /= 2.0
    raise AssertionError("no difference step keeps the strides in the orbit's cell")


def _matched(a, b) -> float:
    """The largest distance from a multiplier of ``a`` to the nearest of ``b``."""
    return max(min(abs(x - y) for y in b) for x in a)


CASES = {
    "model II, Table I": dict(model="II"),
    "model I, Table I": dict(model="I"),
    "ideal, Table I": dict(model="ideal"),
    # half the default pitch-rate gain: a one-stride orbit (the default locks into six)
    "model II, torso feedback": dict(
        model="II",
        controller=PitchFeedbackController(
            ControllerParameters(pitch_rate_gain_front=-0.025, pitch_rate_gain_back=-0.025)
        ),
    ),
    "model II, user's compiled controller": dict(model="II", controller="filtered"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_exact_multipliers_are_the_limit_of_differences(case):
    setting = dict(CASES[case])
    if setting.get("controller") == "filtered":
        setting["controller"] = filtered()
    orbit = controlled_fixed_point(settle_duration=8.0, **setting)
    assert orbit.jacobian_method == "exact"
    m = StrideMap(integrator=orbit.setting["integrator"], **setting)
    c = m.crossing(orbit.state, strides=orbit.strides, exact=True)
    assert c.smoothness is not None and c.smoothness["nonsmooth"] == 0
    assert c.smoothness["events"] > 0
    # the differences of strides integrated a hundred times more tightly than the orbit's
    # (rtol 1e-13): at the orbit's own 1e-11 their noise over the difference step moved
    # the reference's multipliers by up to 3e-5; at 1e-13 the exact ones are within
    # 1.3e-8 to 4.1e-6 of them (measured on the five cases)
    tight = dataclasses.replace(orbit.setting["integrator"], rtol=1e-13, atol=1e-15)
    reference = _extrapolated(StrideMap(integrator=tight, **setting), orbit)
    scale = np.abs(reference).max()
    assert np.abs(orbit.jacobian - reference).max() < 1e-4 * scale
    assert _matched(floquet_multipliers(orbit.jacobian), floquet_multipliers(reference)) < 1e-5
