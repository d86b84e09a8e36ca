"""The independent SciPy formulation of the passive model, and its apex return map.

The passive conservative model (docs/specification.md section 2: massless, undamped legs
placed in flight at prescribed touchdown angles from the world vertical, up to two
undamped axial springs ``k_v = legs_per_virtual_leg * k`` between the hips and the pinned
toes in stance) is the same model as ``simulate(..., model="passive")`` with
:func:`passive_robot`, written here a second time with SciPy: the torso's equations
(:func:`_passive_rhs`) integrated by DOP853 phase by phase, touchdown (toe height 0,
descending) and lift-off (``l = l0``) located as events. It is used

* by :func:`passive_apex_map`, the return map the passive orbits
  (:mod:`scoutsim.analysis.passive_orbits`) are found on, because the compiled massless
  touchdown occasionally undoes itself at rounding level and lets the toe through the
  ground (:func:`_glitched` detects it; docs/orbits.md);
* as a cross-check of the compiled simulator: tests/analysis/test_orbits.py checks that a
  ``simulate()`` run gives the same next apex, and tests/_core/numerics/test_passive_bounding.py
  runs the compiled simulator on the orbits found here.

**Section**: the torso apex in double flight, ``dy = 0`` with ``y`` at a maximum; the
section state is ``z = (y, theta, dx, dtheta)`` (:data:`APEX_STATE_NAMES`; x is irrelevant,
the legs carry no state). In double flight the torso is ballistic, so the next apex follows
in closed form from the state at the last lift-off, and the map is as accurate as the
integrator (:data:`ORBIT_TOLERANCE`, rtol = atol = 1e-12).

Units: SI (m, rad, m/s, rad/s, s).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..names import LEG_NAMES, EventKind, Leg
from ..parameters import RobotParameters
from .poincare import MapError
from .saltation import Guard, flow_to_event, saltation_matrix

__all__ = [
    "passive_robot",
    "passive_apex_map",
    "ApexMap",
    "APEX_STATE_NAMES",
    "ORBIT_TOLERANCE",
    "ApexMapDerivative",
    "passive_apex_map_derivative",
    "TANGENT_STATE_NAMES",
    "TANGENT_VARIABLES",
    "PARAMETER_NAMES",
    "SIMULTANEOUS_EVENT_TOL",
]

#: Components of the apex section state z.
APEX_STATE_NAMES = ("y", "theta", "dx", "dtheta")
#: Integrator tolerance of the orbit computations (rtol = atol).
ORBIT_TOLERANCE = 1e-12


def passive_robot(robot: RobotParameters | None = None) -> RobotParameters:
    """The massless-leg conservative configuration (docs/specification.md section 2) of ``robot`` (default Scout II):
    leg mass, leg inertia and leg damping set to zero."""
    import dataclasses

    base = robot if robot is not None else RobotParameters()
    return dataclasses.replace(base, leg_mass=0.0, leg_inertia=0.0, leg_damping=0.0)


@dataclass(frozen=True)
class ApexMap:
    """One evaluation of the apex return map.

    z : (4,) the next apex state (y [m], theta [rad], dx [m/s], dtheta [rad/s]).
    period : time from the start apex to the next [s].
    order : legs in the order of their first touchdown ("back"/"front"; simultaneous
        touchdowns are listed back first).
    stride_length : forward travel of the torso from the start apex to the next [m].
    """

    z: np.ndarray
    period: float
    order: tuple
    stride_length: float = math.nan

    @property
    def mean_speed(self) -> float:
        """Mean forward speed over the stride [m/s]."""
        return self.stride_length / self.period


def _glitched(result) -> bool:
    """True if a massless leg's touchdown in the ``simulate()`` run ``result`` was undone
    at the same instant (zero-length stance) and not redone: the toe then passes through
    the ground. This rounding-level defect of the compiled massless touchdown
    (docs/orbits.md) is why :func:`passive_apex_map` integrates the passive equations
    itself."""
    for leg in Leg:
        log = result.event_log(leg=leg)
        t, kinds = log["t"], log["kind"]
        for i in range(len(t) - 1):
            if (
                kinds[i] == EventKind.TOUCHDOWN
                and kinds[i + 1] == EventKind.LIFTOFF
                and t[i + 1] - t[i] < 1e-12
            ):
                if not (
                    i + 2 < len(t)
                    and kinds[i + 2] == EventKind.TOUCHDOWN
                    and t[i + 2] - t[i + 1] < 1e-9
                ):
                    return True
    return False


def _hips(rob: RobotParameters) -> tuple[float, float]:
    """The hips' positions along the torso axis from the torso COM [m], -L - e and L - e
    (L half the hip spacing, e the COM offset), written out here from the fields."""
    half = 0.5 * rob.hip_spacing
    return (-half - rob.com_offset, half - rob.com_offset)


def _passive_rhs(rob: RobotParameters, anchors):
    """Torso equations of the massless-leg passive model (docs/specification.md section 2): up to two undamped
    axial springs k_v = legs_per_virtual_leg * k between the hips and pinned toes (each leg
    with its own k and l0)."""
    m, I, g = rob.torso_mass, rob.torso_inertia, rob.gravity
    k = [rob.legs_per_virtual_leg * v for v in rob.per_leg("leg_stiffness")]
    l0, hip = rob.per_leg("leg_rest_length"), _hips(rob)

    def rhs(u):
        x, y, th = u[0], u[1], u[2]
        c, sn = math.cos(th), math.sin(th)
        fx = fy = tq = 0.0
        for leg, ax in enumerate(anchors):
            if ax is None:
                continue
            sL = hip[leg]
            hx, hy = x + sL * c, y + sL * sn
            dx_, dy_ = hx - ax, hy
            ll = math.hypot(dx_, dy_)
            F = k[leg] * (l0[leg] - ll)
            Fx, Fy = F * dx_ / ll, F * dy_ / ll
            fx += Fx
            fy += Fy
            tq += sL * c * Fy - sL * sn * Fx
        return [u[3], u[4], u[5], fx / m, fy / m - g, tq / I]

    return rhs


#: Layout of the state the passive stride's sensitivities are taken of: the torso's six
#: coordinates and rates, the back and front toe anchors (x of the pinned toe [m]), then
#: constants (zero rate) that the flow, the touchdown reset or a guard depend on: the
#: touchdown angles [rad], the legs' stiffness (per physical leg, N/m) and rest length [m],
#: the torso's mass [kg] and inertia [kg m^2] and the hip spacing [m].
TANGENT_STATE_NAMES = ("x", "y", "theta", "dx", "dy", "dtheta", "anchor_back", "anchor_front",
                       "gamma_back", "gamma_front", "leg_stiffness_back", "leg_stiffness_front",
                       "leg_rest_length_back", "leg_rest_length_front", "torso_mass",
                       "torso_inertia", "hip_spacing")  # fmt: skip
_ANCHOR, _GAMMA, _K, _L0, _M, _I, _D = 6, 8, 10, 12, 14, 15, 16
_NW = len(TANGENT_STATE_NAMES)
#: the robot constants of the derivative's parameter blocks (columns of
#: ApexMapDerivative.parameter_jacobian), as named in TANGENT_STATE_NAMES
PARAMETER_NAMES = TANGENT_STATE_NAMES[_K:]
#: the variables the sensitivities are taken with respect to (the columns of ``phi``): the
#: apex state z, then the constants of TANGENT_STATE_NAMES from the touchdown angles on
TANGENT_VARIABLES = ("y", "theta", "dx", "dtheta", *TANGENT_STATE_NAMES[_GAMMA:])


class _PassiveTangent:
    """The sensitivities of the passive stride (docs/orbits.md, "Exact derivatives"):
    ``phi`` = d(state of :data:`TANGENT_STATE_NAMES`)/d(:data:`TANGENT_VARIABLES`),
    integrated with the torso by the variational equations of :func:`_passive_rhs` and
    mapped across each touchdown and lift-off by its saltation matrix
    (:mod:`scoutsim.analysis.saltation`)."""

    def __init__(self, rob: RobotParameters, gammas):
        self.rob, self.gammas = rob, gammas
        self.n = rob.legs_per_virtual_leg
        self.k = [self.n * v for v in rob.per_leg("leg_stiffness")]
        self.l0, self.hip = rob.per_leg("leg_rest_length"), _hips(rob)
        phi = np.zeros((_NW, len(TANGENT_VARIABLES)))
        for row, col in ((1, 0), (2, 1), (3, 2), (5, 3)):
            phi[row, col] = 1.0
        phi[_GAMMA:, 4:] = np.eye(_NW - _GAMMA)
        self.phi = phi
        self.simultaneous = False

    @property
    def phi_u(self) -> np.ndarray:
        return self.phi[:6]

    @phi_u.setter
    def phi_u(self, value) -> None:
        self.phi[:6] = value

    def _leg(self, u, leg, anchor):
        """Hip lever r, its derivatives in theta and in the hip spacing, the leg vector d
        (hip - toe) and its length l."""
        sL, c, sn = self.hip[leg], math.cos(u[2]), math.sin(u[2])
        r, rp = np.array([sL * c, sL * sn]), np.array([-sL * sn, sL * c])
        rD = (0.5 if leg else -0.5) * np.array([c, sn])  # hips at -D/2 - e, D/2 - e
        d = np.array([u[0] + r[0] - anchor, u[1] + r[1]])
        return r, rp, rD, d, math.hypot(d[0], d[1])

    def jacobians(self, u, anchors):
        """d f_u / d(u (6), anchors (2), constants from the touchdown angles on (9)) of the
        torso equations, (6, 17)."""
        rob = self.rob
        m, inertia = rob.torso_mass, rob.torso_inertia
        J = np.zeros((6, _NW))
        J[0:3, 3:6] = np.eye(3)
        total = np.zeros(3)  # sum of Fx, Fy, torque
        for leg, ax in enumerate(anchors):
            if ax is None:
                continue
            r, rp, rD, d, ll = self._leg(u, leg, ax)
            k, l0 = self.k[leg], self.l0[leg]
            F = k * (l0 / ll - 1.0) * d  # axial spring force on the hip
            K = k * (l0 / ll - 1.0) * np.eye(2) - k * l0 / ll**3 * np.outer(d, d)  # dF/dd
            cols = {0: K[:, 0], 1: K[:, 1], 2: K @ rp, _ANCHOR + leg: -K[:, 0], _D: K @ rD,
                    _K + leg: self.n * (l0 / ll - 1.0) * d, _L0 + leg: k * d / ll}  # fmt: skip
            for j, dF in cols.items():
                dtau = r[0] * dF[1] - r[1] * dF[0]
                if j == 2:
                    dtau += rp[0] * F[1] - rp[1] * F[0]
                elif j == _D:
                    dtau += rD[0] * F[1] - rD[1] * F[0]
                J[3, j] += dF[0] / m
                J[4, j] += dF[1] / m
                J[5, j] += dtau / inertia
            total += (F[0], F[1], r[0] * F[1] - r[1] * F[0])
        J[3, _M], J[4, _M] = -total[0] / m**2, -total[1] / m**2
        J[5, _I] = -total[2] / inertia**2
        return J

    def variational(self, anchors):
        anchors = list(anchors)

        def rhs(u, phi_u):
            J = self.jacobians(u, anchors)
            return J[:, :6] @ phi_u + J[:, 6:] @ self.phi[6:]

        return rhs

    def _flow(self, u, anchors) -> np.ndarray:
        f = np.zeros(_NW)
        f[:6] = _passive_rhs(self.rob, list(anchors))(u)
        return f

    def jump(self, kind, leg, u, before, after) -> None:
        """Map ``phi`` across the ``kind`` event of ``leg`` at state ``u`` (anchors before
        and after the reset)."""
        n = np.zeros(_NW)
        DR = np.eye(_NW)
        c, sn = math.cos(u[2]), math.sin(u[2])
        half = 0.5 if leg else -0.5  # d(hip lever)/d(hip spacing)
        if kind == "touchdown":  # toe height y + sL sin(theta) - l0 cos(gamma) = 0
            sL, gam, l0 = self.hip[leg], self.gammas[leg], self.l0[leg]
            n[1], n[2], n[_GAMMA + leg] = 1.0, sL * c, l0 * math.sin(gam)
            n[_L0 + leg], n[_D] = -math.cos(gam), half * sn
            # reset: anchor = x + sL cos(theta) + l0 sin(gamma)
            row = _ANCHOR + leg
            DR[row] = 0.0
            DR[row, 0], DR[row, 2] = 1.0, -sL * sn
            DR[row, _GAMMA + leg], DR[row, _L0 + leg] = l0 * math.cos(gam), math.sin(gam)
            DR[row, _D] = half * c
        else:  # lift-off: leg length |d| - l0 = 0
            r, rp, rD, d, ll = self._leg(u, leg, before[leg])
            n[0], n[1], n[2] = d[0] / ll, d[1] / ll, float(d @ rp) / ll
            n[_ANCHOR + leg], n[_L0 + leg], n[_D] = -d[0] / ll, -1.0, float(d @ rD) / ll
        fm, fp = self._flow(u, before), self._flow(u, after)
        self.phi = saltation_matrix(DR, fm, fp, n) @ self.phi


@dataclass(frozen=True)
class ApexMapDerivative:
    """The apex return map and its exact first derivatives (variational equations and
    saltation matrices, :func:`passive_apex_map_derivative`).

    map : the :class:`ApexMap` evaluated with the sensitivities.
    state_jacobian : (4, 4) dz_next/dz (:data:`APEX_STATE_NAMES` both ways).
    angle_jacobian : (4, 2) dz_next/d(gamma_back, gamma_front) [per rad].
    period_gradient : (4,) d period/dz.
    period_angle_gradient : (2,) d period/d(gamma_back, gamma_front) [s/rad].
    parameter_jacobian : (4, 7) dz_next/d(robot constants), the constants of
        :data:`PARAMETER_NAMES` (SI).
    period_parameter_gradient : (7,) d period/d(robot constants).
    stride_gradient : (13,) d stride_length/d(z, touchdown angles, robot constants).
    simultaneous : two events happened at one instant (a pronk's touchdowns or lift-offs):
        the map is only piecewise smooth there and the derivatives are those of one side
        (the events taken back leg first when they were found together).
    """

    map: ApexMap
    state_jacobian: np.ndarray
    angle_jacobian: np.ndarray
    period_gradient: np.ndarray
    period_angle_gradient: np.ndarray
    parameter_jacobian: np.ndarray
    period_parameter_gradient: np.ndarray
    stride_gradient: np.ndarray
    simultaneous: bool


#: two events of the passive stride are simultaneous when the second one's function (toe
#: height or leg extension beyond l0) is within this distance [m] of zero at the first
SIMULTANEOUS_EVENT_TOL = 1e-12


def _integrate_passive_stride(z, gammas, rob, rtol, max_period, tangent=None):
    """From apex z, run the passive model until both legs have had a stance and both are in
    flight; return (state at the last lift-off, its time, order of first touchdowns).

    With a ``tangent`` (:class:`_PassiveTangent`) the sensitivities are integrated with the
    state and jump at each touchdown and lift-off (its ``phi`` is then the sensitivity of
    the state just after the last lift-off)."""
    l0, hip = rob.per_leg("leg_rest_length"), _hips(rob)
    u = np.array([0.0, z[0], z[1], z[2], 0.0, z[3]], dtype=float)
    t = 0.0
    anchors = [None, None]
    had_stance = [False, False]
    first_td = [math.inf, math.inf]
    armed = [True, True]  # a flight toe event counts only after the toe was seen above ground

    def toe_y(u, leg):
        sL = hip[leg]
        return u[1] + sL * math.sin(u[2]) - l0[leg] * math.cos(gammas[leg])

    def leg_length(u, leg):
        sL = hip[leg]
        return math.hypot(u[0] + sL * math.cos(u[2]) - anchors[leg], u[1] + sL * math.sin(u[2]))

    for leg in (0, 1):
        if toe_y(u, leg) < 0.0:
            raise MapError(f"the {LEG_NAMES[leg]} toe starts below the ground")
    for _ in range(12):
        if all(had_stance) and anchors == [None, None]:
            return u, t, tuple(LEG_NAMES[i] for i in np.argsort(first_td, kind="stable"))
        guards, meaning = [], []
        for leg in (0, 1):
            if anchors[leg] is None:
                guards.append(
                    Guard(lambda u_, leg=leg: toe_y(u_, leg), -1.0 if armed[leg] else 1.0)
                )
                meaning.append(("touchdown" if armed[leg] else "arm", leg))
            else:
                guards.append(Guard(lambda u_, leg=leg: leg_length(u_, leg) - l0[leg], 1.0))
                meaning.append(("liftoff", leg))
        guards.append(Guard(lambda u_: u_[1] - 0.5 * rob.torso_height))
        seg = flow_to_event(
            _passive_rhs(rob, list(anchors)),
            u,
            t0=t,
            t_max=max_period,
            guards=guards,
            variational=None if tangent is None else tangent.variational(anchors),
            sensitivity=None if tangent is None else tangent.phi_u,
            rtol=rtol,
            atol=rtol,
        )
        if seg.guard is None:
            raise MapError(f"no stride within {max_period} s")
        i = seg.guard
        if i == len(guards) - 1:
            raise MapError("the torso fell")
        u, t = seg.x, seg.t
        if tangent is not None:
            tangent.phi_u = seg.sensitivity
        kind, leg = meaning[i]
        if kind == "arm":
            armed[leg] = True
            continue
        # Simultaneous events (a pronk's two touchdowns and two lift-offs) are one
        # transition: the other leg's event counts as reached at this instant when its
        # function is within SIMULTANEOUS_EVENT_TOL of zero, whichever side rounding put it
        # on (otherwise a toe found 1e-17 m below the ground at the first touchdown would
        # never see its own crossing, and the result would depend on the machine).
        for lg in (leg, 1 - leg):
            if lg != leg:
                if anchors[lg] is None and kind == "touchdown" and armed[lg]:
                    if toe_y(u, lg) > SIMULTANEOUS_EVENT_TOL:
                        continue
                elif anchors[lg] is not None and kind == "liftoff":
                    if leg_length(u, lg) - l0[lg] < -SIMULTANEOUS_EVENT_TOL:
                        continue
                else:
                    continue
                if tangent is not None:
                    tangent.simultaneous = True
            before = list(anchors)
            if kind == "touchdown":
                sL = hip[lg]
                anchors[lg] = u[0] + sL * math.cos(u[2]) + l0[lg] * math.sin(gammas[lg])
                had_stance[lg] = True
                first_td[lg] = min(first_td[lg], t)
            else:
                anchors[lg] = None
                armed[lg] = toe_y(u, lg) > SIMULTANEOUS_EVENT_TOL
            if tangent is not None:
                tangent.jump(kind, lg, u, before, anchors)
    raise MapError("too many phases in one stride")


def passive_apex_map(
    z,
    touchdown_angles,
    *,
    robot: RobotParameters | None = None,
    rtol: float = ORBIT_TOLERANCE,
    max_period: float = 2.0,
) -> ApexMap:
    """Apex-to-apex return map of the passive model.

    Parameters
    ----------
    z : (4,) apex state (y [m], theta [rad], dx [m/s], dtheta [rad/s]); dy = 0 at an apex.
    touchdown_angles : (back, front) touchdown angles from the world vertical [rad]
        (toe ahead of the hip positive).
    robot : parameters; the legs are made massless and undamped (:func:`passive_robot`).
    rtol : integrator tolerance (rtol = atol; SciPy DOP853 with located events).
    max_period : longest stride looked for [s].

    The passive equations (docs/specification.md section 2: torso with up to two undamped massless springs) are
    integrated here with SciPy's DOP853, phase by phase with located touchdown (toe height
    0, descending) and lift-off (l = l0) events. They are the same model as
    ``simulate(..., model="passive")`` with ``passive_robot()`` and world-referenced
    touchdown angles (tests/analysis/test_orbits.py checks the maps agree), which is not
    used here because its massless touchdown occasionally undoes itself at rounding level
    and lets the toe through the ground (see :func:`_glitched`, docs/orbits.md).

    Raises
    ------
    MapError if the torso falls, a leg never touches down within ``max_period``, or the
    flight after both stances has no apex (the torso is already descending when the last
    leg lifts off).
    """
    rob = passive_robot(robot)
    z = np.asarray(z, dtype=float)
    gam = tuple(float(a) for a in touchdown_angles)
    u, t_lo, order = _integrate_passive_stride(z, gam, rob, rtol, max_period)
    z_next, period, _ = _to_apex(u, t_lo, rob.gravity)
    return ApexMap(z=z_next, period=period, order=order, stride_length=_stride(u, t_lo, period))


def _stride(u, t_lo, period) -> float:
    """x at the next apex: the lift-off's x and the ballistic flight's travel [m]."""
    return float(u[0] + u[3] * (period - t_lo))


def _to_apex(u, t_lo, g):
    """The next apex from the state u at the last lift-off (ballistic flight, closed form):
    (z_next, period, d z_next / d u (4, 6))."""
    dy = u[4]
    if dy < 0.0:
        raise MapError(
            f"no apex in the flight after both stances (the torso is descending "
            f"at the last lift-off, t = {t_lo:.4f} s)"
        )
    ta = dy / g
    z_next = np.array([u[1] + dy * dy / (2.0 * g), u[2] + u[5] * ta, u[3], u[5]])
    D = np.zeros((4, 6))
    D[0, 1], D[0, 4] = 1.0, dy / g
    D[1, 2], D[1, 4], D[1, 5] = 1.0, u[5] / g, ta
    D[2, 3] = D[3, 5] = 1.0
    return z_next, t_lo + ta, D


def passive_apex_map_derivative(
    z,
    touchdown_angles,
    *,
    robot: RobotParameters | None = None,
    rtol: float = ORBIT_TOLERANCE,
    max_period: float = 2.0,
) -> ApexMapDerivative:
    """The apex return map :func:`passive_apex_map` with its exact first derivatives with
    respect to the apex state and the touchdown angles.

    The variational equations of the torso (the Jacobian of the spring forces in closed
    form) are integrated with the state by the same DOP853 under the same error control;
    at each touchdown and lift-off the sensitivities jump by the event's saltation matrix
    (:func:`scoutsim.analysis.saltation.saltation_matrix`: the touchdown reset places the
    toe's anchor at ``x + sL cos(theta) + l0 sin(gamma)``, and the event-time correction
    uses the toe-height and leg-length guards); the ballistic flight to the next apex is
    differentiated in closed form. Exact up to the integration error (rtol), unlike
    differences of the map, whose error is set by their step. Parameters as
    :func:`passive_apex_map`.

    Raises
    ------
    MapError as :func:`passive_apex_map`;
    :class:`scoutsim.analysis.saltation.GrazingEventError` if a leg's event is tangential
    to the flow (no first derivative there).
    """
    rob = passive_robot(robot)
    z = np.asarray(z, dtype=float)
    gam = tuple(float(a) for a in touchdown_angles)
    tangent = _PassiveTangent(rob, gam)
    u, t_lo, order = _integrate_passive_stride(z, gam, rob, rtol, max_period, tangent)
    z_next, period, D = _to_apex(u, t_lo, rob.gravity)
    phi = tangent.phi_u
    dz = D @ phi
    # phi_u is the sensitivity at the nominal lift-off time, the event-time shift included
    # by the saltation matrix: the apex follows after dy / g from there
    dT = phi[4] / rob.gravity
    dX = phi[0] + (period - t_lo) * phi[3] + u[3] * phi[4] / rob.gravity
    return ApexMapDerivative(
        map=ApexMap(z=z_next, period=period, order=order, stride_length=_stride(u, t_lo, period)),
        state_jacobian=dz[:, :4],
        angle_jacobian=dz[:, 4:6],
        period_gradient=dT[:4],
        period_angle_gradient=dT[4:6],
        parameter_jacobian=dz[:, 6:],
        period_parameter_gradient=dT[6:],
        stride_gradient=dX,
        simultaneous=tangent.simultaneous,
    )
