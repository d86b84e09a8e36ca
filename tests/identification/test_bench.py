"""The derivatives a bench replay carries (scoutsim.simulation.sample_derivatives.SampleDerivatives)
and the fit's exact Jacobian built from them (Residuals.jacobian).

Law checked: the derivative of the replay. The driven-gear angles' and motor currents'
derivatives with respect to hip parameters, carried through the flight-step rig's steps,
events and control samples, must equal central differences of replays with the parameter
moved (at a tolerance where those are accurate); carrying them must not change the
replay; the fit's Jacobian is those derivatives chained to ln p over the noise.
"""

from __future__ import annotations

import numpy as np
import pytest

from scoutsim.identification import example_logs
from scoutsim.identification.fit import FitSettings
from scoutsim.identification.residuals import Residuals
from scoutsim.identification.rig_data import prepare_logs
from scoutsim.identification.rigs import FlightSteps, run_rig
from scoutsim.parameters import RobotParameters
from scoutsim.parameters.robot_fields import robot_value, robot_with_value
from scoutsim.simulation.integrator import IntegratorSettings
from scoutsim.simulation.sample_derivatives import SampleDerivatives

TIGHT = IntegratorSettings(method="dopri5", rtol=1e-11, atol=1e-13)
FIELDS = ("drive_gear_inertia", "joint_damping", "joint_stiction")


def _series(res):
    angle = np.stack([res.motor_angle(leg) for leg in (0, 1)], axis=1)
    current = np.stack([res.motor_current(leg) for leg in (0, 1)], axis=1)
    return angle, current


def test_flight_step_derivatives_match_differences_of_replays():
    """Measured: angles 7e-5 to 3e-4 of each derivative's largest value, currents 1.6e-4
    to 9.6e-4 (the currents' derivatives in closed form; the differences' own error at
    rtol 1e-11 over a step of 1e-5)."""
    robot, rig = RobotParameters(), FlightSteps()
    plain = run_rig(rig, robot, integrator=TIGHT)
    der = SampleDerivatives(FIELDS)
    carried = run_rig(rig, robot, integrator=TIGHT, derivatives=der)
    assert np.array_equal(plain.state, carried.state)
    assert np.array_equal(plain.aux, carried.aux)
    assert der.smoothness["nonsmooth"] == 0 and der.smoothness["events"] >= 10
    assert der.angle.shape == (plain.state.shape[0], 2, len(FIELDS))
    for j, name in enumerate(FIELDS):
        value = robot_value(robot, name)
        h = 1e-5 * value
        hi, lo = (
            _series(run_rig(rig, robot_with_value(robot, name, value + s * h), integrator=TIGHT))
            for s in (1.0, -1.0)
        )
        for k, carried_k in enumerate((der.angle, der.current)):
            fd = (hi[k] - lo[k]) / (2.0 * h)
            err = np.abs(carried_k[:, :, j] - fd).max() / np.abs(fd).max()
            assert err < 3e-3, (name, ("angle", "current")[k], err)


def test_the_fits_exact_jacobian_is_the_replays_derivatives_in_ln_p():
    """At the example's starting robot, on its flight-step log (angles and currents): the
    exact Jacobian against central differences of the residuals in x = ln p, steps 2e-4.
    Measured 2.5e-5 of the column's largest value for the joint damping. (The belt
    damper moves these residuals so little that differences of them are noisy at 1e-3,
    whatever the step: not a reference for it.)"""
    robot = RobotParameters()
    data = prepare_logs(example_logs(rigs=("flight-steps",)), None, robot, None)
    names = ["joint_damping", "drive_gear_inertia"]
    res = Residuals(data, robot, names, TIGHT)
    x = np.log([robot_value(robot, n) for n in names])
    J = res.jacobian(x)
    assert res.nfd == 0
    for i in range(len(names)):
        e = np.zeros_like(x)
        e[i] = 2e-4
        central = (res(x + e) - res(x - e)) / 4e-4
        assert np.abs(J[:, i] - central).max() < 1e-3 * np.abs(central).max(), names[i]


def test_a_bad_jacobian_setting_is_refused():
    from scoutsim.identification import identify

    with pytest.raises(ValueError, match="jacobian = 'exakt' is not allowed"):
        identify(example_logs(rigs=("flight-steps",)), settings=FitSettings(jacobian="exakt"))
