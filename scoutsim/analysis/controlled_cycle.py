"""The converged bounding cycle of the controlled robot, estimated by simulation alone: a
cross-check of the Newton solution (:mod:`scoutsim.analysis.controlled_orbit`).

**Section**: back-leg lift-off (the plant's event); the section state is the torso's
``(y, theta, dx, dy, dtheta)`` there (:data:`LIFTOFF_STATE_NAMES`; m, rad, m/s, m/s,
rad/s), interpolated between the 1 kHz samples. :func:`controlled_cycle` runs one long
simulation, takes the mean of the last strides' section states as the cycle and fits the
multipliers to the converging transient (least squares, ``dz_{k+1} = A dz_k``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..parameters import DEFAULT_FRICTION_COEFFICIENT
from ..simulation.integrator import IntegratorSettings
from ..simulation.simulator import simulate
from ..state import InitialState
from .poincare import MapError, floquet_multipliers

__all__ = ["ControlledCycle", "controlled_cycle", "LIFTOFF_STATE_NAMES"]

#: Torso components of the controlled section state at back-leg lift-off.
LIFTOFF_STATE_NAMES = ("y", "theta", "dx", "dy", "dtheta")


@dataclass
class ControlledCycle:
    """Steady cycle of the controlled robot on the back-leg lift-off section.

    Attributes
    ----------
    z : (5,) mean torso state (y, theta, dx, dy, dtheta) at back-leg lift-off over the
        last ``n_tail`` strides (SI).
    period : mean stride period over the tail [s].
    spread : max |z_k - z| over the tail (componentwise max): the cycle's stride-to-stride
        jitter (the 1 kHz sample-and-hold makes the map piecewise smooth, so the strides
        settle onto a band, not a point).
    multipliers : eigenvalues of the linear stride map fitted (least squares) to the
        deviations of consecutive section states along the transient, by decreasing
        modulus; an estimate, not a Jacobian.
    n_strides, n_tail : strides seen / used for z.
    outcome : outcome of the run.
    method : how the multipliers were obtained.
    """

    z: np.ndarray
    period: float
    spread: np.ndarray
    multipliers: np.ndarray
    n_strides: int
    n_tail: int
    outcome: str
    method: str

    def to_dict(self) -> dict:
        return {
            "section": "back-leg lift-off",
            "state_names": list(LIFTOFF_STATE_NAMES),
            "state": [float(v) for v in self.z],
            "stride_to_stride_spread": [float(v) for v in self.spread],
            "period_s": self.period,
            "eigenvalues": [[float(m.real), float(m.imag)] for m in self.multipliers],
            "n_strides": self.n_strides,
            "n_tail": self.n_tail,
            "outcome": self.outcome,
            "method": self.method,
        }


def _liftoff_states(result):
    """Torso state at each back-leg lift-off: positions by cubic Hermite on (q, dq) of the
    1 kHz samples, velocities linearly (their derivative, the acceleration, is not stored;
    error O(h^2 a'), about 1e-4 m/s)."""
    from ..result.interpolation import hermite

    t = result.t
    te = result.event_times("liftoff", "back")
    te = te[(te > t[0]) & (te < t[-1])]
    cols = []
    for q, dq in ((result.height, result.vertical_speed), (result.pitch, result.pitch_rate)):
        cols.append(hermite(t, q, dq, te))
    for dq in (result.forward_speed, result.vertical_speed, result.pitch_rate):
        cols.append(np.interp(te, t, dq))
    return te, np.column_stack(cols)


def controlled_cycle(
    *,
    model: str = "II",
    friction_coefficient: float = DEFAULT_FRICTION_COEFFICIENT,
    duration: float = 12.0,
    robot=None,
    controller=None,
    initial_state: InitialState | None = None,
    integrator: IntegratorSettings | None = None,
    n_tail: int = 10,
) -> ControlledCycle:
    """Converged bounding cycle of the controlled robot (default Model II on the default floor).

    Simulation-only estimate (no restarts; :func:`controlled_fixed_point` is the Newton
    solution on the sampled stride map). The cycle is found by converging simulation (mean of the last ``n_tail`` back-leg lift-off
    states) and its multipliers are estimated by finite differences along the transient: a
    least-squares fit ``dz_{k+1} = A dz_k`` of the deviations from the converged state of
    the strides whose deviation is above 20x the converged jitter.
    """
    r = simulate(
        robot,
        controller,
        initial_state,
        duration,
        model=model,
        integrator=integrator,
        friction_coefficient=friction_coefficient,
    )
    te, Z = _liftoff_states(r)
    n = len(te)
    if n < n_tail + 3:
        raise MapError(
            f"only {n} back-leg lift-offs in {duration} s (outcome {r.outcome}): no steady cycle"
        )
    tail = Z[-n_tail:]
    z = tail.mean(axis=0)
    spread = np.max(np.abs(tail - z), axis=0)
    period = float(np.mean(np.diff(te[-n_tail - 1 :])))
    scale = np.maximum(np.abs(Z).max(axis=0), 1e-3)
    D = (Z - z) / scale
    noise = max(20.0 * float(np.max(spread / scale)), 1e-9)
    use = np.flatnonzero(np.max(np.abs(D[:-1]), axis=1) > noise)
    if len(use) >= Z.shape[1] + 2:
        X, Y = D[use], D[use + 1]
        A, *_ = np.linalg.lstsq(X, Y, rcond=None)
        mult = floquet_multipliers(A.T)
        method = (
            f"least-squares linear stride map fitted to {len(use)} transient strides "
            "(finite differences along the converging transient; see "
            "controlled_fixed_point for the Newton solution)"
        )
    else:
        mult = np.full(Z.shape[1], np.nan + 0j)
        method = "too few transient strides above the jitter to fit the stride map"
    return ControlledCycle(
        z=z,
        period=period,
        spread=spread,
        multipliers=mult,
        n_strides=n,
        n_tail=n_tail,
        outcome=r.outcome,
        method=method,
    )
