"""Periodic orbits (Poincaré analysis) of bounding: return maps, fixed points, Floquet
multipliers and a one-parameter continuation (docs/orbits.md).

Passive conservative model (docs/specification.md section 2: massless, undamped legs placed in flight at
prescribed touchdown angles from the world vertical, ``model="passive"``):

* **Section**: the torso apex in double flight, ``dy = 0`` with ``y`` at a maximum. The
  section state is ``z = (y, theta, dx, dtheta)`` (x is irrelevant: the dynamics are
  invariant under horizontal translation; the legs are massless, so they carry no state).
* **Return map** :func:`passive_apex_map`: from an apex, simulate until both legs have had
  a stance and both are in flight again, then go to the next apex. In double flight the
  torso is ballistic (massless legs transmit no force), so the apex is reached exactly by
  propagating any double-flight sample analytically: ``t_a = t_k + dy_k / g``,
  ``y_a = y_k + dy_k^2 / (2 g)``, ``theta_a = theta_k + dtheta_k (t_a - t_k)``. The map is
  therefore as accurate as the integrator (rtol 1e-12 by default), not limited by the
  1 ms sample grid.
* **Fixed points** :func:`passive_bounding_orbit`: at given forward speed ``V``, apex height
  ``H`` and pitch rate ``W`` with the torso level at the apex, ``z* = (H, 0, V, W)``, solve
  ``P(z*; gamma_b, gamma_f) = z*`` for the back and front touchdown angles by
  Levenberg-Marquardt / Gauss-Newton on the four residuals (two unknowns; the system is
  consistent because such orbits are symmetric under the time-reversal-and-mirror symmetry
  of the conservative model, which leaves two independent conditions) with a central
  finite-difference Jacobian.
* **Floquet multipliers**: eigenvalues of the central-difference Jacobian ``dP/dz`` at the
  fixed point. Energy conservation makes one of them exactly 1.

Controlled robot (:func:`controlled_fixed_point`): the Table I law samples and holds at
1 kHz, so the closed loop is a sampled-data system. **Section**: the control sample at which
the controller detects back-leg lift-off; the section state is the complete hybrid state
there (:class:`~scoutsim.state.HybridState`: continuous state without x, pinned toes'
anchors relative to x, and the discrete plant/controller modes, which must recur). The
stride map :func:`controlled_stride_map` is smooth as long as every controller transition
stays on the same sample, so its fixed point is a periodic orbit lasting a whole number of
control periods; Newton's method (forward-difference Jacobian, least-squares steps because
pinned legs and stuck motor joints make some coordinates dependent) converges on it to a
residual ~1e-12, and the eigenvalues of the Jacobian are its Floquet multipliers. On the
Scout II defaults (Model II, default floor) the orbit lasts 234 ms with spectral radius
0.925 (a real multiplier -0.925: successive strides alternate about the orbit), and a long
simulation from the default start settles onto it at that rate (tests/analysis).
:func:`controlled_cycle` is the simulation-only estimate (mean of converged strides,
multipliers fitted to the transient), kept as a cross-check.

Units: SI, angles in rad (degrees only in the ``*_deg`` conveniences).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..model import layout as L
from ..parameters import DEFAULT_FRICTION_COEFFICIENT, RobotParameters
from ..integrator import IntegratorSettings
from ..simulation import simulate
from ..state import HybridState, InitialState

__all__ = ["MapError", "ApexMap", "PassiveOrbit", "ControlledCycle", "ControlledOrbit",
           "controlled_fixed_point", "controlled_stride_map", "section_state", "CONTROLLED_Z_NAMES", "passive_robot",
           "passive_apex_map", "fd_jacobian", "passive_bounding_orbit",
           "continue_passive_family", "floquet_multipliers", "controlled_cycle",
           "APEX_STATE_NAMES", "LIFTOFF_STATE_NAMES"]

#: Components of the apex section state z.
APEX_STATE_NAMES = ("y", "theta", "dx", "dtheta")
#: Integrator tolerance of the orbit computations (rtol = atol).
ORBIT_TOLERANCE = 1e-12


class MapError(RuntimeError):
    """The return map is not defined here (fall, no stance, no apex in double flight)."""


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
    """

    z: np.ndarray
    period: float
    order: tuple


def _glitched(events) -> bool:
    """True if a massless leg's touchdown in a ``simulate()`` run was undone at the same
    instant (zero-length stance) and not redone: the toe then passes through the ground.
    This rounding-level defect of the compiled massless touchdown (docs/orbits.md) is why
    :func:`passive_apex_map` integrates the passive equations itself."""
    for leg in (0, 1):
        e = events[events[:, 2] == leg]
        kinds = e[:, 1]
        for i in range(len(e) - 1):
            if (kinds[i] == L.EK_TOUCHDOWN and kinds[i + 1] == L.EK_LIFTOFF
                    and e[i + 1, 0] - e[i, 0] < 1e-12):
                if not (i + 2 < len(e) and kinds[i + 2] == L.EK_TOUCHDOWN
                        and e[i + 2, 0] - e[i + 1, 0] < 1e-9):
                    return True
    return False


def _passive_rhs(rob: RobotParameters, anchors):
    """Torso equations of the massless-leg passive model (docs/specification.md section 2): up to two undamped
    axial springs k_v = legs_per_virtual_leg * k between the hips and pinned toes."""
    m, I, g = rob.torso_mass, rob.torso_inertia, rob.gravity
    k = rob.legs_per_virtual_leg * rob.leg_stiffness
    l0, Lh = rob.leg_rest_length, rob.half_hip_spacing

    def rhs(t, u):
        x, y, th = u[0], u[1], u[2]
        c, sn = math.cos(th), math.sin(th)
        fx = fy = tq = 0.0
        for leg, ax in enumerate(anchors):
            if ax is None:
                continue
            sL = (2 * leg - 1) * Lh
            hx, hy = x + sL * c, y + sL * sn
            dx_, dy_ = hx - ax, hy
            ll = math.hypot(dx_, dy_)
            F = k * (l0 - ll)
            Fx, Fy = F * dx_ / ll, F * dy_ / ll
            fx += Fx
            fy += Fy
            tq += sL * c * Fy - sL * sn * Fx
        return [u[3], u[4], u[5], fx / m, fy / m - g, tq / I]
    return rhs


#: two events of the passive stride are simultaneous when the second one's function (toe
#: height or leg extension beyond l0) is within this distance [m] of zero at the first
SIMULTANEOUS_EVENT_TOL = 1e-12


def _integrate_passive_stride(z, gammas, rob, rtol, max_period):
    """From apex z, run the passive model until both legs have had a stance and both are in
    flight; return (state at the last lift-off, its time, order of first touchdowns)."""
    from scipy.integrate import solve_ivp
    l0, Lh = rob.leg_rest_length, rob.half_hip_spacing
    u = np.array([0.0, z[0], z[1], z[2], 0.0, z[3]], dtype=float)
    t = 0.0
    anchors = [None, None]
    had_stance = [False, False]
    first_td = [math.inf, math.inf]
    armed = [True, True]   # a flight toe event counts only after the toe was seen above ground

    def toe_y(u, leg):
        sL = (2 * leg - 1) * Lh
        return u[1] + sL * math.sin(u[2]) - l0 * math.cos(gammas[leg])

    def leg_length(u, leg):
        sL = (2 * leg - 1) * Lh
        return math.hypot(u[0] + sL * math.cos(u[2]) - anchors[leg], u[1] + sL * math.sin(u[2]))

    for leg in (0, 1):
        if toe_y(u, leg) < 0.0:
            raise MapError(f"the {L.LEG_NAMES[leg]} toe starts below the ground")
    for _ in range(12):
        if all(had_stance) and anchors == [None, None]:
            return u, t, tuple(L.LEG_NAMES[i] for i in np.argsort(first_td, kind="stable"))
        evs, meaning = [], []
        for leg in (0, 1):
            if anchors[leg] is None:
                def e(t_, u_, leg=leg):
                    return toe_y(u_, leg)
                e.direction = -1.0 if armed[leg] else 1.0
                meaning.append(("touchdown" if armed[leg] else "arm", leg))
            else:
                def e(t_, u_, leg=leg):
                    sL = (2 * leg - 1) * Lh
                    hx = u_[0] + sL * math.cos(u_[2])
                    hy = u_[1] + sL * math.sin(u_[2])
                    return math.hypot(hx - anchors[leg], hy) - l0
                e.direction = 1.0
                meaning.append(("liftoff", leg))
            e.terminal = True
            evs.append(e)

        def fall(t_, u_):
            return u_[1] - 0.5 * rob.torso_height
        fall.terminal = True
        evs.append(fall)
        sol = solve_ivp(_passive_rhs(rob, list(anchors)), (t, max_period), u,
                        method="DOP853", rtol=rtol, atol=rtol, events=evs)
        hit = [(te[0], i) for i, te in enumerate(sol.t_events) if len(te)]
        if not hit:
            raise MapError(f"no stride within {max_period} s")
        te, i = min(hit)
        if i == len(evs) - 1:
            raise MapError("the torso fell")
        u = np.array(sol.y_events[i][0])
        t = float(te)
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
                    if leg_length(u, lg) - l0 < -SIMULTANEOUS_EVENT_TOL:
                        continue
                else:
                    continue
            if kind == "touchdown":
                sL = (2 * lg - 1) * Lh
                anchors[lg] = u[0] + sL * math.cos(u[2]) + l0 * math.sin(gammas[lg])
                had_stance[lg] = True
                first_td[lg] = min(first_td[lg], t)
            else:
                anchors[lg] = None
                armed[lg] = toe_y(u, lg) > SIMULTANEOUS_EVENT_TOL
    raise MapError("too many phases in one stride")


def passive_apex_map(z, touchdown_angles, *, robot: RobotParameters | None = None,
                     rtol: float = ORBIT_TOLERANCE, max_period: float = 2.0) -> ApexMap:
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
    g = rob.gravity
    dy = u[4]
    if dy < 0.0:
        raise MapError(f"no apex in the flight after both stances (the torso is descending "
                       f"at the last lift-off, t = {t_lo:.4f} s)")
    ta = dy / g
    z_next = np.array([u[1] + dy * dy / (2.0 * g), u[2] + u[5] * ta, u[3], u[5]])
    return ApexMap(z=z_next, period=t_lo + ta, order=order)


def fd_jacobian(f, x, steps, *, f0=None) -> np.ndarray:
    """Central finite-difference Jacobian of ``f`` at ``x`` with per-component ``steps``.

    Central differences have truncation error O(h^2) and round-off error O(eps_f / h); for
    a map computed to eps_f ~ 1e-12 the steps 1e-5 (SI units of each component) balance
    the two at ~1e-9 (docs/orbits.md)."""
    x = np.asarray(x, dtype=float)
    steps = np.broadcast_to(np.asarray(steps, dtype=float), x.shape)
    cols = []
    for i in range(len(x)):
        e = np.zeros_like(x)
        e[i] = steps[i]
        cols.append((np.asarray(f(x + e)) - np.asarray(f(x - e))) / (2.0 * steps[i]))
    return np.column_stack(cols)


def floquet_multipliers(jacobian) -> np.ndarray:
    """Eigenvalues of the linearised return map, sorted by decreasing modulus."""
    ev = np.linalg.eigvals(np.asarray(jacobian, dtype=float))
    return ev[np.argsort(-np.abs(ev), kind="stable")]


@dataclass
class PassiveOrbit:
    """A periodic bounding orbit of the passive model on the apex section.

    Attributes
    ----------
    speed, apex_height, pitch_rate : the prescribed apex state (m/s, m, rad/s; theta = 0).
    touchdown_angles : (back, front) from the world vertical [rad].
    period : stride period, apex to apex [s].
    residual : max |P(z*) - z*| over the four apex components (SI).
    jacobian : (4, 4) dP/dz at the fixed point (central differences).
    multipliers : Floquet multipliers (eigenvalues of ``jacobian``), by decreasing modulus.
    order : touchdown order of the legs in the stride.
    iterations : map evaluations of the fixed-point search.
    rtol : integrator tolerance used.
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
        m = list(self.multipliers)
        m.pop(int(np.argmin(np.abs(np.array(m) - 1.0))))
        return bool(np.all(np.abs(m) <= 1.0 + 1e-6))

    def to_dict(self) -> dict:
        """JSON-safe summary (the keys of ``scoutsim orbit --passive --json`` and more)."""
        return {
            "touchdown_angle_back_deg": math.degrees(self.touchdown_angles[0]),
            "touchdown_angle_front_deg": math.degrees(self.touchdown_angles[1]),
            "period_s": self.period,
            "eigenvalues": [[float(m.real), float(m.imag)] for m in self.multipliers],
            "residual": self.residual,
        }


def _slip_guess(robot: RobotParameters, speed: float) -> float:
    """Touchdown angle of the symmetric pronk of a spring-mass with both legs (first guess)."""
    k = 2.0 * robot.legs_per_virtual_leg * robot.leg_stiffness
    t_stance = math.pi * math.sqrt(robot.torso_mass / k)
    return math.asin(min(0.9, speed * t_stance / (2.0 * robot.leg_rest_length)))


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


def passive_bounding_orbit(speed: float, apex_height: float, pitch_rate: float, *,
                           guess=None, robot: RobotParameters | None = None,
                           rtol: float = ORBIT_TOLERANCE, tol: float = 1e-11,
                           max_iter: int = 40, jacobian_step: float = 1e-5) -> PassiveOrbit:
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
    jacobian_step : central-difference step of dP/dz (SI units of each component).

    Raises
    ------
    MapError if no orbit is found (residual above 1e-9).
    """
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
        if gam is None or np.max(np.abs(r)) > 1e-9:
            fam = continue_passive_family(speed, apex_height,
                                          np.linspace(0.0, pitch_rate, 6), robot=rob,
                                          rtol=rtol, tol=tol, linearise=False)
            return _finish(fam[-1], rob, integ, jacobian_step)
    res = float(np.max(np.abs(r)))
    if not res <= 1e-9:
        raise MapError(f"no periodic orbit found at speed {speed} m/s, apex height "
                       f"{apex_height} m, pitch rate {math.degrees(pitch_rate):.3g} deg/s "
                       f"(residual {res:.3g} after {n} map evaluations)")
    orb = PassiveOrbit(speed=float(speed), apex_height=float(apex_height),
                       pitch_rate=float(pitch_rate), touchdown_angles=(float(gam[0]), float(gam[1])),
                       period=math.nan, residual=res, jacobian=np.full((4, 4), np.nan),
                       multipliers=np.full(4, np.nan + 0j), order=(), iterations=n, rtol=rtol)
    return _finish(orb, rob, integ, jacobian_step)


def _finish(orb: PassiveOrbit, rob, integ, jacobian_step) -> PassiveOrbit:
    """Fill in period, order, Jacobian and multipliers of a converged orbit."""
    m = passive_apex_map(orb.z, orb.touchdown_angles, robot=rob, rtol=integ.rtol)
    J = fd_jacobian(lambda x: passive_apex_map(x, orb.touchdown_angles, robot=rob, rtol=integ.rtol).z, orb.z, jacobian_step)
    orb.period = m.period
    orb.order = m.order
    orb.residual = float(np.max(np.abs(m.z - orb.z)))
    orb.jacobian = J
    orb.multipliers = floquet_multipliers(J)
    return orb


def continue_passive_family(speed: float, apex_height: float, pitch_rates, *,
                            robot: RobotParameters | None = None, rtol: float = ORBIT_TOLERANCE,
                            tol: float = 1e-11, linearise: bool = True,
                            jacobian_step: float = 1e-5) -> list[PassiveOrbit]:
    """Natural-parameter continuation of passive bounding orbits in the apex pitch rate.

    Each solve starts from a secant prediction through the two previous solutions (the
    first from the spring-mass pronk angle). ``pitch_rates`` [rad/s] should be ordered and
    closely spaced (a few tens of deg/s). Returns one :class:`PassiveOrbit` per pitch rate
    (with multipliers if ``linearise``)."""
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
            raise MapError(f"continuation lost the family at pitch rate "
                           f"{math.degrees(w):.3g} deg/s (residual {res:.3g})")
        sols.append((w, gam))
        orb = PassiveOrbit(speed=float(speed), apex_height=float(apex_height), pitch_rate=w,
                           touchdown_angles=(float(gam[0]), float(gam[1])), period=math.nan,
                           residual=res, jacobian=np.full((4, 4), np.nan),
                           multipliers=np.full(4, np.nan + 0j), order=(), iterations=n,
                           rtol=rtol)
        if linearise:
            orb = _finish(orb, rob, integ, jacobian_step)
        out.append(orb)
    return out


# -----------------------------------------------------------------------------------------
# controlled robot: converged cycle at back-leg lift-off
# -----------------------------------------------------------------------------------------
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
    from .gait import _hermite
    t = result.t
    te = result.event_times("liftoff", "back")
    te = te[(te > t[0]) & (te < t[-1])]
    S = result.state
    cols = []
    for i in (L.IY, L.ITH):
        cols.append(_hermite(t, S[:, i], S[:, L.NQ + i], te))
    for i in (L.IX, L.IY, L.ITH):
        cols.append(np.interp(te, t, S[:, L.NQ + i]))
    return te, np.column_stack(cols)


def controlled_cycle(*, model: str = "II", friction_coefficient: float = DEFAULT_FRICTION_COEFFICIENT,
                     duration: float = 12.0, robot=None, controller=None,
                     initial_state: InitialState | None = None,
                     integrator: IntegratorSettings | None = None,
                     n_tail: int = 10) -> ControlledCycle:
    """Converged bounding cycle of the controlled robot (default Model II on the default floor).

    Simulation-only estimate (no restarts; :func:`controlled_fixed_point` is the Newton
    solution on the sampled stride map). The cycle is found by converging simulation (mean of the last ``n_tail`` back-leg lift-off
    states) and its multipliers are estimated by finite differences along the transient: a
    least-squares fit ``dz_{k+1} = A dz_k`` of the deviations from the converged state of
    the strides whose deviation is above 20x the converged jitter.
    """
    r = simulate(robot, controller, initial_state, duration, model=model,
                 integrator=integrator, friction_coefficient=friction_coefficient)
    te, Z = _liftoff_states(r)
    n = len(te)
    if n < n_tail + 3:
        raise MapError(f"only {n} back-leg lift-offs in {duration} s (outcome {r.outcome}): "
                       "no steady cycle")
    tail = Z[-n_tail:]
    z = tail.mean(axis=0)
    spread = np.max(np.abs(tail - z), axis=0)
    period = float(np.mean(np.diff(te[-n_tail - 1:])))
    scale = np.maximum(np.abs(Z).max(axis=0), 1e-3)
    D = (Z - z) / scale
    noise = max(20.0 * float(np.max(spread / scale)), 1e-9)
    use = np.flatnonzero(np.max(np.abs(D[:-1]), axis=1) > noise)
    if len(use) >= Z.shape[1] + 2:
        X, Y = D[use], D[use + 1]
        A, *_ = np.linalg.lstsq(X, Y, rcond=None)
        mult = floquet_multipliers(A.T)
        method = (f"least-squares linear stride map fitted to {len(use)} transient strides "
                  "(finite differences along the converging transient; see "
                  "controlled_fixed_point for the Newton solution)")
    else:
        mult = np.full(Z.shape[1], np.nan + 0j)
        method = "too few transient strides above the jitter to fit the stride map"
    return ControlledCycle(z=z, period=period, spread=spread, multipliers=mult,
                           n_strides=n, n_tail=n_tail, outcome=r.outcome, method=method)


# -----------------------------------------------------------------------------------------
# controlled robot: fixed point of the sampled stride map (Newton)
# -----------------------------------------------------------------------------------------
#: names of the section coordinates z of the controlled stride map (SI)
CONTROLLED_Z_NAMES = (
    "y", "theta", "phi_back", "phi_front", "alpha_back", "alpha_front",
    "dx", "dy", "dtheta", "dphi_back", "dphi_front", "dalpha_back", "dalpha_front",
    "leg_length_back", "leg_length_front", "anchor_back_rel", "anchor_front_rel")


def _z_of(hs) -> np.ndarray:
    """Section coordinates of a HybridState: the state without x, and the pinned toes'
    anchors relative to x (0 for a leg not pinned)."""
    s = np.asarray(hs.state)
    rel = [(hs.toe_anchors[leg] - s[L.IX]) if hs.contact_modes[leg] in (L.STICK, L.STRUT)
           else 0.0 for leg in range(2)]
    return np.concatenate([s[1:], rel])


def _hs_of(z, discrete):
    s = np.concatenate([[0.0], z[:L.NS - 1]])
    return HybridState(state=s, toe_anchors=(float(z[-2]), float(z[-1])), **discrete)


def _discrete(hs) -> dict:
    return dict(leg_states=hs.leg_states, contact_modes=hs.contact_modes,
                motor_modes=hs.motor_modes, slide_directions=hs.slide_directions)


def section_state(result):
    """The HybridState at the second-to-last sample at which the controller of ``result``
    (a :class:`~scoutsim.SimulationResult`) detected back-leg lift-off: a Newton start for
    :func:`controlled_fixed_point`. MapError if the run has fewer than 3 such samples or
    did not complete."""
    dt = float(result.provenance["control_period_s"])
    te = result.event_times("controller_liftoff", "back")
    if result.outcome != "completed" or len(te) < 3:
        raise MapError(f"no steady bounding to start from (outcome {result.outcome}, "
                       f"{len(te)} back-leg lift-offs in {result.t[-1]:.3g} s)")
    return result.hybrid_state(int(round(te[-2] / dt)))


def controlled_stride_map(hs, *, model: str = "II", friction_coefficient: float = DEFAULT_FRICTION_COEFFICIENT,
                          robot=None, controller=None,
                          integrator: IntegratorSettings | None = None,
                          max_period: float = 0.6):
    """One stride of the sampled closed loop from the HybridState ``hs`` taken at a control
    sample: run until the controller next detects a back-leg lift-off (a sample, so the
    stride lasts a whole number of control periods) and return
    ``(z_start, z_end, hs_end, period_s)`` with z the section coordinates
    (:data:`CONTROLLED_Z_NAMES`); z_start is ``hs`` after the projection of its dependent
    coordinates. MapError if the robot falls or no lift-off is detected."""
    r = simulate(robot, controller, hs, max_period, model=model, integrator=integrator,
                 friction_coefficient=friction_coefficient)
    dt = float(r.provenance["control_period_s"])
    te = r.event_times("controller_liftoff", "back")
    te = te[te > 0.5 * dt]
    if len(te) == 0:
        raise MapError(f"no back-leg lift-off detected within {max_period} s (outcome "
                       f"{r.outcome} at t = {r.t_end:.3f} s)")
    k1 = int(round(te[0] / dt))
    if k1 >= len(r.t):
        raise MapError(f"the run ended (outcome {r.outcome}) at the lift-off sample")
    h1 = r.hybrid_state(k1)
    return _z_of(r.hybrid_state(0)), _z_of(h1), h1, float(r.t[k1])


@dataclass
class ControlledOrbit:
    """Fixed point of the controlled stride map (section: the control sample at which the
    controller detects back-leg lift-off)."""

    z: np.ndarray                 # section coordinates (CONTROLLED_Z_NAMES), SI
    state: object                 # the HybridState at the section
    period: float                 # [s], a whole number of control periods
    residual: float               # max |P(z) - z| (SI units of each coordinate)
    multipliers: np.ndarray       # eigenvalues of dP/dz (complex)
    jacobian: np.ndarray = field(repr=False)
    iterations: int = 0
    history: list = field(default_factory=list)   # residual per Newton iteration
    #: leg angle from the world vertical (theta + phi) at each leg's touchdown on the orbit
    #: [rad] (back, front; linear interpolation between the 1 kHz samples)
    touchdown_angles_world: tuple = (math.nan, math.nan)
    mean_speed: float = math.nan    # forward travel over the period / period [m/s]

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


def controlled_fixed_point(start=None, *, model: str = "II",
                           friction_coefficient: float = DEFAULT_FRICTION_COEFFICIENT, robot=None, controller=None,
                           integrator: IntegratorSettings | None = None,
                           settle_duration: float = 12.0, tol: float = 1e-10,
                           max_iter: int = 10, jacobian_step: float = 1e-6,
                           progress=None) -> ControlledOrbit:
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
    kw = dict(model=model, friction_coefficient=friction_coefficient, robot=robot,
              controller=controller, integrator=integ)
    say = progress or (lambda message: None)
    if start is None:
        say(f"settling: {settle_duration:g} s of model {model} to a Newton start")
        start = simulate(robot, controller, None, settle_duration, model=model,
                         friction_coefficient=friction_coefficient)
    if not isinstance(start, HybridState):
        start = section_state(start)
    disc = _discrete(start)
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
        if _discrete(h1) != disc:
            raise MapError(f"the discrete state at the section changed ({disc} -> "
                           f"{_discrete(h1)}): not a period-1 orbit of this section")
        if res < tol or it == max_iter:
            break
        J = np.empty((z.size, z.size))
        for j in range(z.size):
            e = jacobian_step * max(1.0, abs(z[j]))
            zp = z.copy()
            zp[j] += e
            _, zj1, _, Tj = controlled_stride_map(_hs_of(zp, disc), **kw)
            if Tj != T:
                raise MapError(f"the stride length changed from {T} s to {Tj} s under a "
                               f"perturbation of {CONTROLLED_Z_NAMES[j]}: the start lies on "
                               "a sample-phase boundary")
            J[:, j] = (zj1 - z1) / e
        dz = np.linalg.lstsq(J - np.eye(z.size), -F, rcond=1e-12)[0]
        z0, z1, h1, T = controlled_stride_map(_hs_of(z + dz, disc), **kw)
        z = z0
    if hist[-1] >= tol:
        raise MapError(f"Newton did not converge: residual {hist[-1]:.2e} after {it} "
                       f"iterations (history {['%.1e' % v for v in hist]})")
    if J is None or it > 0:
        J = np.empty((z.size, z.size))
        for j in range(z.size):
            e = jacobian_step * max(1.0, abs(z[j]))
            zp = z.copy()
            zp[j] += e
            J[:, j] = (controlled_stride_map(_hs_of(zp, disc), **kw)[1] - z1) / e
    hs = _hs_of(z, disc)
    r = simulate(robot, controller, hs, T, model=model, integrator=integ,
                 friction_coefficient=friction_coefficient)
    td = []
    for leg in ("back", "front"):
        te = r.event_times("touchdown", leg)
        if len(te) == 0:
            td.append(math.nan)
            continue
        g = r.pitch + r.leg_angle(leg)
        td.append(float(np.interp(te[0], r.t, g)))
    return ControlledOrbit(z=z, state=hs, period=T, residual=hist[-1],
                           multipliers=floquet_multipliers(J), jacobian=J,
                           iterations=len(hist) - 1, history=hist,
                           touchdown_angles_world=tuple(td),
                           mean_speed=float((r.x[-1] - r.x[0]) / (r.t[-1] - r.t[0])))
