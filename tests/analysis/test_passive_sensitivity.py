"""Sensitivities of a passive orbit to the robot's constants from exact derivatives
(scoutsim.analysis.passive_sensitivity): against orbits solved again, and the scaling law
that leaves the motion unchanged when stiffness, mass and inertia scale together."""

import dataclasses
import json
import math

import numpy as np
import pytest

from scoutsim.analysis.passive_orbits import passive_bounding_orbit
from scoutsim.analysis.passive_reference import passive_apex_map, passive_robot
from scoutsim.analysis.passive_sensitivity import (
    PASSIVE_SENSITIVITY_METRICS,
    PASSIVE_SENSITIVITY_PARAMETERS,
    passive_orbit_sensitivities,
)
from scoutsim.cli import main

W = math.radians(50.0)


@pytest.fixture(scope="module")
def orbit_and_sensitivities():
    orbit = passive_bounding_orbit(1.3, 0.35, W)
    return orbit, *passive_orbit_sensitivities(orbit)


def _metrics(robot, guess):
    o = passive_bounding_orbit(1.3, 0.35, W, robot=robot, guess=guess)
    m = list(o.multipliers)
    m.pop(int(np.argmin(np.abs(np.array(m) - 1.0))))  # the energy multiplier
    speed = passive_apex_map(o.z, o.touchdown_angles, robot=robot).mean_speed
    return np.array([*o.touchdown_angles, o.period, speed, float(np.max(np.abs(m)))])


@pytest.mark.parametrize("name", PASSIVE_SENSITIVITY_PARAMETERS)
def test_sensitivities_match_orbits_solved_again(orbit_and_sensitivities, name):
    """Central differences of orbits re-solved at p +- 1e-4 p agree within 1e-5 relative
    (measured 2e-7)."""
    orbit, sens, _ = orbit_and_sensitivities
    s = sens[name]
    assert s.status == "ok"
    fld = name.partition(".")[2]
    h = 1e-4 * s.value
    rob = passive_robot()
    up = _metrics(dataclasses.replace(rob, **{fld: s.value + h}), orbit.touchdown_angles)
    down = _metrics(dataclasses.replace(rob, **{fld: s.value - h}), orbit.touchdown_angles)
    fd = (up - down) / (2 * h)
    exact = np.array([s.derivative[k] for k in PASSIVE_SENSITIVITY_METRICS])
    np.testing.assert_allclose(exact, fd, rtol=1e-5, atol=1e-12)


def test_scaling_stiffness_mass_and_inertia_together_changes_nothing(orbit_and_sensitivities):
    """k, m and I scaled by one factor leave every acceleration (F/m, tau/I, gravity) and so
    the orbit unchanged: the three elasticities of each metric sum to zero."""
    _, sens, _ = orbit_and_sensitivities
    for metric in PASSIVE_SENSITIVITY_METRICS:
        total = sum(
            sens[f"robot.{p}"].elasticity[metric]
            for p in ("leg_stiffness", "torso_mass", "torso_inertia")
        )
        assert abs(total) < 1e-6, metric


def test_cli_passive_sensitivity_json_and_refusal(capsys):
    code = main(["orbit", "--passive", "--pitch-rate", "50", "--sensitivity",
                 "robot.leg_stiffness,robot.hip_spacing", "--json"])  # fmt: skip
    assert code == 0
    d = json.loads(capsys.readouterr().out)
    assert set(d["sensitivities"]) == {"robot.leg_stiffness", "robot.hip_spacing"}
    assert set(d["sensitivities"]["robot.hip_spacing"]["elasticity"]) == set(
        PASSIVE_SENSITIVITY_METRICS
    )
    # a change that breaks the mirror symmetry has no level-apex orbit to follow
    assert main(["orbit", "--passive", "--sensitivity", "robot.com_offset"]) == 2
    assert "robot.leg_stiffness" in capsys.readouterr().err
