"""The periodic orbit of the controlled robot: the fixed point of the sampled stride map
(:func:`~scoutsim.analysis.stride_map.controlled_stride_map`) by Newton's method, and its
Floquet multipliers (docs/orbits.md).

Newton's method with a forward-difference Jacobian and least-squares steps (pinned legs
and stuck motor joints make some coordinates dependent) converges to a residual ~1e-12;
the eigenvalues of the Jacobian at the fixed point are the multipliers. On the Scout II
defaults (Model II, default floor) the orbit lasts 234 ms with spectral radius 0.925.

Units: SI (section coordinates as :data:`~scoutsim.analysis.stride_map.CONTROLLED_Z_NAMES`,
period [s], speed [m/s], angles [rad]; degrees only in ``to_dict``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..names import LEG_NAMES
from ..parameters import DEFAULT_FRICTION_COEFFICIENT
from ..simulation.integrator import IntegratorSettings
from ..simulation.simulator import simulate
from ..state import HybridState
from .poincare import MapError, floquet_multipliers
from .stride_map import (
    CONTROLLED_Z_NAMES,
    controlled_stride_map,
    discrete_modes,
    hs_of,
    section_state,
)

__all__ = ["ControlledOrbit", "controlled_fixed_point"]


@dataclass
class ControlledOrbit:
    """Fixed point of the controlled stride map (section: the control sample at which the
    controller detects back-leg lift-off)."""

    z: np.ndarray  # section coordinates (CONTROLLED_Z_NAMES), SI
    state: object  # the HybridState at the section
    period: float  # [s], a whole number of control periods
    residual: float  # max |P(z) - z| (SI units of each coordinate)
    multipliers: np.ndarray  # eigenvalues of dP/dz (complex)
    jacobian: np.ndarray = field(repr=False)
    iterations: int = 0
    history: list = field(default_factory=list)  # residual per Newton iteration
    #: leg angle from the world vertical (theta + phi) at each leg's touchdown on the orbit
    #: [rad] (back, front; linear interpolation between the 1 kHz samples)
    touchdown_angles_world: tuple = (math.nan, math.nan)
    mean_speed: float = math.nan  # forward travel over the period / period [m/s]

    @property
    def stable(self) -> bool:
        return bool(np.max(np.abs(self.multipliers)) < 1.0)

    def to_dict(self) -> dict:
        return {
            "section": "controller detects back-leg lift-off (control sample)",
            "touchdown_angle_back_deg": math.degrees(self.touchdown_angles_world[0]),
            "touchdown_angle_front_deg": math.degrees(self.touchdown_angles_world[1]),
            "state": {n: float(v) for n, v in zip(CONTROLLED_Z_NAMES, self.z)},
            "period_s": self.period,
            "mean_speed_m_s": self.mean_speed,
            "residual": self.residual,
            "eigenvalues": [[float(m.real), float(m.imag)] for m in self.multipliers],
            "spectral_radius": float(np.max(np.abs(self.multipliers))),
            "stable": self.stable,
            "iterations": self.iterations,
            "residual_history": [float(v) for v in self.history],
        }


def controlled_fixed_point(
    start=None,
    *,
    model: str = "II",
    friction_coefficient: float = DEFAULT_FRICTION_COEFFICIENT,
    robot=None,
    controller=None,
    integrator: IntegratorSettings | None = None,
    settle_duration: float = 12.0,
    tol: float = 1e-10,
    max_iter: int = 10,
    jacobian_step: float = 1e-6,
    progress=None,
) -> ControlledOrbit:
    """Periodic orbit of the controlled robot (Table I law at 1 kHz) by Newton's method on
    the sampled stride map :func:`controlled_stride_map`, and its Floquet multipliers.

    The closed loop is a sampled-data system: between samples the plant flows, at samples
    the controller switches. On the section "the sample at which the controller detects
    back-leg lift-off" the stride map is smooth as long as every controller transition
    stays on the same sample, so a fixed point is a periodic orbit of a whole number of
    control periods, and Newton converges on it quadratically (within a sample-phase
    cell). ``start``: a HybridState at such a sample (default: the last one of a
    ``settle_duration`` run from the default start). Jacobian: forward differences with
    steps ``jacobian_step`` max(1, |z_j|); Newton steps by least squares (the dependent
    coordinates of pinned legs and stuck motor joints make ``dP/dz - I`` rank deficient).
    Default integrator: DOPRI5 at rtol 1e-11 / atol 1e-12, so the map is accurate well
    below ``tol``. MapError if the discrete modes at the section change or no fixed point
    is found within ``max_iter`` iterations. ``progress``: optional callable(str), told
    the settling run and each Newton iteration's residual."""
    integ = integrator or IntegratorSettings(rtol=1e-11, atol=1e-12)
    kw = dict(
        model=model,
        friction_coefficient=friction_coefficient,
        robot=robot,
        controller=controller,
        integrator=integ,
    )
    say = progress or (lambda message: None)
    if start is None:
        say(f"settling: {settle_duration:g} s of model {model} to a Newton start")
        start = simulate(
            robot,
            controller,
            None,
            settle_duration,
            model=model,
            friction_coefficient=friction_coefficient,
        )
    if not isinstance(start, HybridState):
        start = section_state(start)
    disc = discrete_modes(start)
    z0, z1, h1, T = controlled_stride_map(start, **kw)
    z = z0
    hist = []
    J = None
    it = 0
    for it in range(max_iter + 1):
        F = z1 - z
        res = float(np.max(np.abs(F)))
        hist.append(res)
        say(f"Newton iteration {it}: residual max|P(z)-z| = {res:.2e}")
        if discrete_modes(h1) != disc:
            raise MapError(
                f"the discrete state at the section changed ({disc} -> "
                f"{discrete_modes(h1)}): not a period-1 orbit of this section"
            )
        if res < tol or it == max_iter:
            break
        J = np.empty((z.size, z.size))
        for j in range(z.size):
            e = jacobian_step * max(1.0, abs(z[j]))
            zp = z.copy()
            zp[j] += e
            _, zj1, _, Tj = controlled_stride_map(hs_of(zp, disc), **kw)
            if Tj != T:
                raise MapError(
                    f"the stride length changed from {T} s to {Tj} s under a "
                    f"perturbation of {CONTROLLED_Z_NAMES[j]}: the start lies on "
                    "a sample-phase boundary"
                )
            J[:, j] = (zj1 - z1) / e
        dz = np.linalg.lstsq(J - np.eye(z.size), -F, rcond=1e-12)[0]
        z0, z1, h1, T = controlled_stride_map(hs_of(z + dz, disc), **kw)
        z = z0
    if hist[-1] >= tol:
        raise MapError(
            f"Newton did not converge: residual {hist[-1]:.2e} after {it} "
            f"iterations (history {[f'{v:.1e}' for v in hist]})"
        )
    if J is None or it > 0:
        J = np.empty((z.size, z.size))
        for j in range(z.size):
            e = jacobian_step * max(1.0, abs(z[j]))
            zp = z.copy()
            zp[j] += e
            J[:, j] = (controlled_stride_map(hs_of(zp, disc), **kw)[1] - z1) / e
    hs = hs_of(z, disc)
    r = simulate(
        robot,
        controller,
        hs,
        T,
        model=model,
        integrator=integ,
        friction_coefficient=friction_coefficient,
    )
    td = []
    for leg in LEG_NAMES:
        te = r.event_times("touchdown", leg)
        if len(te) == 0:
            td.append(math.nan)
            continue
        g = r.pitch + r.leg_angle(leg)
        td.append(float(np.interp(te[0], r.t, g)))
    return ControlledOrbit(
        z=z,
        state=hs,
        period=T,
        residual=hist[-1],
        multipliers=floquet_multipliers(J),
        jacobian=J,
        iterations=len(hist) - 1,
        history=hist,
        touchdown_angles_world=tuple(td),
        mean_speed=float((r.x[-1] - r.x[0]) / (r.t[-1] - r.t[0])),
    )
