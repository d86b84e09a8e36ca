"""Cross-check of the compiled equations of motion against an independent SymPy derivation.

``tools/derive_eom.py`` derives M(q), h(q, dq), the gravity force, the energies and the toe
kinematics from the kinetic and potential energy written down directly from docs/specification.md section 1, 2, 5
(Lagrange's equations, no shared code). These tests compare them with
``scoutsim._core.model`` (rigid_body, evaluate) for random states (fixed seed), for Model II (gear inertias) and
Model I (no gears), for the default robot, for a variant with one physical leg per
virtual leg and a different leg COM distance, and for a robot whose back and front legs
differ in every leg, hip-unit and motor quantity and whose torso COM is ahead of the
hips' midpoint. They also check the constrained stance
dynamics (pinned toe) against an independently assembled KKT system and against finite
differences of the toe's perpendicular velocity along the flow.
"""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest

import scoutsim
from scoutsim._core.model import evaluate as ev
from scoutsim._core.model import kinematics, rigid_body
from scoutsim._core.model import layout as L
from scoutsim._core.model.packing import robot_array

_TOOL = Path(__file__).resolve().parents[3] / "tools" / "derive_eom.py"


def _load_tool():
    name = "scoutsim_tools_derive_eom"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, _TOOL)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod


sym = _load_tool()

RTOL = 1e-10

ROBOTS = {
    "default": scoutsim.RobotParameters(),
    "single_leg": scoutsim.RobotParameters(legs_per_virtual_leg=1, leg_com_distance=0.1),
    "unequal": scoutsim.RobotParameters(
        com_offset=0.035,
        leg_mass=(1.0, 0.7),
        leg_inertia=(0.0052, 0.0031),
        leg_com_distance=(0.16, 0.12),
        leg_rest_length=(0.323, 0.31),
        leg_stiffness=(3520.0, 4100.0),
        leg_damping=(55.0, 62.0),
        planetary_ratio=(5.0, 4.2),
        sprocket_ratio=(20.0, 22.0),
        drive_gear_inertia=(2.0e-6, 3.1e-6),
        driven_gear_inertia=(0.012, 0.009),
        belt_stiffness=(401.0, 350.0),
        belt_damping=(0.2, 0.35),
        joint_damping=(4e-5, 7e-5),
        joint_stiction=(0.02, 0.035),
    ),
}


def _leg(robot, field, leg):
    """Leg ``leg``'s value of a RobotParameters field (one value or a (back, front) pair)."""
    v = getattr(robot, field)
    return v[leg] if isinstance(v, tuple) else v


def _hip_offsets(robot):
    """The hips' positions along the torso axis from the torso COM [m], from the fields."""
    half = robot.hip_spacing / 2.0
    return (-half - robot.com_offset, half - robot.com_offset)


MODELS = ("II", "I")
N_STATES = 8


def _states(seed=20240601, n=N_STATES):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        q = np.empty(7)
        q[0] = rng.uniform(-1.0, 1.0)
        q[1] = rng.uniform(0.2, 0.5)
        q[2] = rng.uniform(-0.6, 0.6)
        q[3:5] = rng.uniform(-1.2, 1.2, 2)
        q[5:7] = q[3:5] + rng.uniform(-0.15, 0.15, 2)
        dq = rng.uniform(-4.0, 4.0, 7)
        dq[5:7] = dq[3:5] + rng.uniform(-2.0, 2.0, 2)
        out.append((q, dq))
    return out


STATES = _states()


def _params(robot, model):
    return sym.params_from_robot(robot, gears=(model == "II"))


def _assert_close(actual, desired, what, rtol=RTOL):
    """Elementwise relative tolerance rtol, plus rtol * 1e-2 of the largest reference
    entry as absolute floor (entries that vanish identically)."""
    actual = np.asarray(actual, dtype=float)
    desired = np.asarray(desired, dtype=float)
    scale = max(np.max(np.abs(desired)), 1e-300)
    np.testing.assert_allclose(actual, desired, rtol=rtol, atol=1e-2 * rtol * scale, err_msg=what)


def _is_close(actual, desired, rtol=RTOL):
    try:
        _assert_close(actual, desired, "", rtol)
    except AssertionError:
        return False
    return True


def _modes(contact_b=L.FLIGHT, contact_f=L.FLIGHT, motor=1):
    mi = np.zeros(L.NMI, dtype=np.int64)
    mi[L.MI_CONTACT_B] = contact_b
    mi[L.MI_CONTACT_F] = contact_f
    mi[L.MI_MOTOR_B] = motor
    mi[L.MI_MOTOR_F] = motor
    return mi


# --- mass matrix, velocity products, energies ---------------------------------------------
@pytest.mark.parametrize("robot_name", sorted(ROBOTS))
@pytest.mark.parametrize("model", MODELS)
def test_mass_matrix(robot_name, model):
    robot = ROBOTS[robot_name]
    P = robot_array(robot, model)
    prm = _params(robot, model)
    M = np.empty((7, 7))
    for q, _ in STATES:
        rigid_body.mass_matrix(q, P, M)
        Ms = sym.mass_matrix(q, prm)
        _assert_close(M, Ms, f"M, model {model}, {robot_name}, q={q}")
        if model == "I":
            _assert_close(M[:5, :5], Ms[:5, :5], "M 5x5 block")
            assert np.all(M[5:, :] == 0.0) and np.all(M[:, 5:] == 0.0)
        else:
            # the gear entries are present and not negligible against the comparison
            assert Ms[5, 5] > 1e3 * RTOL * np.max(np.abs(Ms))
        assert np.allclose(Ms, Ms.T, rtol=0, atol=0)
        assert np.all(np.linalg.eigvalsh(Ms[:5, :5]) > 0.0)


@pytest.mark.parametrize("robot_name", sorted(ROBOTS))
@pytest.mark.parametrize("model", MODELS)
def test_coriolis(robot_name, model):
    robot = ROBOTS[robot_name]
    P = robot_array(robot, model)
    prm = _params(robot, model)
    h = np.empty(7)
    for q, dq in STATES:
        rigid_body.coriolis(q, dq, P, h)
        hs = sym.coriolis(q, dq, prm)
        _assert_close(h, hs, f"h, model {model}, {robot_name}, q={q}, dq={dq}")
        # the comparison is sensitive: the velocity products are not negligible, and a
        # flipped sign (or a missing back/front hip sign) would be caught
        assert np.max(np.abs(hs[:5])) > 1e-3
        assert not _is_close(-h, hs)


def test_coriolis_detects_swapped_hip_sign():
    """A model with the hips swapped (L -> -L) differs from the reference: the comparison
    of test_coriolis would catch a wrong hip sign."""
    robot = ROBOTS["default"]
    prm = _params(robot, "II")
    prm_bad = dict(prm, L=-prm["L"])
    for q, dq in STATES:
        assert not _is_close(sym.coriolis(q, dq, prm_bad), sym.coriolis(q, dq, prm))
        assert not _is_close(sym.mass_matrix(q, prm_bad), sym.mass_matrix(q, prm))


def test_coriolis_consistent_with_mass_matrix():
    """h from Lagrange's equations equals the Christoffel form built from finite differences
    of M: h_i = sum_jk (dM_ij/dq_k - 1/2 dM_jk/dq_i) dq_j dq_k (checks the tool itself)."""
    prm = _params(ROBOTS["default"], "II")
    eps = 1e-6
    for q, dq in STATES[:3]:
        dM = np.empty((7, 7, 7))
        for k in range(7):
            e = np.zeros(7)
            e[k] = eps
            dM[:, :, k] = (sym.mass_matrix(q + e, prm) - sym.mass_matrix(q - e, prm)) / (2 * eps)
        h = np.einsum("ijk,j,k->i", dM, dq, dq) - 0.5 * np.einsum("jki,j,k->i", dM, dq, dq)
        np.testing.assert_allclose(h, sym.coriolis(q, dq, prm), rtol=1e-6, atol=1e-7)


@pytest.mark.parametrize("robot_name", sorted(ROBOTS))
@pytest.mark.parametrize("model", MODELS)
def test_kinetic_energy(robot_name, model):
    robot = ROBOTS[robot_name]
    P = robot_array(robot, model)
    prm = _params(robot, model)
    for q, dq in STATES:
        dq_ = dq.copy()
        if model != "II":
            dq_[5:7] = dq_[3:5]  # alpha is a copy of phi (no gear inertia anyway)
        Ms = sym.mass_matrix(q, prm)
        t_quad = 0.5 * dq_ @ Ms @ dq_
        t_sym = sym.kinetic_energy(q, dq_, prm)
        assert t_sym == pytest.approx(t_quad, rel=1e-12)
        assert rigid_body.kinetic_energy(q, dq_, P) == pytest.approx(t_quad, rel=RTOL)


@pytest.mark.parametrize("robot_name", sorted(ROBOTS))
@pytest.mark.parametrize("model", MODELS)
def test_potential_energy(robot_name, model):
    robot = ROBOTS[robot_name]
    P = robot_array(robot, model)
    prm = _params(robot, model)
    rng = np.random.default_rng(7)
    for q, _ in STATES:
        l = rng.uniform(0.25, min(robot.per_leg("leg_rest_length")), 2)
        v_sym = sym.potential_energy(q, l, prm)
        v_c = rigid_body.potential_energy(q, l, P)
        assert v_c == pytest.approx(v_sym, rel=RTOL, abs=1e-12)
        # gravity part alone: springs relaxed, belts undeflected
        q0 = q.copy()
        q0[5:7] = q0[3:5]
        l0 = np.array(robot.per_leg("leg_rest_length"))
        assert rigid_body.potential_energy(q0, l0, P) == pytest.approx(
            sym.potential_energy(q0, l0, prm), rel=RTOL
        )
    # the spring terms are really present in the comparison
    q = STATES[0][0]
    l_short = np.array([0.28, 0.30])
    l0 = np.array(robot.per_leg("leg_rest_length"))
    dv = sym.potential_energy(q, l_short, prm) - sym.potential_energy(q, l0, prm)
    assert dv > 1.0


def test_gravity_force_is_gradient_of_potential():
    """-dV/dq by central differences of the tool's potential (checks the tool itself)."""
    prm = _params(ROBOTS["default"], "II")
    prm0 = dict(prm, k_b=0.0, k_f=0.0, k_b_b=0.0, k_b_f=0.0)
    eps = 1e-6
    l = np.array([0.3, 0.3])
    for q, _ in STATES[:3]:
        fd = np.empty(7)
        for i in range(7):
            e = np.zeros(7)
            e[i] = eps
            fd[i] = -(
                sym.potential_energy(q + e, l, prm0) - sym.potential_energy(q - e, l, prm0)
            ) / (2 * eps)
        np.testing.assert_allclose(sym.gravity_force(q, prm), fd, rtol=1e-7, atol=1e-6)


# --- gravity and flight dynamics through evaluate -------------------------------------------
def _flight_state(q, dq, robot):
    s = np.zeros(L.NS)
    s[:7] = q
    s[7:14] = dq
    s[L.IL_B] = _leg(robot, "leg_rest_length", 0)
    s[L.IL_F] = _leg(robot, "leg_rest_length", 1)
    return s


@pytest.mark.parametrize("robot_name", sorted(ROBOTS))
def test_gravity_force_passive(robot_name):
    """Model passive, massive legs, both legs in flight, at rest: M ddq = Q_grav."""
    robot = ROBOTS[robot_name]
    P = robot_array(robot, "passive")
    prm = _params(robot, "passive")
    mi = _modes(motor=1)
    mf = np.zeros(L.NMF)
    cmd = np.zeros(2)
    ds = np.empty(L.NS)
    aux = np.empty(L.NAUX)
    M = np.empty((7, 7))
    for q, _ in STATES:
        q = q.copy()
        q[5:7] = q[3:5]
        s = _flight_state(q, np.zeros(7), robot)
        assert ev.evaluate(s, P, mi, mf, cmd, ds, aux)
        rigid_body.mass_matrix(q, P, M)
        qg_compiled = M[:5, :5] @ ds[7:12]
        qg_sym = sym.gravity_force(q, prm)
        _assert_close(qg_compiled, qg_sym[:5], f"gravity force, {robot_name}, q={q}", rtol=RTOL)
        ddq_sym = np.linalg.solve(sym.mass_matrix(q, prm)[:5, :5], qg_sym[:5])
        _assert_close(ds[7:12], ddq_sym, "flight ddq at rest", rtol=RTOL)
        assert np.all(ds[12:14] == ds[10:12])  # alpha copies phi
        assert abs(qg_sym[2]) > 0.1 or abs(qg_sym[3]) > 0.1
        # energy output = V at rest
        assert aux[L.A_ENERGY] == pytest.approx(sym.potential_energy(q, s[14:16], prm), rel=1e-12)


@pytest.mark.parametrize("robot_name", sorted(ROBOTS))
@pytest.mark.parametrize("model", ("passive", "I"))
def test_flight_dynamics_with_velocity(robot_name, model):
    """Both legs in flight, moving: M ddq + h = Q_grav + Q_hip with the hip torque acting
    on phi only (torso reaction, docs/specification.md section 1). Checks the sign with which h enters."""
    robot = ROBOTS[robot_name]
    P = robot_array(robot, model)
    prm = _params(robot, model)
    mi = _modes(motor=1)
    mf = np.zeros(L.NMF)
    cmd = np.array([4.0, -3.0]) if model == "I" else np.zeros(2)
    ds = np.empty(L.NS)
    aux = np.empty(L.NAUX)
    npl = robot.legs_per_virtual_leg
    for q, dq in STATES:
        q = q.copy()
        dq = 0.5 * dq  # keep the motor speed inside the torque-speed line
        q[5:7] = q[3:5]
        dq[5:7] = dq[3:5]
        s = _flight_state(q, dq, robot)
        assert ev.evaluate(s, P, mi, mf, cmd, ds, aux)
        Qa = np.zeros(7)
        if model == "I":
            # commanded torques are well inside all limits here
            for leg in range(2):
                assert aux[leg * L.NAUX_LEG + L.A_TAU_APP] == pytest.approx(cmd[leg], rel=1e-12)
            Qa[3:5] = npl * cmd
        Ms = sym.mass_matrix(q, prm)
        rhs = sym.gravity_force(q, prm) + Qa - sym.coriolis(q, dq, prm)
        ddq_sym = np.linalg.solve(Ms[:5, :5], rhs[:5])
        _assert_close(ds[7:12], ddq_sym, f"flight ddq, {model}, {robot_name}", rtol=RTOL)
        _assert_close(ds[:7], dq, "ds[:7] = dq")
        e_sym = sym.kinetic_energy(q, dq, prm) + sym.potential_energy(q, s[14:16], prm)
        assert aux[L.A_ENERGY] == pytest.approx(e_sym, rel=1e-12)


# --- stance: constrained dynamics of a pinned toe ------------------------------------------
def _stance_state(robot, model, legs, rng):
    """A state with the toes of ``legs`` exactly on the ground at l = 0.30, other legs in
    flight; returns (s, mi, mf)."""
    hips = _hip_offsets(robot)
    l_st = 0.30
    q = np.zeros(7)
    double = len(legs) == 2
    q[0] = rng.uniform(-0.5, 0.5)
    q[2] = rng.uniform(-0.08, 0.08) if double else rng.uniform(-0.25, 0.25)
    q[3] = rng.uniform(-0.4, 0.4)
    q[4] = rng.uniform(-0.4, 0.4)
    if double:
        # both hips within reach (hip heights 0.22 .. 0.29 m); each stance leg's absolute
        # angle such that its toe is on the ground at l = 0.30: hip_y - l cos(g) = 0
        q[1] = rng.uniform(0.245, 0.265)
        for leg in legs:
            hy = q[1] + hips[leg] * math.sin(q[2])
            g = math.acos(hy / l_st) * rng.choice((-1.0, 1.0))
            q[3 + leg] = g - q[2]
    else:
        # y such that the stance leg's toe is on the ground
        leg = legs[0]
        g = q[2] + q[3 + leg]
        q[1] = l_st * math.cos(g) - hips[leg] * math.sin(q[2])
    q[5:7] = q[3:5]
    if model == "II":
        q[5:7] += rng.uniform(-0.05, 0.05, 2)
    dq = rng.uniform(-1.5, 1.5, 7)
    if model != "II":
        dq[5:7] = dq[3:5]
    mi = _modes(motor=1)
    mf = np.zeros(L.NMF)
    l = np.array([_leg(robot, "leg_rest_length", leg) for leg in range(2)])
    for leg in legs:
        mi[L.MI_CONTACT_B + leg] = L.STICK
        gl = q[2] + q[3 + leg]
        hx = q[0] + hips[leg] * math.cos(q[2])
        mf[L.MF_ANCHOR_B + leg] = hx + l_st * math.sin(gl)
        l[leg] = l_st
    s = np.concatenate([q, dq, l])
    return s, mi, mf


def _toe_jacobian(q, l, prm, leg):
    """2 x 7 toe Jacobian at fixed leg length from the tool's toe velocity (linear in dq)."""
    J = np.empty((2, 7))
    for j in range(7):
        e = np.zeros(7)
        e[j] = 1.0
        J[:, j] = sym.toe_velocity(q, e, l, 0.0, prm, leg)
    return J


def _independent_stance_ddq(s, mi, robot, model):
    """Assemble and solve the stance KKT system from the tool's M, h, Q_grav and toe
    kinematics; returns (ddq_active, ldot, ground forces per stance leg)."""
    prm = _params(robot, model)
    q = s[:7]
    dq = s[7:14]
    l = s[14:16]
    nact = 7 if model == "II" else 5
    npl = robot.legs_per_virtual_leg
    Q = sym.gravity_force(q, prm) - sym.coriolis(q, dq, prm)
    if model == "II":
        # hip unit forces (docs/specification.md section 5), zero command: belt spring/damper, joint friction
        for leg in range(2):
            Nr = _leg(robot, "planetary_ratio", leg) * _leg(robot, "sprocket_ratio", leg)
            tb = _leg(robot, "belt_stiffness", leg) * (q[5 + leg] - q[3 + leg]) + _leg(
                robot, "belt_damping", leg
            ) * (dq[5 + leg] - dq[3 + leg])
            Q[3 + leg] += npl * tb
            Q[5 + leg] -= npl * tb
            om = Nr * dq[5 + leg]
            tf = (
                _leg(robot, "joint_damping", leg) * om
                + _leg(robot, "joint_stiction", leg) * mi[L.MI_MOTOR_B + leg]
            )
            Q[5 + leg] -= npl * Nr * tf
    rows, rhs, ldot, forces = [], [], {}, {}
    for leg in range(2):
        if mi[L.MI_CONTACT_B + leg] != L.STICK:
            continue
        n = sym.leg_normal(q, leg)
        gl = q[2] + q[3 + leg]
        u = np.array([math.sin(gl), -math.cos(gl)])
        v0 = sym.toe_velocity(q, dq, l[leg], 0.0, prm, leg)
        ld = -v0 @ u  # pinned toe: v0 + ld u = 0 (axially)
        ldot[leg] = ld
        F = npl * (
            _leg(robot, "leg_stiffness", leg) * (_leg(robot, "leg_rest_length", leg) - l[leg])
            - _leg(robot, "leg_damping", leg) * ld
        )
        J = _toe_jacobian(q, l[leg], prm, leg)
        Q += J.T @ (-F * u)
        bias = sym.toe_acceleration(q, dq, np.zeros(7), l[leg], ld, 0.0, prm, leg)
        rows.append(n @ J)
        rhs.append(-(n @ bias))
        forces[leg] = (F, u, n)
    Ms = sym.mass_matrix(q, prm)
    nr = len(rows)
    A = np.zeros((nact + nr, nact + nr))
    b = np.zeros(nact + nr)
    A[:nact, :nact] = Ms[:nact, :nact]
    b[:nact] = Q[:nact]
    for r, (row, rr) in enumerate(zip(rows, rhs)):
        A[nact + r, :nact] = row[:nact]
        A[:nact, nact + r] = -row[:nact]  # M ddq - R^T lam = Q
        b[nact + r] = rr
    x = np.linalg.solve(A, b)
    ground = {}
    for r, leg in enumerate(sorted(forces)):
        F, u, n = forces[leg]
        ground[leg] = -F * u + x[nact + r] * n
    return x[:nact], ldot, ground


STANCE_CASES = [("I", (0,)), ("I", (1,)), ("I", (0, 1)), ("II", (0,)), ("II", (0, 1))]


@pytest.mark.parametrize("robot_name", sorted(ROBOTS))
@pytest.mark.parametrize("model,legs", STANCE_CASES)
def test_stance_constrained_dynamics(robot_name, model, legs):
    robot = ROBOTS[robot_name]
    P = robot_array(robot, model)
    prm = _params(robot, model)
    rng = np.random.default_rng(99 + 10 * len(legs) + legs[0])
    cmd = np.zeros(2)
    ds = np.empty(L.NS)
    aux = np.empty(L.NAUX)
    for _ in range(4):
        s, mi, mf = _stance_state(robot, model, legs, rng)
        s0 = s.copy()
        kinematics.project_state(s, P, mi, mf)
        # the chosen state was already on the constraint: only dphi of stance legs changes
        np.testing.assert_allclose(s[:7], s0[:7], rtol=0, atol=1e-12)
        np.testing.assert_allclose(s[14:16], s0[14:16], rtol=0, atol=1e-12)
        assert ev.evaluate(s, P, mi, mf, cmd, ds, aux)
        q, dq, l = s[:7], s[7:14], s[14:16]
        np.testing.assert_array_equal(ds[:7], dq)
        for leg in legs:
            # toe on the ground at its anchor, at rest (position and velocity level)
            toe = sym.toe_position(q, l[leg], prm, leg)
            assert toe[0] == pytest.approx(mf[leg], abs=1e-12)
            assert toe[1] == pytest.approx(0.0, abs=1e-12)
            v = sym.toe_velocity(q, dq, l[leg], ds[L.IL_B + leg], prm, leg)
            np.testing.assert_allclose(v, 0.0, atol=1e-12)
            # acceleration level: the perpendicular toe acceleration vanishes (the axial
            # part is the massless toe's first-order slide and is not constrained)
            n = sym.leg_normal(q, leg)
            for ddl in (0.0, 37.0):
                a = sym.toe_acceleration(q, dq, ds[7:14], l[leg], ds[L.IL_B + leg], ddl, prm, leg)
                assert abs(n @ a) < 1e-9, (leg, n @ a)
        # full independent solution: accelerations, leg rates and ground forces
        ddq_ref, ldot_ref, ground = _independent_stance_ddq(s, mi, robot, model)
        nact = len(ddq_ref)
        _assert_close(ds[7 : 7 + nact], ddq_ref, f"stance ddq {model} legs={legs}", rtol=RTOL)
        for leg in legs:
            assert ds[L.IL_B + leg] == pytest.approx(ldot_ref[leg], rel=1e-10, abs=1e-12)
            o = leg * L.NAUX_LEG
            _assert_close(
                [aux[o + L.A_GT], aux[o + L.A_GN]],
                ground[leg],
                f"ground force leg {leg}",
                rtol=RTOL,
            )
        # the constraint matters: without it the toe would accelerate off its anchor
        Ms = sym.mass_matrix(q, prm)
        for leg in legs:
            n = sym.leg_normal(q, leg)
            ddq_free = ds[7:14].copy()
            free = np.linalg.solve(
                Ms[:nact, :nact],
                Ms[:nact, :nact] @ ds[7 : 7 + nact]
                - ((_toe_jacobian(q, l[leg], prm, leg).T @ n)[:nact] * (n @ ground[leg])),
            )
            ddq_free[:nact] = free
            a = sym.toe_acceleration(q, dq, ddq_free, l[leg], ds[L.IL_B + leg], 0.0, prm, leg)
            assert abs(n @ a) > 1e-3


def _perp_toe_velocity(s, prm, leg):
    """n . v_toe, a function of the state only (n . u = 0 removes dl)."""
    q, dq, l = s[:7], s[7:14], s[14:16]
    return sym.leg_normal(q, leg) @ sym.toe_velocity(q, dq, l[leg], 0.0, prm, leg)


@pytest.mark.parametrize("robot_name", ("default", "unequal"))
@pytest.mark.parametrize("model", ("I", "II"))
def test_stance_toe_finite_difference(model, robot_name):
    """Back leg pinned (STICK): the derivative of the toe's perpendicular velocity along the
    flow ds, by central differences of states advanced by +-h ds, vanishes (it equals the
    perpendicular toe acceleration since the toe velocity is zero); the front leg flies."""
    robot = ROBOTS[robot_name]
    P = robot_array(robot, model)
    prm = _params(robot, model)
    rng = np.random.default_rng(4242)
    cmd = np.zeros(2)
    ds = np.empty(L.NS)
    aux = np.empty(L.NAUX)
    hstep = 1e-5
    for _ in range(4):
        s, mi, mf = _stance_state(robot, model, (0,), rng)
        kinematics.project_state(s, P, mi, mf)
        assert ev.evaluate(s, P, mi, mf, cmd, ds, aux)
        assert abs(_perp_toe_velocity(s, prm, 0)) < 1e-12
        wp = _perp_toe_velocity(s + hstep * ds, prm, 0)
        wm = _perp_toe_velocity(s - hstep * ds, prm, 0)
        dw = (wp - wm) / (2 * hstep)
        assert abs(dw) < 1e-6, dw
        # the same derivative with the front leg's (unconstrained) toe is not small, so the
        # test can tell a pinned toe from a free one
        wpf = _perp_toe_velocity(s + hstep * ds, prm, 1)
        wmf = _perp_toe_velocity(s - hstep * ds, prm, 1)
        assert abs((wpf - wmf) / (2 * hstep)) > 1e-2
        # toe position also stays put to second order: the drift of the anchored toe
        # over +-h is O(h^3) (the toe is at rest and its acceleration vanishes
        # perpendicular to the leg; along the leg the toe slides with the leg length)
        q, l = s[:7], s[14:16]
        sp_ = s + hstep * ds
        sm_ = s - hstep * ds
        tp = sym.toe_position(sp_[:7], sp_[14], prm, 0)
        tm = sym.toe_position(sm_[:7], sm_[14], prm, 0)
        t0 = sym.toe_position(q, l[0], prm, 0)
        np.testing.assert_allclose(tp, t0, atol=1e-8)
        np.testing.assert_allclose(tm, t0, atol=1e-8)
