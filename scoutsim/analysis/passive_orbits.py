"""Periodic bounding orbits of the passive model: fixed points of the apex return map
(:func:`~scoutsim.analysis.passive_reference.passive_apex_map`), their Floquet
multipliers, and a one-parameter continuation in the apex pitch rate (docs/orbits.md).

At a given forward speed ``V`` [m/s], apex height ``H`` [m] and pitch rate ``W`` [rad/s]
with the torso level at the apex, ``z* = (H, 0, V, W)``, :func:`passive_bounding_orbit`
solves ``P(z*; gamma_b, gamma_f) = z*`` for the back and front touchdown angles [rad, from
the world vertical] by Levenberg-Marquardt / Gauss-Newton on the four residuals (two
unknowns; the system is consistent because such orbits are symmetric under the
time-reversal-and-mirror symmetry of the conservative model, which leaves two independent
conditions) with a central finite-difference Jacobian. The Floquet multipliers are the
eigenvalues of the Jacobian ``dP/dz`` at the fixed point, exact by default (variational
equations and saltation matrices, :func:`~scoutsim.analysis.passive_reference.passive_apex_map_derivative`)
or by central differences (``jacobian="fd"``, the check); energy conservation makes one of
them exactly 1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..parameters import RobotParameters
from ..simulation.integrator import IntegratorSettings
from .continuation import multipliers_outside
from .passive_reference import (
    ORBIT_TOLERANCE,
    passive_apex_map,
    passive_apex_map_derivative,
    passive_robot,
)
from .poincare import MapError, fd_jacobian, floquet_multipliers

__all__ = [
    "PassiveOrbit",
    "passive_bounding_orbit",
    "continue_passive_family",
    "non_energy_multipliers",
]


def non_energy_multipliers(jacobian) -> np.ndarray:
    """The multipliers of the passive apex map's Jacobian ``dP/dz`` without the energy
    multiplier (the one nearest +1, which energy conservation fixes at 1), by decreasing
    modulus: those that decide the orbit's stability."""
    return multipliers_outside(floquet_multipliers(jacobian), 1)


@dataclass
class PassiveOrbit:
    """A periodic bounding orbit of the passive model on the apex section.

    Attributes
    ----------
    speed, apex_height, pitch_rate : the prescribed apex state (m/s, m, rad/s; theta = 0).
    touchdown_angles : (back, front) from the world vertical [rad].
    period : stride period, apex to apex [s].
    residual : max |P(z*) - z*| over the four apex components (SI).
    jacobian : (4, 4) dP/dz at the fixed point.
    multipliers : Floquet multipliers (eigenvalues of ``jacobian``), by decreasing modulus.
    order : touchdown order of the legs in the stride.
    iterations : map evaluations of the fixed-point search.
    rtol : integrator tolerance used.
    jacobian_method : "exact" (variational equations and saltation matrices) or "fd"
        (central differences with step ``jacobian_step``).
    angle_jacobian : (4, 2) dP/d(gamma_back, gamma_front) at the fixed point [per rad].
    """

    speed: float
    apex_height: float
    pitch_rate: float
    touchdown_angles: tuple
    period: float
    residual: float
    jacobian: np.ndarray = field(repr=False)
    multipliers: np.ndarray
    order: tuple
    iterations: int
    rtol: float
    jacobian_method: str = "exact"
    angle_jacobian: np.ndarray = field(default_factory=lambda: np.full((4, 2), np.nan), repr=False)

    @property
    def z(self) -> np.ndarray:
        return np.array([self.apex_height, 0.0, self.speed, self.pitch_rate])

    @property
    def touchdown_angles_deg(self) -> tuple:
        return tuple(math.degrees(a) for a in self.touchdown_angles)

    @property
    def unit_multiplier_error(self) -> float:
        """Distance of the multiplier closest to 1 from 1 (energy conservation: ~0)."""
        return float(np.min(np.abs(self.multipliers - 1.0)))

    @property
    def is_stable(self) -> bool:
        """All multipliers except the energy one inside or on the unit circle (+1e-6)."""
        return bool(np.all(np.abs(multipliers_outside(self.multipliers, 1)) <= 1.0 + 1e-6))

    def to_dict(self) -> dict:
        """JSON-safe summary (the keys of ``scoutsim orbit --passive --json`` and more)."""
        return {
            "touchdown_angle_back_deg": math.degrees(self.touchdown_angles[0]),
            "touchdown_angle_front_deg": math.degrees(self.touchdown_angles[1]),
            "period_s": self.period,
            "eigenvalues": [[float(m.real), float(m.imag)] for m in self.multipliers],
            "residual": self.residual,
            "jacobian_method": self.jacobian_method,
        }


def _slip_guess(robot: RobotParameters, speed: float) -> float:
    """Touchdown angle of the symmetric pronk of a spring-mass with both legs (first guess)."""
    k = robot.legs_per_virtual_leg * sum(robot.per_leg("leg_stiffness"))
    t_stance = math.pi * math.sqrt(robot.torso_mass / k)
    return math.asin(min(0.9, speed * t_stance / sum(robot.per_leg("leg_rest_length"))))


def _solve_angles(z, guess, robot, integ, tol, max_iter):
    """Gauss-Newton (Levenberg-Marquardt damped) on r(gamma) = P(z; gamma) - z."""
    z = np.asarray(z, dtype=float)
    n_eval = 0

    def resid(gam):
        nonlocal n_eval
        n_eval += 1
        return passive_apex_map(z, gam, robot=robot, rtol=integ.rtol).z - z

    gam = np.asarray(guess, dtype=float)
    r = resid(gam)
    lam = 1e-3
    h = 1e-6
    for _ in range(max_iter):
        if np.max(np.abs(r)) < tol:
            break
        try:
            J = fd_jacobian(resid, gam, h)
        except MapError:
            break
        JTJ = J.T @ J
        g = J.T @ r
        improved = False
        for _ in range(12):
            step = -np.linalg.solve(JTJ + lam * np.diag(np.diag(JTJ)), g)
            step = np.clip(step, -0.1, 0.1)
            try:
                r_new = resid(gam + step)
            except MapError:
                lam *= 10.0
                continue
            if np.linalg.norm(r_new) < np.linalg.norm(r):
                gam, r = gam + step, r_new
                lam = max(lam / 10.0, 1e-12)
                improved = True
                break
            lam *= 10.0
        if not improved:
            break
    return gam, r, n_eval


def passive_bounding_orbit(
    speed: float,
    apex_height: float,
    pitch_rate: float,
    *,
    guess=None,
    robot: RobotParameters | None = None,
    rtol: float = ORBIT_TOLERANCE,
    tol: float = 1e-11,
    max_iter: int = 40,
    jacobian: str = "exact",
    jacobian_step: float = 1e-5,
) -> PassiveOrbit:
    """Periodic passive bounding through the level-torso apex ``(apex_height, 0, speed,
    pitch_rate)``: solve for the touchdown angles, then linearise the return map.

    Parameters
    ----------
    speed : forward speed at the apex [m/s].
    apex_height : torso COM height at the apex [m].
    pitch_rate : pitch rate at the apex [rad/s] (positive: nose rising, the back leg
        touches down first).
    guess : (back, front) touchdown angles [rad] to start from (default: the spring-mass
        pronk angle for both, then a continuation in pitch rate from 0 if that fails).
    rtol : integrator tolerance (rtol = atol).
    tol : stop when max |P(z*) - z*| < tol.
    jacobian : "exact" (variational equations and saltation matrices) or "fd" (central
        differences of the map, the check).
    jacobian_step : central-difference step of dP/dz with ``jacobian="fd"`` (SI units of
        each component).

    Raises
    ------
    MapError if no orbit is found (residual above 1e-9).
    """
    _check_jacobian(jacobian)
    rob = passive_robot(robot)
    integ = IntegratorSettings(rtol=rtol, atol=rtol)
    z = np.array([apex_height, 0.0, speed, pitch_rate], dtype=float)
    g0 = _slip_guess(rob, speed)
    gam, r, n = (None, None, 0)
    if guess is not None:
        gam, r, n = _solve_angles(z, guess, rob, integ, tol, max_iter)
    elif pitch_rate == 0.0:
        gam, r, n = _solve_angles(z, (g0, g0), rob, integ, tol, max_iter)
    else:
        try:
            gam, r, n = _solve_angles(z, (g0, g0), rob, integ, tol, max_iter)
        except MapError:
            gam = None
        if gam is None or r is None or np.max(np.abs(r)) > 1e-9:
            fam = continue_passive_family(
                speed,
                apex_height,
                np.linspace(0.0, pitch_rate, 6),
                robot=rob,
                rtol=rtol,
                tol=tol,
                linearise=False,
            )
            return _finish(fam[-1], rob, integ, jacobian, jacobian_step)
    res = float(np.max(np.abs(r)))
    if not res <= 1e-9:
        raise MapError(
            f"no periodic orbit found at speed {speed} m/s, apex height "
            f"{apex_height} m, pitch rate {math.degrees(pitch_rate):.3g} deg/s "
            f"(residual {res:.3g} after {n} map evaluations){_asymmetry(rob)}"
        )
    orb = PassiveOrbit(
        speed=float(speed),
        apex_height=float(apex_height),
        pitch_rate=float(pitch_rate),
        touchdown_angles=(float(gam[0]), float(gam[1])),
        period=math.nan,
        residual=res,
        jacobian=np.full((4, 4), np.nan),
        multipliers=np.full(4, np.nan + 0j),
        order=(),
        iterations=n,
        rtol=rtol,
    )
    return _finish(orb, rob, integ, jacobian, jacobian_step)


def _asymmetry(rob: RobotParameters) -> str:
    """A note naming what breaks the back-front mirror symmetry the level-apex orbits rely
    on ("" for a symmetric robot)."""
    what = []
    if rob.com_offset != 0.0:
        what.append(f"com_offset = {rob.com_offset:g} m")
    for fld in ("leg_stiffness", "leg_rest_length"):
        back, front = rob.per_leg(fld)
        if back != front:
            what.append(f"{fld} = [{back:g}, {front:g}]")
    if not what:
        return ""
    return (
        "; the orbits looked for pass through a level-torso apex, which needs the robot's "
        "back-front mirror symmetry, and this robot has none: " + ", ".join(what)
    )


def _check_jacobian(jacobian: str) -> None:
    if jacobian not in ("exact", "fd"):
        raise ValueError(f"jacobian = {jacobian!r}: must be 'exact' or 'fd'")


def _finish(orb: PassiveOrbit, rob, integ, jacobian, jacobian_step) -> PassiveOrbit:
    """Fill in period, order, Jacobians and multipliers of a converged orbit."""
    # the map the orbit was solved on (the derivative's own integration, with the
    # sensitivities under the error control, takes other steps)
    m = passive_apex_map(orb.z, orb.touchdown_angles, robot=rob, rtol=integ.rtol)
    if jacobian == "exact":
        d = passive_apex_map_derivative(orb.z, orb.touchdown_angles, robot=rob, rtol=integ.rtol)
        J, Jg = d.state_jacobian, d.angle_jacobian
    else:

        def f(x):
            return passive_apex_map(x, orb.touchdown_angles, robot=rob, rtol=integ.rtol).z

        def f_angles(gam):
            return passive_apex_map(orb.z, gam, robot=rob, rtol=integ.rtol).z

        J = fd_jacobian(f, orb.z, jacobian_step)
        Jg = fd_jacobian(f_angles, np.array(orb.touchdown_angles), jacobian_step)
    orb.period = m.period
    orb.order = m.order
    orb.residual = float(np.max(np.abs(m.z - orb.z)))
    orb.jacobian = J
    orb.angle_jacobian = Jg
    orb.jacobian_method = jacobian
    orb.multipliers = floquet_multipliers(J)
    return orb


def continue_passive_family(
    speed: float,
    apex_height: float,
    pitch_rates,
    *,
    robot: RobotParameters | None = None,
    rtol: float = ORBIT_TOLERANCE,
    tol: float = 1e-11,
    linearise: bool = True,
    jacobian: str = "exact",
    jacobian_step: float = 1e-5,
) -> list[PassiveOrbit]:
    """Natural-parameter continuation of passive bounding orbits in the apex pitch rate.

    Each solve starts from a secant prediction through the two previous solutions (the
    first from the spring-mass pronk angle). ``pitch_rates`` [rad/s] should be ordered and
    closely spaced (a few tens of deg/s). Returns one :class:`PassiveOrbit` per pitch rate
    (with multipliers if ``linearise``; ``jacobian`` and ``jacobian_step`` as
    :func:`passive_bounding_orbit`)."""
    _check_jacobian(jacobian)
    rob = passive_robot(robot)
    integ = IntegratorSettings(rtol=rtol, atol=rtol)
    out: list[PassiveOrbit] = []
    sols: list[tuple[float, np.ndarray]] = []
    g0 = _slip_guess(rob, speed)
    for w in pitch_rates:
        w = float(w)
        if len(sols) >= 2:
            (w1, a1), (w2, a2) = sols[-2], sols[-1]
            guess = a2 + (a2 - a1) * (w - w2) / (w2 - w1) if w2 != w1 else a2
        elif sols:
            guess = sols[-1][1]
        else:
            guess = np.array([g0, g0])
        z = np.array([apex_height, 0.0, speed, w])
        gam, r, n = _solve_angles(z, guess, rob, integ, tol, 40)
        res = float(np.max(np.abs(r)))
        if not res <= 1e-9:
            raise MapError(
                f"continuation lost the family at pitch rate "
                f"{math.degrees(w):.3g} deg/s (residual {res:.3g})"
            )
        sols.append((w, gam))
        orb = PassiveOrbit(
            speed=float(speed),
            apex_height=float(apex_height),
            pitch_rate=w,
            touchdown_angles=(float(gam[0]), float(gam[1])),
            period=math.nan,
            residual=res,
            jacobian=np.full((4, 4), np.nan),
            multipliers=np.full(4, np.nan + 0j),
            order=(),
            iterations=n,
            rtol=rtol,
        )
        if linearise:
            orb = _finish(orb, rob, integ, jacobian, jacobian_step)
        out.append(orb)
    return out
