"""The family of passive bounding orbits in the apex pitch rate, by pseudo-arclength
continuation with exact Jacobians, with its multipliers along the branch and where they
cross the unit circle (docs/orbits.md, "Families of gaits").

The unknowns are the touchdown angles (gamma_b, gamma_f) [rad, from the world vertical]
and the parameter the apex pitch rate W [rad/s]; the residual is the apex map's
``P(z*(W); gamma) - z*(W)`` with ``z* = (H, 0, V, W)`` (four components, rank two:
:mod:`scoutsim.analysis.passive_orbits`). Its Jacobian ``[dP/dgamma, dP/dW - dz*/dW]``
comes from :func:`~scoutsim.analysis.passive_reference.passive_apex_map_derivative`, so
the corrector converges quadratically and the multipliers of every point are exact. The
energy multiplier (always 1) is left out of the spectral radius and of the crossings.

Units: SI inside; the table's angles and pitch rate in degrees, as their names say.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ..parameters import RobotParameters
from .continuation import (
    BranchStep,
    ContinuationSettings,
    crossings_between,
    locate_fold,
    pseudo_arclength,
)
from .gait_family import GaitFamily
from .passive_orbits import non_energy_multipliers, passive_bounding_orbit
from .passive_reference import ORBIT_TOLERANCE, passive_apex_map_derivative, passive_robot
from .poincare import MapError, floquet_multipliers

__all__ = ["PITCH_RATE", "passive_family"]

#: the energy multiplier of a conservative orbit: left out of the stability assessment
_ENERGY = 1
#: an orbit of the conservative model is (neutrally) stable when no multiplier other than
#: the energy one lies outside the unit circle by more than this
_STABLE_MARGIN = 1e-9
#: the varied parameter's column
PITCH_RATE = "pitch_rate_deg"


def _residual(speed, apex_height, rob, rtol, cache):
    def residual(w):
        gam, W = w[:2], float(w[2])
        z = np.array([apex_height, 0.0, speed, W])
        d = passive_apex_map_derivative(z, gam, robot=rob, rtol=rtol)
        cache[w.tobytes()] = d
        J = np.column_stack((d.angle_jacobian, d.state_jacobian[:, 3] - np.eye(4)[3]))
        return d.map.z - z, J

    return residual


def passive_family(
    speed: float,
    apex_height: float,
    pitch_rate_range: tuple[float, float],
    *,
    robot: RobotParameters | None = None,
    rtol: float = ORBIT_TOLERANCE,
    settings: ContinuationSettings | None = None,
    progress: Callable[[str], None] | None = None,
) -> GaitFamily:
    """The branch of passive bounding orbits through level-torso apexes of ``speed``
    [m/s] and ``apex_height`` [m] as the apex pitch rate runs over ``pitch_rate_range``
    (lo, hi) [rad/s], from lo upwards, by pseudo-arclength continuation
    (:func:`~scoutsim.analysis.continuation.pseudo_arclength`; the arclength in rad and
    rad/s, first step 0.05, at most 0.2). Each crossing of the unit circle by a multiplier
    between two neighbours is located by bisection along the branch and added as a row
    naming it ("fold", "branch point", "period doubling", "torus";
    :func:`~scoutsim.analysis.continuation.crossing_kind`), and so is each turning point
    of the pitch rate ("fold": the branch comes back; it may then leave the range at its
    lower end).

    Raises MapError if no orbit is found at the lower end.
    """
    lo, hi = (float(v) for v in pitch_rate_range)
    if not hi > lo:
        raise ValueError(f"pitch_rate_range = ({lo}, {hi}): the upper end must exceed the lower")
    say = progress or (lambda message: None)
    rob = passive_robot(robot)
    cache: dict = {}
    residual = _residual(speed, apex_height, rob, rtol, cache)

    def derivative(w):
        key = w.tobytes()
        if key not in cache:
            residual(w)
        return cache[key]

    def multipliers(w):
        return floquet_multipliers(derivative(w).state_jacobian)

    def told(step: BranchStep) -> None:
        say(
            f"pitch rate {math.degrees(step.parameter):8.3f} deg/s: "
            f"residual {step.residual:.1e} after {step.iterations} iteration(s)"
        )

    w0 = _start(speed, apex_height, lo, rob, rtol, residual, settings)
    steps, stopped = pseudo_arclength(
        residual, w0, parameter_range=(lo, hi), settings=settings, progress=told
    )
    fam = GaitFamily(
        parameter=PITCH_RATE,
        stopped=stopped,
        setting={
            "model": "passive",
            "speed_m_s": float(speed),
            "apex_height_m": float(apex_height),
        },
        method="pseudo-arclength",
    )
    prev: BranchStep | None = None
    for step in steps:
        if prev is not None:
            events = crossings_between(residual, prev, step, multipliers, trivial=_ENERGY)
            fold = locate_fold(residual, prev, step)
            if fold is not None and not any(kind == "fold" for kind, _ in events):
                events.append(("fold", fold))
            origin, chord = prev.w, step.w - prev.w
            for kind, at in sorted(events, key=lambda e: float((e[1].w - origin) @ chord)):
                fam.rows.append(_row(at.w, derivative(at.w), kind))
                say(f"{kind} at pitch rate {math.degrees(at.parameter):.4f} deg/s")
        fam.rows.append(_row(step.w, derivative(step.w), ""))
        prev = step
    return fam


def _start(speed, apex_height, lo, rob, rtol, residual, settings) -> np.ndarray:
    """(gamma_b, gamma_f, lo): the orbit at the lower end, solved there, or, if that fails
    far from the pronk, followed along the branch from the pronk at zero pitch rate."""
    try:
        orb = passive_bounding_orbit(speed, apex_height, lo, robot=rob, rtol=rtol)
        return np.array([*orb.touchdown_angles, lo])
    except MapError as exc:
        if lo == 0.0:
            raise
        why = exc
    pronk = passive_bounding_orbit(speed, apex_height, 0.0, robot=rob, rtol=rtol)
    steps, _ = pseudo_arclength(
        residual,
        np.array([*pronk.touchdown_angles, 0.0]),
        parameter_range=(min(lo, 0.0), max(lo, 0.0)),
        direction=1.0 if lo > 0.0 else -1.0,
        settings=settings,
    )
    if not steps or abs(steps[-1].parameter - lo) > 1e-12 * max(1.0, abs(lo)):
        raise MapError(
            f"no orbit at pitch rate {math.degrees(lo):.6g} deg/s: solved there, {why}; "
            "followed from the pronk, the branch does not reach it"
        )
    return steps[-1].w


def _row(w, d, bifurcation: str) -> dict:
    m = non_energy_multipliers(d.state_jacobian)
    rho = float(np.max(np.abs(m)))
    return {
        PITCH_RATE: math.degrees(w[2]),
        "touchdown_angle_back_deg": math.degrees(w[0]),
        "touchdown_angle_front_deg": math.degrees(w[1]),
        "period_s": d.map.period,
        "strides": 1,
        "mean_speed_m_s": d.map.mean_speed,
        "spectral_radius": rho,
        "stable": bool(rho <= 1.0 + _STABLE_MARGIN),
        "bifurcation": bifurcation,
        "multipliers": [(float(x.real), float(x.imag)) for x in m],
        "status": "ok",
    }
