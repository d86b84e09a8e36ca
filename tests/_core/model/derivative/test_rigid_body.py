"""The tangents of the rigid-body terms (scoutsim._core.model.derivative.rigid_body) equal
the central differences of the primal terms (scoutsim._core.model.rigid_body) along the
same direction: in the sines and cosines of the configuration (taken as independent
numbers), the velocities and the parameters, for a geared (Model II) and rigid (ideal,
Model I) hip unit, and a robot whose legs differ with its torso COM off the hips' midpoint;
each kernel takes several directions at once, a column each.
"""

import math

import numpy as np
import pytest

from scoutsim import RobotParameters
from scoutsim._core.model import layout as L
from scoutsim._core.model.derivative.rigid_body import (
    add_gravity_t,
    coriolis_t,
    mass_matrix_times_t,
)
from scoutsim._core.model.hip_unit import is_geared
from scoutsim._core.model.packing import robot_array
from scoutsim._core.model.rigid_body import add_gravity_at, coriolis_at, mass_matrix_at

#: relative step of the central differences (directions are scaled to their inputs)
EPS = 1e-6
#: allowed difference, relative to the largest entry of the central difference: the
#: truncation error is O(EPS^2) (the terms are polynomials of low degree), the round-off
#: O(1e-16 / EPS)
RTOL = 1e-7

#: legs that differ, the torso COM ahead of the hips' midpoint, and gears on both sides
UNEQUAL = RobotParameters(
    com_offset=0.03,
    leg_mass=(1.0, 0.8),
    leg_inertia=(0.0052, 0.004),
    leg_com_distance=(0.16, 0.14),
    planetary_ratio=(5.0, 4.6),
    sprocket_ratio=(20.4, 21.0),
    drive_gear_inertia=(2.4e-6, 2.0e-6),
    driven_gear_inertia=(0.0011, 0.0009),
)

#: the float parameters the rigid-body terms read (whole robot, then per leg)
READ = [L.P_MT, L.P_IT, L.P_L, L.P_COM_OFFSET, L.P_NP, L.P_G] + [
    s + leg for s in (L.P_ML, L.P_IL, L.P_D, L.P_N, L.P_J1, L.P_J2) for leg in range(2)
]

CASES = {
    "II": (RobotParameters(), "II"),
    "I": (RobotParameters(), "I"),
    "ideal": (RobotParameters(), "ideal"),
    "II-unequal": (UNEQUAL, "II"),
    "I-unequal": (UNEQUAL, "I"),
}


def _P(case):
    robot, model = CASES[case]
    return robot_array(robot, model, friction_coefficient=1.0)


def _trig(rng):
    """Sines and cosines (TR_* order) of a random pitch and leg angles."""
    th, gb, gf = rng.uniform(-0.6, 0.6, 3)
    return np.array([math.sin(v) for a in (th, gb, gf) for v in (a, a + math.pi / 2)])


def _direction(rng, P, *, trig=True, params=True):
    """Random tangents of the sines and cosines and of the parameters read (each scaled
    to its value, or to 0.01 where the value is 0); the integer codes and flags, and the
    parameters not read, are left at zero."""
    tr_t = rng.normal(size=6) if trig else np.zeros(6)
    P_t = np.zeros_like(P)
    if params:
        for s in READ:
            P_t[s] = rng.normal() * (abs(P[s]) or 0.01)
    return tr_t, P_t


def _central(f, x0, x_t, eps=EPS):
    """Central difference of f along x_t at x0 (a tuple of arrays and their tangents)."""
    plus = f(*[x + eps * t for x, t in zip(x0, x_t)])
    minus = f(*[x - eps * t for x, t in zip(x0, x_t)])
    return (plus - minus) / (2.0 * eps)


def _mass_times(a, P, tr):
    M = np.empty((L.NQ, L.NQ))
    mass_matrix_at(M, P, *tr)
    return M @ a


def _coriolis(dq, P, tr):
    h = np.empty(L.NQ)
    coriolis_at(h, dq, P, *tr)
    return h


def _gravity(P, tr):
    Q = np.zeros(L.NQ)
    add_gravity_at(Q, P, *tr)
    return Q


def _rel_error(t, fd):
    """Largest difference of the tangent t from the central difference fd, relative to
    fd's largest entry (which must not vanish: a test of a zero tangent proves nothing)."""
    scale = np.max(np.abs(fd))
    assert scale > 0.0
    return np.max(np.abs(t - fd)) / scale


def _columns(directions):
    """The batched layout of directions [(tr_t (6), P_t (NP)), ...]: tr_t (6, m) with a
    column per direction, P_t (m, NP) with a row per direction."""
    tr_t = np.stack([d[0] for d in directions], axis=1)
    P_t = np.stack([d[1] for d in directions])
    return tr_t, P_t


def _pairs(P, tr, tr_t, P_t, rng, eps=EPS):
    """(tangents, central differences), both (NQ, m), of each term at (P, tr) along the m
    directions of the columns of tr_t (6, m) and the rows of P_t (m, NP), all in one call
    of each kernel, with random accelerations and velocities; the velocities' tangents of
    a direction are random too when it has both a configuration and a parameter part, else
    zero (a direction in one part alone, or none); ``eps``: the step of the differences.
    The kernels that add are given outputs that already hold random values, which they
    must keep."""
    m = tr_t.shape[1]
    a = rng.normal(size=L.NQ)
    dq = rng.normal(size=L.NQ) * 3.0
    dq_t = np.zeros((L.NQ, m))
    for c in range(m):
        if tr_t[:, c].any() and P_t[c].any():
            dq_t[:, c] = rng.normal(size=L.NQ) * 3.0
    out0 = rng.normal(size=(L.NQ, m))
    out = out0.copy()
    mass_matrix_times_t(out, a, P, tr, tr_t, P_t)
    h_t = np.full((L.NQ, m), np.nan)
    coriolis_t(h_t, dq, dq_t, P, tr, tr_t, P_t)
    Q0 = rng.normal(size=(L.NQ, m))
    Q_t = Q0.copy()
    add_gravity_t(Q_t, P, tr, tr_t, P_t)
    fd_m, fd_h, fd_q = (np.empty((L.NQ, m)) for _ in range(3))
    for c in range(m):
        x_t = (P_t[c], tr_t[:, c])
        fd_m[:, c] = _central(lambda P_, tr_: _mass_times(a, P_, tr_), (P, tr), x_t, eps)
        fd_h[:, c] = _central(_coriolis, (dq, P, tr), (dq_t[:, c],) + x_t, eps)
        fd_q[:, c] = _central(_gravity, (P, tr), x_t, eps)
    return {"mass": (out - out0, fd_m), "coriolis": (h_t, fd_h), "gravity": (Q_t - Q0, fd_q)}


def _errors(P, tr, tr_t, P_t, rng):
    """Relative errors of the three tangents along one direction (tr_t (6), P_t (NP)),
    given to the kernels as one column (:func:`_pairs`, :func:`_rel_error`)."""
    tr_t, P_t = _columns([(tr_t, P_t)])
    return {k: _rel_error(t, fd) for k, (t, fd) in _pairs(P, tr, tr_t, P_t, rng).items()}


@pytest.mark.parametrize("case", sorted(CASES))
def test_tangents_equal_central_differences_along_random_directions(case):
    """The tangent of the mass matrix product equals the central difference of M a, that of
    the velocity terms the central difference of h, that of gravity the central difference
    of Q, along random directions in the sines and cosines, the velocities and the
    parameters read (kernels that add keep what the output held)."""
    rng = np.random.default_rng(7)
    P = _P(case)
    assert is_geared(P[L.P_HIP_UNIT]) == (CASES[case][1] == "II")
    for _ in range(5):
        tr = _trig(rng)
        tr_t, P_t = _direction(rng, P)
        err = _errors(P, tr, tr_t, P_t, rng)
        assert max(err.values()) < RTOL, err


@pytest.mark.parametrize("case", ["II-unequal", "I-unequal"])
@pytest.mark.parametrize("part", ["trig", "params"])
def test_tangents_along_the_configuration_alone_and_the_parameters_alone(case, part):
    """Along a direction in the sines and cosines alone, and along one in the parameters
    alone, each tangent equals the central difference of its primal term."""
    rng = np.random.default_rng(11)
    P = _P(case)
    for _ in range(3):
        tr = _trig(rng)
        tr_t, P_t = _direction(rng, P, trig=part == "trig", params=part == "params")
        err = _errors(P, tr, tr_t, P_t, rng)
        assert max(err.values()) < RTOL, err


GEAR = [s + leg for s in (L.P_N, L.P_J1, L.P_J2) for leg in range(2)]


@pytest.mark.parametrize("slot", READ)
def test_each_parameter_read_has_its_tangent(slot):
    """Along each parameter the terms read, alone, the tangent of each term equals its
    central difference, and some term depends on it (Model II, legs that differ); a gear
    parameter of a rigid hip unit (Model I) gives no tangent, as the primal does not read
    it. Each term is a polynomial of degree 2 at most in any one parameter, on which a
    central difference is exact: a step of 1 % keeps the round-off of the terms' large
    entries (the torso's) from hiding the small ones (a gear inertia's)."""
    rng = np.random.default_rng(slot)
    tr = _trig(rng)
    for case in ("II-unequal", "I-unequal"):
        P = _P(case)
        P_t = np.zeros_like(P)
        P_t[slot] = abs(P[slot]) or 0.01
        pairs = _pairs(P, tr, *_columns([(np.zeros(6), P_t)]), rng, eps=1e-2)
        for t, fd in pairs.values():
            scale = np.max(np.abs(fd))
            assert np.max(np.abs(t - fd)) <= RTOL * scale
        largest = max(np.max(np.abs(fd)) for _, fd in pairs.values())
        if case == "I-unequal" and slot in GEAR:
            assert largest == 0.0
            assert not any(t.any() for t, _ in pairs.values())
        else:
            assert largest > 0.0


def test_mass_matrix_tangent_is_symmetric():
    """The tangent of the symmetric mass matrix is symmetric: its columns M_t e_j, from the
    product with the unit vectors, form a symmetric matrix equal to the central difference
    of M."""
    rng = np.random.default_rng(3)
    P = _P("II-unequal")
    tr = _trig(rng)
    tr_t, P_t = _direction(rng, P)
    Mt = np.zeros((L.NQ, L.NQ))
    tr_tc, P_tc = _columns([(tr_t, P_t)])
    for j in range(L.NQ):
        mass_matrix_times_t(Mt[:, j : j + 1], np.eye(L.NQ)[j], P, tr, tr_tc, P_tc)
    np.testing.assert_allclose(Mt, Mt.T, rtol=0.0, atol=1e-15 * np.max(np.abs(Mt)))

    def mass(P_, tr_):
        M = np.empty((L.NQ, L.NQ))
        mass_matrix_at(M, P_, *tr_)
        return M

    fd = _central(mass, (P, tr), (P_t, tr_t))
    assert np.max(np.abs(Mt - fd)) < RTOL * np.max(np.abs(fd))


@pytest.mark.parametrize("case", sorted(CASES))
def test_several_directions_at_once_column_by_column(case):
    """Given several directions at once (a column each), each kernel gives in each column
    the tangent along that column's direction: it equals the central difference along it
    (a direction in the sines and cosines alone, one in the parameters alone, three in
    both), and bit for bit what the kernel gives for that direction alone; along a zero
    direction the tangents are zero (what the kernels that add are given is kept)."""
    rng = np.random.default_rng(5)
    P = _P(case)
    tr = _trig(rng)
    dirs = [_direction(rng, P, params=False), _direction(rng, P, trig=False)]
    dirs += [_direction(rng, P) for _ in range(3)]
    dirs.insert(2, _direction(rng, P, trig=False, params=False))
    tr_t, P_t = _columns(dirs)
    pairs = _pairs(P, tr, tr_t, P_t, np.random.default_rng(13))
    for c in range(len(dirs)):
        for name, (t, fd) in pairs.items():
            if c == 2:
                assert not t[:, c].any() and not fd[:, c].any(), name
            else:
                assert _rel_error(t[:, c], fd[:, c]) < RTOL, (name, c)
    # each direction alone (a one-column call, with the same accelerations, velocities,
    # velocity tangents and outputs' initial values) gives its batched column bit for bit
    a = rng.normal(size=L.NQ)
    dq = rng.normal(size=L.NQ)
    dq_t = rng.normal(size=(L.NQ, len(dirs)))
    out = rng.normal(size=(L.NQ, len(dirs)))
    h_t = np.full_like(out, np.nan)
    Q_t = out.copy()
    outs = (out.copy(), h_t.copy(), Q_t.copy())
    mass_matrix_times_t(outs[0], a, P, tr, tr_t, P_t)
    coriolis_t(outs[1], dq, dq_t, P, tr, tr_t, P_t)
    add_gravity_t(outs[2], P, tr, tr_t, P_t)
    for c in range(len(dirs)):
        one = (out[:, c : c + 1].copy(), h_t[:, c : c + 1].copy(), Q_t[:, c : c + 1].copy())
        tr_1, P_1 = tr_t[:, c : c + 1], P_t[c : c + 1]
        mass_matrix_times_t(one[0], a, P, tr, tr_1, P_1)
        coriolis_t(one[1], dq, dq_t[:, c : c + 1], P, tr, tr_1, P_1)
        add_gravity_t(one[2], P, tr, tr_1, P_1)
        for batched, alone in zip(outs, one):
            assert np.array_equal(batched[:, c], alone[:, 0])
