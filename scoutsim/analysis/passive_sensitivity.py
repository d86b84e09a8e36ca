"""How a passive bounding orbit moves with the robot's constants, from exact derivatives
(docs/orbits.md, "Exact derivatives").

A passive orbit solves ``r(gamma, p) = P(z*; gamma, p) - z* = 0`` for the touchdown
angles gamma at a fixed apex state z*. By the implicit function theorem

    dgamma/dp = -(dr/dgamma)^+ dr/dp,

with both Jacobians exact (:func:`~scoutsim.analysis.passive_reference.passive_apex_map_derivative`;
the system has four equations of rank two, consistent because the orbits are symmetric:
:mod:`scoutsim.analysis.passive_orbits`). The period and the mean speed follow from their
exact gradients; the spectral radius (the multipliers other than the energy one) by a
central difference of the exact Jacobian along the orbit's tangent (steps 1e-4 |p|). Only
constants that keep the robot its own mirror image can move: both legs' stiffness and rest
length together, the torso's mass and inertia, the hip spacing.

Units: SI (the touchdown angles in rad); elasticities in % per %.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..parameters import RobotParameters
from .orbit_sensitivity import ParameterSensitivity
from .passive_orbits import PassiveOrbit, non_energy_multipliers
from .passive_reference import PARAMETER_NAMES, passive_apex_map_derivative, passive_robot

__all__ = ["PASSIVE_SENSITIVITY_PARAMETERS", "PASSIVE_SENSITIVITY_METRICS",
           "passive_orbit_sensitivities"]  # fmt: skip

#: the parameters a passive orbit's sensitivities are taken to, and the robot constants
#: (PARAMETER_NAMES) each moves together
_DIRECTIONS = {
    "robot.leg_stiffness": ("leg_stiffness_back", "leg_stiffness_front"),
    "robot.leg_rest_length": ("leg_rest_length_back", "leg_rest_length_front"),
    "robot.torso_mass": ("torso_mass",),
    "robot.torso_inertia": ("torso_inertia",),
    "robot.hip_spacing": ("hip_spacing",),
}
PASSIVE_SENSITIVITY_PARAMETERS = tuple(_DIRECTIONS)
#: the metrics (SI; touchdown angles from the world vertical in rad)
PASSIVE_SENSITIVITY_METRICS = (
    "touchdown_angle_back",
    "touchdown_angle_front",
    "period_s",
    "mean_speed_m_s",
    "spectral_radius",
)
#: a parameter whose dr/dp is not in the range of dr/dgamma by more than this (relative)
#: moves the orbit off the level-apex family
_INCONSISTENT = 1e-6


def _with(rob: RobotParameters, name: str, value: float) -> RobotParameters:
    changes: dict = {name.partition(".")[2]: value}
    return dataclasses.replace(rob, **changes)


def _value(rob: RobotParameters, name: str) -> float:
    """The parameter's value (both legs' value for a per-leg field, which must agree)."""
    fld = name.partition(".")[2]
    if fld in ("leg_stiffness", "leg_rest_length"):
        back, front = rob.per_leg(fld)
        if back != front:
            raise ValueError(
                f"{name}: the legs differ ({back:g}, {front:g}); a passive orbit needs them alike"
            )
        return float(back)
    return float(getattr(rob, fld))


def _spectral_radius(d) -> float:
    return float(np.max(np.abs(non_energy_multipliers(d.state_jacobian))))


def passive_orbit_sensitivities(
    orbit: PassiveOrbit, names="all", *, robot: RobotParameters | None = None
) -> tuple[dict[str, ParameterSensitivity], dict]:
    """The derivatives and elasticities of the passive orbit's metrics
    (:data:`PASSIVE_SENSITIVITY_METRICS`) to each parameter of ``names``
    (:data:`PASSIVE_SENSITIVITY_PARAMETERS`, or "all"), at the orbit's apex state.
    ``robot``: the robot the orbit was found for (default Scout II), made passive.

    Returns ({name: ParameterSensitivity}, the orbit's metrics). ValueError for a name that
    is not allowed."""
    names = list(PASSIVE_SENSITIVITY_PARAMETERS) if names == "all" else list(names)
    for n in names:
        if n not in _DIRECTIONS:
            raise ValueError(
                f"parameter {n!r} is not allowed for a passive orbit: must be one of "
                f"{', '.join(PASSIVE_SENSITIVITY_PARAMETERS)} (changes that keep the robot "
                "its own mirror image)"
            )
    rob = passive_robot(robot)
    gam = np.array(orbit.touchdown_angles)
    d = passive_apex_map_derivative(orbit.z, gam, robot=rob, rtol=orbit.rtol)
    period, stride = d.map.period, d.map.stride_length
    base = {
        "touchdown_angle_back": float(gam[0]),
        "touchdown_angle_front": float(gam[1]),
        "period_s": period,
        "mean_speed_m_s": stride / period,
        "spectral_radius": _spectral_radius(d),
    }
    out = {}
    for n in names:
        e = np.array([1.0 if c in _DIRECTIONS[n] else 0.0 for c in PARAMETER_NAMES])
        value = _value(rob, n)
        rhs = d.parameter_jacobian @ e
        dgam, *_ = np.linalg.lstsq(d.angle_jacobian, -rhs, rcond=None)
        miss = float(np.linalg.norm(d.angle_jacobian @ dgam + rhs))
        if miss > _INCONSISTENT * max(1.0, float(np.linalg.norm(rhs))):
            out[n] = ParameterSensitivity(
                n, value, status=f"the orbit leaves the level-apex family (residual {miss:.2g})"
            )
            continue
        dT = float(d.period_angle_gradient @ dgam + d.period_parameter_gradient @ e)
        dX = float(d.stride_gradient[4:6] @ dgam + d.stride_gradient[6:] @ e)
        h = 1e-4 * abs(value)
        rho = []
        for sign in (1.0, -1.0):
            shifted = _with(rob, n, value + sign * h)
            ds = passive_apex_map_derivative(
                orbit.z, gam + sign * h * dgam, robot=shifted, rtol=orbit.rtol
            )
            rho.append(_spectral_radius(ds))
        deriv = {
            "touchdown_angle_back": float(dgam[0]),
            "touchdown_angle_front": float(dgam[1]),
            "period_s": dT,
            "mean_speed_m_s": (dX * period - stride * dT) / period**2,
            "spectral_radius": (rho[0] - rho[1]) / (2.0 * h),
        }
        elast = {
            k: (v * value / base[k] if base[k] != 0.0 and value != 0.0 else float("nan"))
            for k, v in deriv.items()
        }
        out[n] = ParameterSensitivity(n, value, deriv, elast)
    return out, base
