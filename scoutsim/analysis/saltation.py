"""First-order sensitivities of a hybrid flow: the variational equations between events
and the saltation matrix across each event.

A hybrid flow runs under a vector field ``f-`` until the state reaches a guard surface
``g(x) = 0``, is reset to ``x+ = R(x-)`` and continues under ``f+``. Between events the
sensitivity ``Phi = dx(t)/dp`` of the state to the initial state and the parameters
(parameters are carried as states with zero rate, so a reset may depend on them) obeys the
variational equations ``dPhi/dt = (df/dx) Phi``. At the event a perturbation ``dx-`` taken
just before it, at the nominal event time, maps to ``dx+ = S dx-`` with the **saltation
matrix**

    S = DR + (f+ - DR f-) n^T / (n^T f-),     n = grad g(x-)

(Aizerman and Gantmacher 1958; Kong, Payne, Johnson and Council, "Saltation matrices: the
essential tool for linearizing hybrid dynamical systems", Proc. IEEE 2024). The reset's
Jacobian ``DR`` alone would be the answer for an event at a fixed time; the second term is
the event-time correction: the perturbed state reaches the guard
``dt = -n^T dx- / (n^T f-)`` earlier (:func:`event_time_sensitivity`) and spends that time
under the new flow instead of the old one.

The formula needs ``n^T f- != 0``: a flow that grazes the guard (touches it tangentially)
has no first-order sensitivity there, and :func:`saltation_matrix` raises
:class:`GrazingEventError` saying how close to tangential it was. Two events at the same
instant (a pronk's two touchdowns) give a map that is only piecewise smooth: composing the
two saltation matrices in one order gives the derivative on one side.

This module is the general machinery, tested against closed forms (a bouncing point mass,
a spring-damper hopper: tests/analysis/test_saltation.py); the passive model's apex map
(:mod:`scoutsim.analysis.passive_variational`) is built on it. Flows are autonomous (no
explicit time), guards depend on the state only. Units: those of the state.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

__all__ = [
    "Guard",
    "FlowSegment",
    "GrazingEventError",
    "saltation_matrix",
    "event_time_sensitivity",
    "flow_to_event",
]

#: |n^T f-| below this fraction of |n| |f-| is treated as grazing (no first-order
#: sensitivity): the event-time correction would divide by a number dominated by rounding.
GRAZING_COSINE = 1e-9


class GrazingEventError(ArithmeticError):
    """The flow meets the guard tangentially (``n^T f- = 0``): the event time, and with it
    the hybrid flow, is not differentiable there."""


@dataclass(frozen=True)
class Guard:
    """An event surface ``value(x) = 0``, crossed with ``direction`` +1 (increasing), -1
    (decreasing) or 0 (either way). ``value`` takes the state the flow integrates."""

    value: Callable[[np.ndarray], float]
    direction: float = 0.0


@dataclass(frozen=True)
class FlowSegment:
    """The flow from its start to the first guard reached (or to ``t_max``).

    t : time at the end [s].
    x : state at the end (just before the event's reset).
    sensitivity : ``dx(t)/dp`` at the end, before the event's jump (None if not asked).
    guard : index of the guard reached in the list given, or None if ``t_max`` came first.
    """

    t: float
    x: np.ndarray
    sensitivity: np.ndarray | None
    guard: int | None


def _grazing_check(normal, flow_before, rate) -> None:
    scale = float(np.linalg.norm(normal) * np.linalg.norm(flow_before))
    if not abs(rate) > GRAZING_COSINE * scale:
        raise GrazingEventError(
            f"the flow meets the guard tangentially (n.f = {rate:.3g}, |n||f| = "
            f"{scale:.3g}): the event time has no first-order sensitivity here"
        )


def event_time_sensitivity(guard_gradient, flow_before, sensitivity) -> np.ndarray:
    """``dt_event/dp = -n^T Phi- / (n^T f-)``: how the event time moves with the variables
    ``Phi-`` differentiates by (one entry per column of ``sensitivity``) [s per unit].

    guard_gradient : n = grad g at the event state, (n,).
    flow_before : f- at the event state, (n,).
    sensitivity : Phi- just before the event, (n, m).
    """
    n = np.asarray(guard_gradient, dtype=float)
    f = np.asarray(flow_before, dtype=float)
    rate = float(n @ f)
    _grazing_check(n, f, rate)
    return -(n @ np.asarray(sensitivity, dtype=float)) / rate


def saltation_matrix(reset_jacobian, flow_before, flow_after, guard_gradient) -> np.ndarray:
    """``S = DR + (f+ - DR f-) n^T / (n^T f-)``: the jump of the sensitivities at an event.

    reset_jacobian : DR = dR/dx at the event state, (n, n) (the identity if the event
        resets nothing).
    flow_before, flow_after : f- at the event state and f+ at the reset state, (n,).
    guard_gradient : n = grad g at the event state, (n,).

    Raises :class:`GrazingEventError` if ``n^T f-`` vanishes relative to ``|n| |f-|``.
    """
    DR = np.asarray(reset_jacobian, dtype=float)
    fm = np.asarray(flow_before, dtype=float)
    fp = np.asarray(flow_after, dtype=float)
    n = np.asarray(guard_gradient, dtype=float)
    rate = float(n @ fm)
    _grazing_check(n, fm, rate)
    return DR + np.outer(fp - DR @ fm, n) / rate


class _SolverEvent:
    """A :class:`Guard` as SciPy's ``solve_ivp`` takes an event: terminal, directed, and
    reading the state part of the integrated vector."""

    terminal = True

    def __init__(self, guard: Guard, n: int):
        self.guard, self.n, self.direction = guard, n, guard.direction

    def __call__(self, t, y) -> float:
        return self.guard.value(y[: self.n])


def flow_to_event(
    flow: Callable[[np.ndarray], Sequence[float]],
    x0,
    *,
    t0: float,
    t_max: float,
    guards: Sequence[Guard],
    variational: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None,
    sensitivity=None,
    rtol: float,
    atol: float,
) -> FlowSegment:
    """Integrate ``dx/dt = flow(x)`` from ``x0`` at ``t0`` until the first guard is reached
    (SciPy DOP853 with located events), with the sensitivities if asked.

    flow : the vector field, x -> dx/dt.
    guards : the event surfaces to watch (:class:`Guard`); the first one reached ends the
        segment.
    variational : (x, Phi) -> dPhi/dt, the variational equations (``(df/dx) Phi`` plus, for
        parameters carried outside ``x``, their forcing term); with ``sensitivity`` (the
        initial Phi, (n, m)) the sensitivities are integrated with the state and under the
        same error control.
    rtol, atol : DOP853 tolerances (applied to state and sensitivities alike).
    """
    from scipy.integrate import solve_ivp

    x0 = np.asarray(x0, dtype=float)
    n = len(x0)
    events = [_SolverEvent(g, n) for g in guards]
    if sensitivity is None or variational is None:

        def rhs(t, y):
            return flow(y)

        y0 = x0
        shape = None
    else:
        phi0 = np.asarray(sensitivity, dtype=float)
        shape = phi0.shape

        def rhs(t, y):
            x = y[:n]
            dphi = variational(x, y[n:].reshape(shape))
            return np.concatenate((np.asarray(flow(x), dtype=float), np.ravel(dphi)))

        y0 = np.concatenate((x0, phi0.ravel()))
    sol = solve_ivp(rhs, (t0, t_max), y0, method="DOP853", rtol=rtol, atol=atol, events=events)
    t_events, y_events = sol.t_events or [], sol.y_events or []
    hit = [(te[0], i) for i, te in enumerate(t_events) if len(te)]
    if hit:
        te, i = min(hit)
        y, t, which = np.asarray(y_events[i][0]), float(te), i
    else:
        y, t, which = sol.y[:, -1], float(sol.t[-1]), None
    phi = None if shape is None else y[n:].reshape(shape).copy()
    return FlowSegment(t=t, x=y[:n].copy(), sensitivity=phi, guard=which)
