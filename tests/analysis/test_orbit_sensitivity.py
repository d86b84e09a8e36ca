"""Orbit sensitivities (scoutsim.analysis.orbit_sensitivity): the implicit function theorem
on the fixed point against the derivatives of the orbits solved again at perturbed
parameters (central differences, +-1e-4 relative: an independent route through Newton).

Laws checked: agreement of the two routes for parameters of every kind (a belt spring, a
touchdown angle, the floor's friction); the stride frequency of a sampled orbit is locked
to the control period, so its derivative is 0 within a sample-phase cell; a parameter at
0 (a backlash) takes a one-sided step and has no elasticity; the derivative is linear in
the parameter's direction: a per-leg field's (both legs at once) is the sum of its two
legs' (chain rule).
"""

import json
import math

import numpy as np
import pytest

from scoutsim.analysis.controlled_orbit import controlled_fixed_point
from scoutsim.analysis.orbit_sensitivity import (
    SENSITIVITY_METRICS,
    orbit_metrics,
    orbit_sensitivities,
    radius_integrator,
    setting_with,
)
from scoutsim.cli import main

PARAMETERS = ("robot.belt_stiffness", "controller.touchdown_angle_front", "friction_coefficient")


@pytest.fixture(scope="module")
def orbit():
    return controlled_fixed_point(settle_duration=8.0)


@pytest.fixture(scope="module")
def sensitivities(orbit):
    legs = ["robot.belt_stiffness.back", "robot.belt_stiffness.front", "robot.belt_stiffness"]
    sens, base = orbit_sensitivities(orbit, list(PARAMETERS) + ["robot.belt_backlash"])
    # the per-leg test leaves the spectral radius out
    per_leg, _ = orbit_sensitivities(orbit, legs, spectral_radius=False)
    return {**sens, **{name: per_leg[name] for name in legs[:2]}}, base


def _resolved(orbit, name, value, integrator=None):
    """The metrics of the orbit solved again (Newton from the orbit) with ``name`` set to
    ``value`` (``integrator``: the orbit's if None)."""
    st = setting_with(orbit.setting, name, value)
    integ = integrator or orbit.setting["integrator"]
    o = controlled_fixed_point(
        orbit.state,
        model=st["model"],
        friction_coefficient=st["friction_coefficient"],
        robot=st["robot"],
        controller=st["controller"],
        strides=orbit.strides,
        integrator=integ,
    )
    assert o.period == orbit.period
    return orbit_metrics(o.state, o.period, st, integ, o.jacobian)


@pytest.mark.parametrize("name", PARAMETERS)
def test_implicit_function_theorem_agrees_with_orbits_solved_again(orbit, sensitivities, name):
    sens = sensitivities[0][name]
    assert sens.status == "ok"
    p = sens.value
    h = 1e-4 * abs(p)
    plus, minus = _resolved(orbit, name, p + h), _resolved(orbit, name, p - h)
    for metric in SENSITIVITY_METRICS:
        fd = (plus[metric] - minus[metric]) / (2 * h)
        ift = sens.derivative[metric]
        if metric == "stride_frequency_hz":
            assert ift == fd == 0.0  # locked to the control period
            continue
        if metric == "spectral_radius":
            continue  # its own step: below
        # the orbits solved again are accurate to about 1e-9 in z (Newton's 1e-10
        # residual over 1 - 0.925), which their difference divides by 2 h: the
        # reference's own noise
        assert ift == pytest.approx(fd, rel=1e-3, abs=1e-9 / h)
    # the spectral radius's derivative is a difference of two Jacobians at the tolerances
    # of its ends (radius_integrator), on both routes. The carried Jacobian's integration
    # error moves with the parameter (the steps change), so each radius scatters by up to
    # 2.5e-7 (measured): a parameter that barely moves the radius (the friction,
    # elasticity -0.008) is resolved to its elasticity, within 1e-3 % per %, not to 1e-3
    # of its derivative
    hr = sens.radius_step
    assert hr == h
    tight = radius_integrator(orbit.setting["integrator"])
    plus, minus = _resolved(orbit, name, p + hr, tight), _resolved(orbit, name, p - hr, tight)
    fd = (plus["spectral_radius"] - minus["spectral_radius"]) / (2 * hr)
    per_elasticity = plus["spectral_radius"] / abs(p)  # d radius / d p of elasticity 1
    error = abs(sens.derivative["spectral_radius"] - fd)
    assert error <= 1e-3 * max(abs(fd), per_elasticity)
    if name != "friction_coefficient":  # measured 1.8e-4 (belt), 1.1e-4 (touchdown)
        assert error <= 1e-3 * abs(fd)


def test_a_per_leg_fields_derivative_is_the_sum_of_its_legs(sensitivities):
    """Moving both legs' belt springs by h is moving the back's by h and the front's by h:
    to first order the metrics move by the sum (the spectral radius is left out: its
    derivative is taken over larger steps, module orbit_sensitivity)."""
    both = sensitivities[0]["robot.belt_stiffness"]
    back = sensitivities[0]["robot.belt_stiffness.back"]
    front = sensitivities[0]["robot.belt_stiffness.front"]
    assert back.status == front.status == "ok"
    assert back.value == front.value == both.value
    for metric in SENSITIVITY_METRICS:
        if metric in ("spectral_radius", "stride_frequency_hz"):
            continue
        total = back.derivative[metric] + front.derivative[metric]
        scale = max(abs(back.derivative[metric]), abs(front.derivative[metric]))
        # measured 5.6e-7 .. 9.7e-5 of the larger leg's (the largest: the pitch maximum,
        # whose derivative is the smallest; each side a difference quotient of orbits)
        assert abs(total - both.derivative[metric]) <= 1e-3 * scale, metric


def test_elasticity_is_the_relative_derivative(sensitivities):
    sens, base = sensitivities
    s = sens["controller.touchdown_angle_front"]
    for metric in ("mean_speed_m_s", "electrical_power_w"):
        assert s.elasticity[metric] == pytest.approx(
            s.derivative[metric] * s.value / base[metric], rel=1e-12
        )


def test_a_parameter_at_zero_takes_a_one_sided_step(sensitivities):
    s = sensitivities[0]["robot.belt_backlash"]
    assert s.value == 0.0 and s.status == "ok"
    assert all(math.isfinite(v) for v in s.derivative.values())
    assert all(math.isnan(v) for v in s.elasticity.values())


def test_cli_orbit_sensitivity_json(capsys):
    assert (
        main(
            [
                "orbit",
                "--duration",
                "8",
                "--sensitivity",
                "controller.touchdown_angle_front,controller.touchdown_angle_front_deg",
                "--json",
                "--no-progress",
            ]
        )
        == 0
    )
    d = json.loads(capsys.readouterr().out)
    s = d["sensitivities"]["controller.touchdown_angle_front"]
    # the same angle named in degrees (the command line's edge): its value in degrees,
    # its derivatives per degree, the same elasticities (they have no unit)
    g = d["sensitivities"]["controller.touchdown_angle_front_deg"]
    assert g["value"] == pytest.approx(21.0, rel=1e-12)
    for m in SENSITIVITY_METRICS:
        assert g["derivative"][m] == pytest.approx(s["derivative"][m] * math.pi / 180, rel=1e-12)
    assert g["elasticity"] == s["elasticity"]
    assert set(s) == {"value", "derivative", "elasticity", "status", "spectral_radius_step"}
    assert set(s["derivative"]) == set(SENSITIVITY_METRICS)
    assert s["value"] == pytest.approx(math.radians(21.0))
    # a steeper front touchdown angle slows the bound (docs/orbits.md)
    assert s["derivative"]["mean_speed_m_s"] < 0
    assert d["metrics"]["mean_speed_m_s"] == pytest.approx(d["mean_speed_m_s"], rel=1e-9)
    assert np.isfinite(d["metrics"]["cost_of_transport"])


def test_cli_refuses_an_unknown_parameter_by_name(capsys):
    assert main(["orbit", "--sensitivity", "robot.belt_stifness"]) == 2
    assert "robot.belt_stiffness" in capsys.readouterr().err
    # _deg names an angle in degrees only
    for name in ("robot.leg_stiffness_deg", "friction_coefficient_deg"):
        assert main(["orbit", "--sensitivity", name]) == 2
        assert f"--sensitivity {name!r} is not allowed" in capsys.readouterr().err


def test_parameters_shared_out_to_two_workers_give_the_same_numbers(orbit, sensitivities):
    """Two parameters on two worker processes, one each: the derivatives of one process,
    number for number (each parameter's computation is the same wherever it runs)."""
    names = ["friction_coefficient", "robot.belt_backlash"]
    two, base = orbit_sensitivities(orbit, names, workers=2)
    assert base == sensitivities[1]
    for name in names:
        assert two[name].status == "ok"
        assert two[name].derivative == sensitivities[0][name].derivative
        assert two[name].radius_step == sensitivities[0][name].radius_step
