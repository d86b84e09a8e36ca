"""Saltation matrices and the variational flow (scoutsim.analysis.saltation) against closed
forms: a point mass bouncing with restitution and a vertical spring-damper hopper, whose
sensitivities are derived by hand here, and against central differences of the hybrid flow
across each event."""

import math

import numpy as np
import pytest

from scoutsim.analysis.saltation import (
    GrazingEventError,
    Guard,
    event_time_sensitivity,
    flow_to_event,
    saltation_matrix,
)

G = 9.81
TOL = dict(rtol=1e-12, atol=1e-12)


# --- a point mass bouncing with restitution e: x = (height y, velocity v) ---------------


def _fall(x):
    return [x[1], -G]


def _fall_var(x, phi):
    return np.array([[0.0, 1.0], [0.0, 0.0]]) @ phi


GROUND = Guard(lambda x: x[0], -1.0)


def _bounce(x0, duration, e, sensitivity=None):
    """Height and velocity after ``duration`` [s] from x0, bouncing once (and its
    sensitivity to x0 if asked)."""
    phi = None if sensitivity is None else np.eye(2)
    seg = flow_to_event(
        _fall, x0, t0=0.0, t_max=duration, guards=[GROUND],
        variational=_fall_var, sensitivity=phi, **TOL,
    )  # fmt: skip
    assert seg.guard == 0
    x = np.array([0.0, -e * seg.x[1]])
    if phi is not None:
        S = saltation_matrix(np.diag([1.0, -e]), _fall(seg.x), _fall(x), [1.0, 0.0])
        phi = S @ seg.sensitivity
    end = flow_to_event(
        _fall, x, t0=seg.t, t_max=duration, guards=[],
        variational=_fall_var, sensitivity=phi, **TOL,
    )  # fmt: skip
    return end.x, end.sensitivity, seg


def test_bouncing_mass_saltation_matches_its_closed_form():
    """S = [[-e, 0], [-(1 + e) g / v-, -e]] at an impact with restitution e, v- < 0."""
    e, v = 0.7, -2.3
    S = saltation_matrix(np.diag([1.0, -e]), [v, -G], [-e * v, -G], [1.0, 0.0])
    closed = np.array([[-e, 0.0], [-(1.0 + e) * G / v, -e]])
    np.testing.assert_allclose(S, closed, rtol=1e-15, atol=0.0)


def test_bouncing_mass_flow_sensitivity_matches_its_closed_form():
    """Across the impact, d(y, v)(T)/d(y0, v0) of the integrated variational flow equals
    the hand-derived Jacobian of the closed-form trajectory: s = sqrt(v0^2 + 2 g y0),
    impact at t1 = (v0 + s)/g, then y = e s tau - g tau^2/2, v = e s - g tau, tau = T - t1."""
    y0, v0, e, T = 1.2, 0.8, 0.7, 1.0
    x, phi, seg = _bounce([y0, v0], T, e, sensitivity=True)
    s = math.sqrt(v0 * v0 + 2 * G * y0)
    t1 = (v0 + s) / G
    tau = T - t1
    assert seg.t == pytest.approx(t1, abs=1e-12)
    np.testing.assert_allclose(x, [e * s * tau - 0.5 * G * tau**2, e * s - G * tau], atol=1e-11)
    ds = np.array([G / s, v0 / s])
    dtau = -np.array([1.0 / s, (1.0 + v0 / s) / G])
    dy = e * tau * ds + (e * s - G * tau) * dtau
    dv = e * ds - G * dtau
    np.testing.assert_allclose(phi, np.vstack((dy, dv)), rtol=1e-10, atol=1e-11)


def test_event_time_sensitivity_of_the_impact_matches_its_closed_form():
    """dt1/d(y0, v0) = (1/s, (1 + v0/s)/g)."""
    y0, v0 = 1.2, 0.8
    seg = flow_to_event(
        _fall, [y0, v0], t0=0.0, t_max=2.0, guards=[GROUND],
        variational=_fall_var, sensitivity=np.eye(2), **TOL,
    )  # fmt: skip
    s = math.sqrt(v0 * v0 + 2 * G * y0)
    dt = event_time_sensitivity([1.0, 0.0], _fall(seg.x), seg.sensitivity)
    np.testing.assert_allclose(dt, [1.0 / s, (1.0 + v0 / s) / G], rtol=1e-10)


def test_grazing_event_is_refused():
    """A flow tangent to the guard (n.f = 0) has no first-order event sensitivity."""
    with pytest.raises(GrazingEventError, match="tangentially"):
        saltation_matrix(np.eye(2), [0.0, -G], [0.0, -G], [1.0, 0.0])


# --- a vertical hopper: mass m on a massless spring-damper leg (k, c, rest length l0) ---

M, K, C, L0 = 2.0, 800.0, 6.0, 0.3


def _flight(x):
    return [x[1], -G]


def _stance(x):
    return [x[1], (K * (L0 - x[0]) - C * x[1]) / M - G]


A_FLIGHT = np.array([[0.0, 1.0], [0.0, 0.0]])
A_STANCE = np.array([[0.0, 1.0], [-K / M, -C / M]])
TOUCHDOWN = Guard(lambda x: x[0] - L0, -1.0)
LIFTOFF = Guard(lambda x: x[0] - L0, 1.0)


def _hop(x0, duration, sensitivity=None, event_time_term=True):
    """Flight, stance, flight for ``duration`` [s]: state and sensitivity at the end
    (without ``event_time_term`` the sensitivities pass the events by the reset's Jacobian
    alone, the identity)."""
    x, t = np.asarray(x0, dtype=float), 0.0
    phi = None if sensitivity is None else np.eye(2)
    for flow, A, guard, after in (
        (_flight, A_FLIGHT, TOUCHDOWN, _stance),
        (_stance, A_STANCE, LIFTOFF, _flight),
        (_flight, A_FLIGHT, None, None),
    ):
        seg = flow_to_event(
            flow, x, t0=t, t_max=duration, guards=[] if guard is None else [guard],
            variational=lambda x_, p, A=A: A @ p, sensitivity=phi, **TOL,
        )  # fmt: skip
        x, t, phi = seg.x, seg.t, seg.sensitivity
        if seg.guard is None:  # the run ended before this phase's event
            break
        if guard is not None:
            if phi is not None and event_time_term:
                phi = saltation_matrix(np.eye(2), flow(x), after(x), [1.0, 0.0]) @ phi
    return x, phi


def test_hopper_touchdown_and_liftoff_saltation_match_their_closed_forms():
    """The damper force -c v switches on at touchdown and off at lift-off (y = l0):
    S_td = [[1, 0], [-c/m, 1]], S_lo = [[1, 0], [c/m, 1]], whatever the velocity."""
    for v in (-1.7, -0.4):
        x = np.array([L0, v])
        S_td = saltation_matrix(np.eye(2), _flight(x), _stance(x), [1.0, 0.0])
        np.testing.assert_allclose(S_td, [[1.0, 0.0], [-C / M, 1.0]], rtol=1e-14, atol=1e-14)
        x = np.array([L0, -v])
        S_lo = saltation_matrix(np.eye(2), _stance(x), _flight(x), [1.0, 0.0])
        np.testing.assert_allclose(S_lo, [[1.0, 0.0], [C / M, 1.0]], rtol=1e-14, atol=1e-14)


def _richardson_jacobian(f, x, h):
    def central(h):
        cols = []
        for i in range(len(x)):
            e = np.zeros(len(x))
            e[i] = h
            cols.append((f(x + e) - f(x - e)) / (2 * h))
        return np.column_stack(cols)

    return (4.0 * central(h / 2) - central(h)) / 3.0


@pytest.mark.parametrize("duration", [0.3, 0.45])
def test_hopper_flow_sensitivity_across_touchdown_and_liftoff_matches_differences(duration):
    """Through touchdown (duration 0.3 s ends in stance) and lift-off (0.45 s ends in the
    next flight), the integrated sensitivity equals Richardson-extrapolated central
    differences of the hybrid flow."""
    x0 = np.array([0.5, 0.0])
    _, phi = _hop(x0, duration, sensitivity=True)
    ref = _richardson_jacobian(lambda x: _hop(x, duration)[0], x0, 1e-4)
    np.testing.assert_allclose(phi, ref, rtol=1e-7, atol=1e-8)


def test_without_the_event_time_term_the_hopper_sensitivity_is_wrong():
    """The saltation's event-time term matters here: passing the events by the reset's
    Jacobian alone (the identity) misses the damper switching on and off, and the
    sensitivity is off by order c/m times the stance-time shift, so the difference check
    above can fail."""
    x0 = np.array([0.5, 0.0])
    _, phi = _hop(x0, 0.45, sensitivity=True, event_time_term=False)
    ref = _richardson_jacobian(lambda x: _hop(x, 0.45)[0], x0, 1e-4)
    assert np.max(np.abs(phi - ref)) > 1e-2
