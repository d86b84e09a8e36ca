"""Touchdown impacts of real runs against laws of impulsive rigid-body mechanics.

Each touchdown of a short bounding run is read from its event record (``layout.EK_TOUCHDOWN``:
v1 normal impulse, v2 tangential impulse, v3 kinetic energy lost) and from the exact states
just before and just after it (``SimulationResult.event_states``). The checks use
kinematics and mass properties written here from docs/specification.md sections 1, 2 and 5
and the fields of ``RobotParameters``, not the package's model functions:

* a no-slip touchdown pins the toe: its velocity across the leg axis is zero after the
  impact; along the axis the massless toe slides into the spring, so the impulse has no
  component along the leg and the leg keeps a length rate (docs/specification.md section 3,
  "Touchdown impact");
* positions do not jump; the angular momentum of the whole robot (torso, both massive legs,
  the Model II gear trains) about the contact point is conserved through a single-toe
  impulse, and the linear momentum changes by exactly the recorded impulse; with the other
  toe pinned, the rest of the momentum change is an impulse across that leg whose moment
  about the landing toe is the angular momentum change;
* the kinetic energy lost equals the recorded loss and is not negative;
* Model II: the belt acts as rigid through the impact, the gear rate equals the leg rate
  after it;
* an impact solved here from scratch (mass matrix from the body velocities, the contact
  rows of section 3) gives the recorded post-impact velocities;
* on a Coulomb floor the toe is pinned only if that pinning impulse lies inside the
  friction cone; otherwise the toe lands sliding with no impulse (a ``slide_start`` record
  with cause ``SLIDE_CAUSE_NO_PIN_IMPULSE``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

import scoutsim
from scoutsim._core.model import layout as L
from scoutsim.parameters import DEFAULT_FRICTION_COEFFICIENT

#: the robot the runs use; every mass property below is read from its fields
ROBOT = scoutsim.RobotParameters()

DURATION = 3.0  # [s] of bounding from the default start: about 20 touchdowns
NO_SLIP = math.inf
#: a Coulomb floor stiff enough to hold the front toe's landing impulse (|P_t| / P_n about
#: 2.9) but not the back toe's (negative normal impulse): both branches of the landing rule
HIGH_MU = 3.0

RUNS = {
    ("II", NO_SLIP): None,
    ("I", NO_SLIP): None,
    ("ideal", NO_SLIP): None,
    ("II", DEFAULT_FRICTION_COEFFICIENT): None,
    ("I", DEFAULT_FRICTION_COEFFICIENT): None,
    ("II", HIGH_MU): None,
}
NO_SLIP_MODELS = ("II", "I", "ideal")
COULOMB_RUNS = [k for k in RUNS if k[1] < math.inf]

#: velocity residuals [m/s, rad/s] and relative residuals of the laws. The impact is an
#: exact linear solve, but it acts with the toe set exactly onto the ground, while the
#: state before it is the located event (within 1e-9 s, section 3: toes at about 2 m/s,
#: lever arms of 0.3 m give relative effects up to about 1e-8). Measured: 2e-10 at worst.
VEL_TOL = 1e-8
REL_TOL = 1e-8

_CONTROLLER_KINDS = (L.EK_CTRL_TOUCHDOWN, L.EK_CTRL_LIFTOFF, L.EK_CTRL_SWEEP)


# --- the robot's mechanics, written from docs/specification.md sections 1, 2, 5 ----------


def _cross(a, b):
    return a[0] * b[1] - a[1] * b[0]


def _leg(s, leg, rp=None):
    """Hip, unit vectors u (hip -> toe) and n (across), leg length, absolute leg rate, hip
    velocity and toe of ``leg`` (0 back, 1 front) in state ``s`` (section 1)."""
    rp = rp or ROBOT
    x, y, th = s[0], s[1], s[2]
    dx, dy, dth = s[7], s[8], s[9]
    side = -1.0 if leg == 0 else 1.0  # back hip behind the COM, front hip ahead
    half = 0.5 * rp.hip_spacing
    g = th + s[3 + leg]
    dg = dth + s[10 + leg]
    hip = np.array([x + side * half * math.cos(th), y + side * half * math.sin(th)])
    vhip = np.array([dx - side * half * math.sin(th) * dth, dy + side * half * math.cos(th) * dth])
    u = np.array([math.sin(g), -math.cos(g)])
    n = np.array([math.cos(g), math.sin(g)])
    l = s[14 + leg]
    return {"hip": hip, "vhip": vhip, "u": u, "n": n, "l": l, "dg": dg, "toe": hip + l * u}


def _toe_velocity_across(s, leg):
    """Velocity [m/s] across the leg axis of the leg-body point at the toe (the massless toe
    moves along the axis on its slider; across it, it moves with the leg)."""
    k = _leg(s, leg)
    return float(k["n"] @ k["vhip"] + k["l"] * k["dg"])


def _leg_length_rate_pinned(s, leg):
    """dl/dt [m/s] of a leg whose toe stands still: minus the hip velocity along the leg."""
    k = _leg(s, leg)
    return float(-(k["u"] @ k["vhip"]))


def _bodies(s, model, rp=None):
    """(mass, inertia, COM position, COM velocity, angular velocity) of every body: torso,
    virtual legs (COM on the leg axis at leg_com_distance from the hip), and for Model II
    each leg's two gear rotors (driven gear at dtheta + dalpha, drive gear at
    dtheta + N dalpha; inertia only, no mass of their own, section 5)."""
    rp = rp or ROBOT
    npl = rp.legs_per_virtual_leg
    out = [(rp.torso_mass, rp.torso_inertia, np.array(s[0:2]), np.array(s[7:9]), s[9])]
    for leg in (0, 1):
        k = _leg(s, leg, rp)
        d = rp.leg_com_distance
        out.append(
            (
                npl * rp.leg_mass,
                npl * rp.leg_inertia,
                k["hip"] + d * k["u"],
                k["vhip"] + d * k["dg"] * k["n"],
                k["dg"],
            )
        )
        if model == "II":
            dal = s[12 + leg]
            out.append((0.0, npl * rp.driven_gear_inertia, None, None, s[9] + dal))
            out.append((0.0, npl * rp.drive_gear_inertia, None, None, s[9] + rp.gear_ratio * dal))
    return out


def _linear_momentum(s, model):
    return sum(m * v for m, _, r, v, _ in _bodies(s, model) if r is not None)


def _angular_momentum(s, model, c):
    """Angular momentum [kg m^2/s] of the whole robot about the fixed point c."""
    h = 0.0
    for m, inertia, r, v, w in _bodies(s, model):
        h += inertia * w
        if r is not None:
            h += m * _cross(r - c, v)
    return h


def _kinetic_energy(s, model):
    e = 0.0
    for m, inertia, r, v, w in _bodies(s, model):
        e += 0.5 * inertia * w * w
        if r is not None:
            e += 0.5 * m * float(v @ v)
    return e


def _with_rates(s, dq):
    s2 = np.array(s, dtype=float)
    s2[7:14] = 0.0
    s2[7 : 7 + len(dq)] = dq
    return s2


def _solve_impact(s, model, pinned, struts=()):
    """Rigid-body impact solved from scratch at the positions of ``s``: the post-impact
    rates closest to the pre-impact ones in the kinetic-energy metric with every toe in
    ``pinned`` stopped across its leg, every leg in ``struts`` also along it, and in Model II
    each gear rate equal to its leg rate. Returns (rates after, {leg: Cartesian impulse of
    the ground on that toe [N s]}). The mass matrix comes from the body velocities of
    :func:`_bodies`, which are linear in the rates."""
    nq = 7 if model == "II" else 5
    units = [_with_rates(s, np.eye(nq)[j]) for j in range(nq)]
    per_unit = [_bodies(u, model) for u in units]
    mass = np.zeros((nq, nq))
    for b in range(len(per_unit[0])):
        m, inertia = per_unit[0][b][0], per_unit[0][b][1]
        jw = np.array([per_unit[j][b][4] for j in range(nq)])
        mass += inertia * np.outer(jw, jw)
        if per_unit[0][b][2] is not None:
            jv = np.array([per_unit[j][b][3] for j in range(nq)]).T  # (2, nq)
            mass += m * jv.T @ jv
    rows, owners = [], []
    for leg in pinned:
        rows.append([_toe_velocity_across(u, leg) for u in units])
        owners.append((leg, "across"))
        if leg in struts:
            rows.append([-_leg_length_rate_pinned(u, leg) for u in units])
            owners.append((leg, "along"))
    if model == "II":
        for leg in (0, 1):
            row = np.zeros(nq)
            row[5 + leg] = 1.0
            row[3 + leg] = -1.0
            rows.append(row)
            owners.append((None, "belt"))
    a = np.array(rows, dtype=float)
    nr = len(rows)
    kkt = np.zeros((nq + nr, nq + nr))
    kkt[:nq, :nq] = mass
    kkt[:nq, nq:] = a.T
    kkt[nq:, :nq] = a
    dq0 = np.asarray(s[7 : 7 + nq], dtype=float)
    rhs = np.concatenate([mass @ dq0, np.zeros(nr)])
    sol = np.linalg.solve(kkt, rhs)
    dq1, mult = sol[:nq], -sol[nq:]
    impulses = {}
    for (leg, kind), lam in zip(owners, mult):
        if leg is None:
            continue
        k = _leg(s, leg)
        direction = k["n"] if kind == "across" else k["u"]
        impulses[leg] = impulses.get(leg, np.zeros(2)) + lam * direction
    return dq1, impulses


# --- the touchdowns of a run ------------------------------------------------------------


@dataclass
class Landing:
    """One touchdown record and the transition it belongs to."""

    t: float
    leg: int
    normal: float  # recorded v1 [N s]
    tangential: float  # recorded v2 [N s]
    loss: float  # recorded v3 [J]
    before: np.ndarray
    after: np.ndarray
    modes_before: dict  # contact mode of each leg just before the transition
    kinds: tuple  # (kind, leg, v3) of every record of the transition
    n_touchdowns: int  # touchdowns in the same transition (2: simultaneous)

    @property
    def other(self):
        return 1 - self.leg

    @property
    def recorded_impulse(self):
        return np.array([self.tangential, self.normal])

    def slid_without_pin_impulse(self):
        return any(
            k == L.EK_SLIDE_START and leg == self.leg and int(v3) == L.SLIDE_CAUSE_NO_PIN_IMPULSE
            for k, leg, v3 in self.kinds
        )


def _landings(result):
    """Every touchdown of ``result`` with its transition's states and the contact modes of
    both legs before it (followed from the plant's event records)."""
    ev, es = result.events, result.event_states
    plant = [i for i in range(len(ev)) if int(ev[i, L.EVR_KIND]) not in _CONTROLLER_KINDS]
    groups = []
    for i in plant:
        if (
            groups
            and ev[i, L.EVR_T] == ev[groups[-1][0], L.EVR_T]
            and np.array_equal(es[i, L.EVS_BEFORE], es[groups[-1][0], L.EVS_BEFORE])
        ):
            groups[-1].append(i)
        else:
            groups.append([i])
    mode = {0: "flight", 1: "flight"}
    out = []
    for g in groups:
        kinds = tuple((int(ev[i, L.EVR_KIND]), int(ev[i, L.EVR_LEG]), ev[i, L.EVR_V3]) for i in g)
        tds = [i for i in g if int(ev[i, L.EVR_KIND]) == L.EK_TOUCHDOWN]
        for i in tds:
            out.append(
                Landing(
                    t=float(ev[i, L.EVR_T]),
                    leg=int(ev[i, L.EVR_LEG]),
                    normal=float(ev[i, L.EVR_V1]),
                    tangential=float(ev[i, L.EVR_V2]),
                    loss=float(ev[i, L.EVR_V3]),
                    before=es[i, L.EVS_BEFORE].copy(),
                    after=es[i, L.EVS_AFTER].copy(),
                    modes_before=dict(mode),
                    kinds=kinds,
                    n_touchdowns=len(tds),
                )
            )
        for k, leg, _ in kinds:
            if k in (L.EK_TOUCHDOWN, L.EK_STICK, L.EK_STRUT_END):
                mode[leg] = "stick"
            elif k == L.EK_SLIDE_START:
                mode[leg] = "slide"
            elif k == L.EK_LIFTOFF:
                mode[leg] = "flight"
            elif k == L.EK_STRUT_START:
                mode[leg] = "strut"
    return out


def _single_toe(landings):
    """Landings where the landing toe is the only one that can take an impulse (the other
    leg in flight, or sliding: its massless toe on a compliant leg carries none)."""
    return [
        d
        for d in landings
        if d.n_touchdowns == 1 and d.modes_before[d.other] in ("flight", "slide")
    ]


def _pinned_landings(landings):
    """Landings whose toe the floor pinned (no slide at touchdown)."""
    return [d for d in landings if not d.slid_without_pin_impulse()]


def _is_strut_landing(d, model):
    """The spec's rule (section 3): a leg landing at its stop while the hip, after the
    across-only impact, moves away from the toe lands as a rigid strut."""
    if d.before[14 + d.leg] < ROBOT.leg_rest_length * (1.0 - 1e-12):
        return False
    pinned = [d.leg] + [k for k in (0, 1) if k != d.leg and d.modes_before[k] in ("stick", "strut")]
    dq1, _ = _solve_impact(d.before, model, pinned)
    return _leg_length_rate_pinned(_with_rates(d.before, dq1), d.leg) > 1e-6


@pytest.fixture(scope="module")
def runs():
    out = {}
    for model, mu in RUNS:
        r = scoutsim.simulate(ROBOT, duration=DURATION, model=model, friction_coefficient=mu)
        assert r.outcome == "completed"
        out[(model, mu)] = _landings(r)
    return out


# --- no-slip floor: the pin -------------------------------------------------------------


@pytest.mark.parametrize("model", NO_SLIP_MODELS)
def test_no_slip_touchdown_stops_toe_across_leg_and_positions_do_not_jump(runs, model):
    """Pinned toe (section 3): after a no-slip touchdown the toe's velocity across the leg
    axis is zero, where before it the toe was at the ground moving down with a real
    velocity across the leg; an impact changes velocities only, not positions (to the
    residual of the event location, 1e-9 m)."""
    landings = runs[(model, NO_SLIP)]
    assert len(landings) >= 15
    for d in landings:
        k = _leg(d.before, d.leg)
        # the massless flight toe obeys c dl/dt = k (l0 - l) (section 2)
        dl = ROBOT.leg_stiffness / ROBOT.leg_damping * (ROBOT.leg_rest_length - k["l"])
        toe_vy = k["vhip"][1] + dl * k["u"][1] + k["l"] * k["dg"] * k["n"][1]
        assert abs(k["toe"][1]) < 1e-9
        assert toe_vy < 0.0
        assert abs(_toe_velocity_across(d.before, d.leg)) > 0.1
        assert abs(_toe_velocity_across(d.after, d.leg)) < VEL_TOL
        # the torso does not move; the landing leg's angle and length change only by the
        # event location's residual, as the toe is set exactly onto the ground
        assert np.allclose(d.after[0:3], d.before[0:3], rtol=0.0, atol=1e-12)
        assert np.allclose(d.after[3:7], d.before[3:7], rtol=0.0, atol=1e-9)
        assert np.allclose(d.after[14:16], d.before[14:16], rtol=0.0, atol=1e-9)
        assert abs(_leg(d.after, d.leg)["toe"][1]) < 1e-12


@pytest.mark.parametrize("model", NO_SLIP_MODELS)
def test_no_slip_impulse_acts_across_leg_only_and_toe_slides_into_spring(runs, model):
    """Along the leg the massless toe slides into the spring (section 3): the ground's
    impulse, measured as the change of the robot's linear momentum, has no component along
    the leg axis, and the leg length keeps changing after the impact (the toe's motion
    along the axis is not stopped). A landing at the stop with the hip moving away (a strut
    landing) would be the exception; these runs have none."""
    landings = _single_toe(runs[(model, NO_SLIP)])
    assert len(landings) >= 10
    rates = []
    for d in landings:
        assert not _is_strut_landing(d, model)
        dp = _linear_momentum(d.after, model) - _linear_momentum(d.before, model)
        u = _leg(d.before, d.leg)["u"]
        assert abs(dp @ u) <= REL_TOL * np.linalg.norm(dp)
        rates.append(_leg_length_rate_pinned(d.after, d.leg))
    # every landing compresses the leg (the hip moves on towards the toe), at m/s rates
    assert max(rates) < 0.0
    assert min(abs(r) for r in rates) > 0.05


# --- momentum and energy ----------------------------------------------------------------


@pytest.mark.parametrize("model", NO_SLIP_MODELS)
def test_angular_momentum_about_contact_point_is_conserved(runs, model):
    """A single-toe impulse acts at the contact point, so the angular momentum of the whole
    robot about that point (torso + both legs + Model II gear trains: sum of m r x v +
    I omega) is the same just before and just after the impact."""
    landings = _single_toe(runs[(model, NO_SLIP)])
    assert len(landings) >= 10
    for d in landings:
        c = _leg(d.before, d.leg)["toe"]
        h0 = _angular_momentum(d.before, model, c)
        h1 = _angular_momentum(d.after, model, c)
        assert abs(h1 - h0) <= REL_TOL * abs(h0)


@pytest.mark.parametrize("model", NO_SLIP_MODELS)
def test_recorded_impulse_is_change_of_linear_momentum(runs, model):
    """Only the ground's impulse acts on the robot over the impact (gravity and every other
    finite force give none), so the change of total linear momentum equals the recorded
    impulse: v2 horizontally (tangential), v1 vertically (normal)."""
    landings = _single_toe(runs[(model, NO_SLIP)])
    assert len(landings) >= 10
    for d in landings:
        dp = _linear_momentum(d.after, model) - _linear_momentum(d.before, model)
        assert np.linalg.norm(dp - d.recorded_impulse) <= REL_TOL * np.linalg.norm(dp)
        assert np.linalg.norm(dp) > 0.1


def test_touchdown_with_other_toe_pinned_gives_it_an_impulse_across_its_leg(runs):
    """With the other toe pinned at the touchdown, both toes take an impulse: the part of
    the momentum change that the landing toe's recorded impulse does not explain acts at
    the other toe, across its leg (its massless toe carries nothing along the axis), and
    its moment about the landing toe is the change of angular momentum about that point.
    The other toe stays stopped across its leg."""
    model = "II"
    landings = [
        d
        for d in runs[(model, NO_SLIP)]
        if d.n_touchdowns == 1 and d.modes_before[d.other] == "stick"
    ]
    assert len(landings) >= 3
    for d in landings:
        c1 = _leg(d.before, d.leg)["toe"]
        k2 = _leg(d.before, d.other)
        dp = _linear_momentum(d.after, model) - _linear_momentum(d.before, model)
        p2 = dp - d.recorded_impulse
        assert np.linalg.norm(p2) > 1e-3 * np.linalg.norm(dp)
        assert abs(p2 @ k2["u"]) <= REL_TOL * np.linalg.norm(dp)
        dh = _angular_momentum(d.after, model, c1) - _angular_momentum(d.before, model, c1)
        assert abs(dh - _cross(k2["toe"] - c1, p2)) <= REL_TOL * abs(
            _angular_momentum(d.before, model, c1)
        )
        assert abs(_toe_velocity_across(d.after, d.other)) < VEL_TOL


@pytest.mark.parametrize("model", NO_SLIP_MODELS)
def test_kinetic_energy_lost_equals_recorded_loss_and_is_not_negative(runs, model):
    """The perfectly inelastic impact dissipates kinetic energy: the drop of the kinetic
    energy (computed here from the bodies) equals the recorded loss v3, which is positive."""
    landings = runs[(model, NO_SLIP)]
    for d in landings:
        lost = _kinetic_energy(d.before, model) - _kinetic_energy(d.after, model)
        assert lost == pytest.approx(d.loss, rel=REL_TOL, abs=1e-12)
        assert d.loss > 0.0


# --- Model II: the rigid belt -----------------------------------------------------------


def test_model_ii_belt_is_rigid_through_the_impact(runs):
    """Section 3: the belt damper is so stiff against the gear-train inertia that the gear
    train moves with the leg through the impact: after every touchdown impact each gear
    rate equals its leg rate, where before it the two differed."""
    landings = runs[("II", NO_SLIP)] + _pinned_landings(runs[("II", HIGH_MU)])
    assert len(landings) >= 20
    slip_before = []
    for d in landings:
        for leg in (0, 1):
            assert abs(d.after[12 + leg] - d.after[10 + leg]) < VEL_TOL
            slip_before.append(abs(d.before[12 + leg] - d.before[10 + leg]))
    assert max(slip_before) > 0.01


# --- the whole impact, solved independently ---------------------------------------------


@pytest.mark.parametrize("model", NO_SLIP_MODELS)
def test_independent_impact_solve_gives_recorded_velocities_and_impulse(runs, model):
    """The post-impact state is the rigid-body impact of section 3: solved here from a mass
    matrix assembled from the body velocities, with the pinned toes' across-leg rows (the
    landing toe and a toe already pinned) and the Model II rigid belts, it gives the
    recorded post-impact velocities and the recorded impulse of the landing toe."""
    nq = 7 if model == "II" else 5
    for d in runs[(model, NO_SLIP)]:
        pinned = [
            k
            for k in (0, 1)
            if k == d.leg or d.modes_before[k] in ("stick", "strut") or (d.n_touchdowns == 2)
        ]
        struts = [k for k in (0, 1) if d.modes_before[k] == "strut"]
        dq1, impulses = _solve_impact(d.before, model, pinned, struts)
        assert np.allclose(d.after[7 : 7 + nq], dq1, rtol=0.0, atol=VEL_TOL)
        assert np.allclose(impulses[d.leg], d.recorded_impulse, rtol=REL_TOL, atol=1e-12)


# --- Coulomb floor: the friction cone ---------------------------------------------------


@pytest.mark.parametrize("model, mu", COULOMB_RUNS)
def test_coulomb_touchdown_pins_only_inside_friction_cone(runs, model, mu):
    """On a Coulomb floor the toe is pinned only if the pinning impulse (solved here) lies
    in the friction cone, |P_t| <= mu P_n: then the recorded impulse is that impulse and the
    toe's velocity across the leg is stopped. Otherwise the floor cannot give it: the toe
    lands sliding (a slide_start record with cause SLIDE_CAUSE_NO_PIN_IMPULSE), with no
    impulse, no loss and unchanged velocities."""
    landings = runs[(model, mu)]
    assert len(landings) >= 10
    n_pinned = n_sliding = 0
    nq = 7 if model == "II" else 5
    for d in landings:
        pinned = [d.leg] + [
            k for k in (0, 1) if k != d.leg and d.modes_before[k] in ("stick", "strut")
        ]
        struts = [k for k in (0, 1) if k != d.leg and d.modes_before[k] == "strut"]
        _, impulses = _solve_impact(d.before, model, pinned, struts)
        pt, pn = impulses[d.leg]
        if abs(pt) <= mu * pn:
            n_pinned += 1
            assert not d.slid_without_pin_impulse()
            assert d.normal > 0.0 and abs(d.tangential) <= mu * d.normal
            assert np.allclose(d.recorded_impulse, impulses[d.leg], rtol=REL_TOL, atol=1e-12)
            assert abs(_toe_velocity_across(d.after, d.leg)) < VEL_TOL
        else:
            n_sliding += 1
            assert d.slid_without_pin_impulse()
            assert (d.normal, d.tangential, d.loss) == (0.0, 0.0, 0.0)
            assert np.array_equal(d.after[7 : 7 + nq], d.before[7 : 7 + nq])
            assert _kinetic_energy(d.after, model) == _kinetic_energy(d.before, model)
    assert n_sliding > 0
    if mu == HIGH_MU:
        assert n_pinned > 0
