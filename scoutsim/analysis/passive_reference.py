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

__all__ = [
    "passive_robot",
    "passive_apex_map",
    "ApexMap",
    "APEX_STATE_NAMES",
    "ORBIT_TOLERANCE",
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
    """

    z: np.ndarray
    period: float
    order: tuple


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

    def rhs(t, u):
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


#: two events of the passive stride are simultaneous when the second one's function (toe
#: height or leg extension beyond l0) is within this distance [m] of zero at the first
SIMULTANEOUS_EVENT_TOL = 1e-12


def _integrate_passive_stride(z, gammas, rob, rtol, max_period):
    """From apex z, run the passive model until both legs have had a stance and both are in
    flight; return (state at the last lift-off, its time, order of first touchdowns)."""
    from scipy.integrate import solve_ivp

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
        evs, meaning = [], []
        for leg in (0, 1):
            if anchors[leg] is None:

                def e(t_, u_, leg=leg):
                    return toe_y(u_, leg)

                e.direction = -1.0 if armed[leg] else 1.0
                meaning.append(("touchdown" if armed[leg] else "arm", leg))
            else:

                def e(t_, u_, leg=leg):
                    sL = hip[leg]
                    hx = u_[0] + sL * math.cos(u_[2])
                    hy = u_[1] + sL * math.sin(u_[2])
                    return math.hypot(hx - anchors[leg], hy) - l0[leg]

                e.direction = 1.0
                meaning.append(("liftoff", leg))
            e.terminal = True
            evs.append(e)

        def fall(t_, u_):
            return u_[1] - 0.5 * rob.torso_height

        fall.terminal = True
        evs.append(fall)
        sol = solve_ivp(
            _passive_rhs(rob, list(anchors)),
            (t, max_period),
            u,
            method="DOP853",
            rtol=rtol,
            atol=rtol,
            events=evs,
        )
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
                    if leg_length(u, lg) - l0[lg] < -SIMULTANEOUS_EVENT_TOL:
                        continue
                else:
                    continue
            if kind == "touchdown":
                sL = hip[lg]
                anchors[lg] = u[0] + sL * math.cos(u[2]) + l0[lg] * math.sin(gammas[lg])
                had_stance[lg] = True
                first_td[lg] = min(first_td[lg], t)
            else:
                anchors[lg] = None
                armed[lg] = toe_y(u, lg) > SIMULTANEOUS_EVENT_TOL
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
    g = rob.gravity
    dy = u[4]
    if dy < 0.0:
        raise MapError(
            f"no apex in the flight after both stances (the torso is descending "
            f"at the last lift-off, t = {t_lo:.4f} s)"
        )
    ta = dy / g
    z_next = np.array([u[1] + dy * dy / (2.0 * g), u[2] + u[5] * ta, u[3], u[5]])
    return ApexMap(z=z_next, period=t_lo + ta, order=order)
