"""Exact derivatives of the passive model's apex return map
(scoutsim.analysis.passive_reference.passive_apex_map_derivative: variational equations and
saltation matrices) against Richardson-extrapolated central differences of the map, the
jump at each touchdown and lift-off against differences of the flow across it, and energy
conservation: the conserved energy's gradient is a left eigenvector of the map's Jacobian
with eigenvalue 1."""

import dataclasses
import math

import numpy as np
import pytest

from scoutsim.analysis import passive_reference as P
from scoutsim.analysis.passive_orbits import passive_bounding_orbit
from scoutsim.analysis.poincare import floquet_multipliers
from scoutsim.analysis.saltation import Guard, flow_to_event

PITCH_RATES_DEG = (50.0, 100.0, 150.0)


@pytest.fixture(scope="module")
def orbits():
    return {w: passive_bounding_orbit(1.3, 0.35, math.radians(w)) for w in (0.0, *PITCH_RATES_DEG)}


def _richardson(f, x, h):
    """Central differences with steps h and h/2, Richardson-extrapolated (error O(h^4))."""
    x = np.asarray(x, dtype=float)

    def central(h):
        cols = []
        for i in range(len(x)):
            e = np.zeros(len(x))
            e[i] = h
            cols.append((np.atleast_1d(f(x + e)) - np.atleast_1d(f(x - e))) / (2 * h))
        return np.column_stack(cols)

    return (4.0 * central(h / 2) - central(h)) / 3.0


@pytest.mark.parametrize("w", PITCH_RATES_DEG)
def test_exact_multipliers_match_richardson_differences_to_1e8(orbits, w):
    orb = orbits[w]
    J = _richardson(lambda x: P.passive_apex_map(x, orb.touchdown_angles).z, orb.z, 1e-3)
    assert orb.jacobian_method == "exact"
    m_fd = floquet_multipliers(J)
    assert np.max(np.abs(orb.multipliers - m_fd)) < 1e-8


@pytest.mark.parametrize("w", (0.0, *PITCH_RATES_DEG))
def test_energy_multiplier_is_one_to_1e11(orbits, w):
    assert orbits[w].unit_multiplier_error < 1e-11


@pytest.mark.parametrize("w", (0.0, *PITCH_RATES_DEG))
def test_energy_gradient_is_a_left_eigenvector_with_eigenvalue_one(orbits, w):
    """E(z) = m g y + m dx^2/2 + I dtheta^2/2 at an apex (massless legs, no spring
    energy in flight) is conserved by the map, so dE/dz J = dE/dz."""
    orb, rob = orbits[w], P.passive_robot()
    y, _, dx, dth = orb.z
    m, inertia = rob.torso_mass, rob.torso_inertia
    dE = np.array([m * rob.gravity, 0.0, m * dx, inertia * dth])
    np.testing.assert_allclose(dE @ orb.jacobian, dE, rtol=0.0, atol=1e-10 * np.abs(dE).max())


def test_map_derivatives_match_richardson_differences(orbits):
    """All four derivative blocks: state and touchdown-angle Jacobians of the next apex and
    of the period."""
    orb = orbits[50.0]
    z, gam = orb.z, np.array(orb.touchdown_angles)
    d = P.passive_apex_map_derivative(z, gam)
    assert not d.simultaneous
    pairs = (
        (d.state_jacobian, _richardson(lambda x: P.passive_apex_map(x, gam).z, z, 1e-3)),
        (d.angle_jacobian, _richardson(lambda g: P.passive_apex_map(z, g).z, gam, 1e-3)),
        (d.period_gradient, _richardson(lambda x: P.passive_apex_map(x, gam).period, z, 1e-3)[0]),
        (
            d.period_angle_gradient,
            _richardson(lambda g: P.passive_apex_map(z, g).period, gam, 1e-3)[0],
        ),
    )
    for exact, ref in pairs:
        scale = max(1.0, float(np.abs(ref).max()))
        np.testing.assert_allclose(exact, ref, rtol=0.0, atol=1e-7 * scale)


def test_pronk_is_flagged_as_simultaneous(orbits):
    """At zero pitch rate both legs touch down (and lift off) together: the map is only
    piecewise smooth there and the derivative says so."""
    orb = orbits[0.0]
    assert P.passive_apex_map_derivative(orb.z, orb.touchdown_angles).simultaneous


# --- the jump at each event, against differences of the flow across it ------------------


def _robot(constants):
    """The passive robot with the constants of PARAMETER_NAMES set to ``constants``."""
    kb, kf, lb, lf, m, inertia, spacing = constants
    return dataclasses.replace(
        P.passive_robot(), leg_stiffness=(kb, kf), leg_rest_length=(lb, lf), torso_mass=m,
        torso_inertia=inertia, hip_spacing=spacing,
    )  # fmt: skip


def _constants():
    rob = P.passive_robot()
    return np.array([*rob.per_leg("leg_stiffness"), *rob.per_leg("leg_rest_length"),
                     rob.torso_mass, rob.torso_inertia, rob.hip_spacing])  # fmt: skip


def _flow_through(z, gammas, events, t_end, with_sensitivity, constants=None):
    """From apex z, the passive flow through ``events`` ((kind, leg) in their known order)
    to the fixed time ``t_end`` [s]: (state (6,), sensitivity to (z, gammas, the robot
    constants) or None, the events' times [s])."""
    rob = P.passive_robot() if constants is None else _robot(constants)
    hip = (-0.5 * rob.hip_spacing - rob.com_offset, 0.5 * rob.hip_spacing - rob.com_offset)
    l0 = rob.per_leg("leg_rest_length")
    tangent = P._PassiveTangent(rob, tuple(gammas)) if with_sensitivity else None
    u = np.array([0.0, z[0], z[1], z[2], 0.0, z[3]])
    t, anchors, times = 0.0, [None, None], []
    for kind, leg in (*events, (None, None)):
        if kind == "touchdown":
            guard = Guard(
                lambda u_, leg=leg: u_[1] + hip[leg] * math.sin(u_[2])
                - l0[leg] * math.cos(gammas[leg]),
                -1.0,
            )  # fmt: skip
        elif kind == "liftoff":
            a = anchors[leg]
            guard = Guard(
                lambda u_, leg=leg, a=a: math.hypot(
                    u_[0] + hip[leg] * math.cos(u_[2]) - a, u_[1] + hip[leg] * math.sin(u_[2])
                ) - l0[leg],
                1.0,
            )  # fmt: skip
        seg = flow_to_event(
            P._passive_rhs(rob, list(anchors)), u, t0=t, t_max=t_end,
            guards=[] if kind is None else [guard],
            variational=None if tangent is None else tangent.variational(anchors),
            sensitivity=None if tangent is None else tangent.phi_u, rtol=1e-12, atol=1e-12,
        )  # fmt: skip
        u, t = seg.x, seg.t
        if tangent is not None:
            tangent.phi_u = seg.sensitivity
        if kind is None:
            break
        assert seg.guard == 0, f"{kind} of leg {leg} not reached before {t_end} s"
        times.append(t)
        before = list(anchors)
        if kind == "touchdown":
            anchors[leg] = u[0] + hip[leg] * math.cos(u[2]) + l0[leg] * math.sin(gammas[leg])
        else:
            anchors[leg] = None
        if tangent is not None:
            tangent.jump(kind, leg, u, before, anchors)
    return u, None if tangent is None else tangent.phi_u.copy(), times


@pytest.mark.parametrize(
    "events, after_s",
    [
        ((("touchdown", 0),), 0.02),
        ((("touchdown", 0), ("touchdown", 1), ("liftoff", 0)), 0.01),
    ],
    ids=["touchdown", "liftoff"],
)
def test_sensitivity_jump_at_each_event_matches_differences_of_the_flow(orbits, events, after_s):
    """Ending a short time after the event (in stance after a touchdown, with the back leg
    in flight after its lift-off), the sensitivity to the apex state and the touchdown
    angles and the robot's constants equals differences of the flow across the event."""
    orb = orbits[50.0]
    x0 = np.concatenate((orb.z, orb.touchdown_angles, _constants()))
    t_end = _flow_through(orb.z, orb.touchdown_angles, events, 2.0, False)[2][-1] + after_s

    def f(x):
        return _flow_through(x[:4], x[4:6], events, t_end, False, x[6:])[0]

    _, phi, _ = _flow_through(orb.z, orb.touchdown_angles, events, t_end, True)
    # differences of each variable scaled to its size (stiffness ~ 3e3 N/m, lengths 0.2 m)
    scale_x = np.maximum(1.0, np.abs(x0))
    ref = _richardson(lambda y: f(y * scale_x), x0 / scale_x, 1e-4) / scale_x
    for j in range(len(x0)):  # each column against its own size
        col = max(1e-12, float(np.abs(ref[:, j]).max()))
        np.testing.assert_allclose(phi[:, j], ref[:, j], rtol=0.0, atol=1e-6 * col)


def test_difference_jacobian_is_kept_as_the_check(orbits):
    """jacobian="fd" gives the central-difference Jacobians, which agree with the exact ones
    to their own accuracy (step 1e-5: ~1e-9); an unknown method is refused by name."""
    exact = orbits[50.0]
    fd = passive_bounding_orbit(1.3, 0.35, math.radians(50.0), jacobian="fd")
    assert fd.jacobian_method == "fd"
    assert np.max(np.abs(fd.multipliers - exact.multipliers)) < 1e-7
    assert np.max(np.abs(fd.angle_jacobian - exact.angle_jacobian)) < 1e-7
    with pytest.raises(ValueError, match="jacobian = 'ad'"):
        passive_bounding_orbit(1.3, 0.35, 0.0, jacobian="ad")
