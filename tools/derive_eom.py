"""Independent symbolic derivation of the planar Scout II equations of motion (SymPy).

This script derives the Lagrangian dynamics from scratch, from the kinetic and potential
energies written down directly from docs/specification.md sections 1, 2 and 5 -- it shares no code with
``scoutsim._core.model.rigid_body`` and is used by ``tests/_core/model/test_eom_independent.py`` to
cross-check the compiled implementation.

Model (docs/specification.md section 1, 2, 5)
-----------------------
Generalized coordinates ``q = [x, y, theta, phi_b, phi_f, alpha_b, alpha_f]``.

* Torso: mass ``m_t`` at (x, y), pitch inertia ``I_t``, angle ``theta``.
* Hip of leg i (s = -1 back, +1 front) at ``h_i = s L - e`` along the torso axis from
  the torso COM (``e``: the COM's distance ahead of the hips' midpoint):
  ``(x + h_i cos theta, y + h_i sin theta)``.
* Virtual leg i = ``n_p`` physical legs, each leg with its own parameters (suffix ``_b``
  back, ``_f`` front): one rigid body of mass ``n_p m_l``, inertia ``n_p I_l`` about its
  COM, COM at ``hip + d (sin g, -cos g)`` with ``g = theta + phi_i``.
* Model II gear pair per physical leg (n_p of them per virtual leg): driven gear ``J_2``
  with absolute angle ``theta + alpha_i``, drive gear ``J_1`` with absolute angle
  ``theta + N alpha_i``.
* Potential: gravity ``sum m g y_com``; leg spring ``1/2 n_p k (l0 - l_i)^2``; belt spring
  ``1/2 n_p k_b (alpha_i - phi_i)^2``.

Outputs: mass matrix ``M = d^2 T / d dq^2``, velocity-product vector
``h = d/dt(dT/d dq) - dT/dq - M ddq`` (so that ``M ddq + h = Q``), gravity generalized
force ``-dV_grav/dq``, the energies, and the toe kinematics (toe = hip + l u, with the leg
length l a separate time-dependent variable) up to second order.

Gear inertias are included in general; set ``J1 = J2 = 0`` for the models without a hip
unit (ideal, Model I, passive).

Run ``python tools/derive_eom.py`` to print the simplified symbolic mass matrix.
"""

from __future__ import annotations

import functools

import numpy as np
import sympy as sp

# --- symbols ------------------------------------------------------------------------------
Q_NAMES = ("x", "y", "theta", "phi_b", "phi_f", "alpha_b", "alpha_f")
#: per-leg parameters, named with the suffix of their leg (``m_l_b``, ``m_l_f``, ...)
LEG_PARAMS = ("m_l", "I_l", "d", "N", "J1", "J2", "k", "l0", "k_b")
LEG_SUFFIX = ("_b", "_f")
PARAM_NAMES = ("m_t", "I_t", "n_p", "L", "e", "g") + tuple(
    n + sfx for sfx in LEG_SUFFIX for n in LEG_PARAMS
)
LEG_SIGN = (-1, 1)  # leg 0 = back (hip at -L - e), leg 1 = front (L - e)

q = sp.symbols(" ".join(Q_NAMES), real=True)
dq = sp.symbols(" ".join("d" + n for n in Q_NAMES), real=True)
ddq = sp.symbols(" ".join("dd" + n for n in Q_NAMES), real=True)
prm = sp.symbols(" ".join(PARAM_NAMES), real=True)
P = dict(zip(PARAM_NAMES, prm))
lsym = sp.symbols("l_b l_f", real=True)  # leg lengths
dlsym = sp.symbols("dl_b dl_f", real=True)
ddlsym = sp.symbols("ddl_b ddl_f", real=True)

x, y, th = q[0], q[1], q[2]


def leg_param(name, leg):
    """Symbol of the per-leg parameter ``name`` of leg ``leg``."""
    return P[name + LEG_SUFFIX[leg]]


def _time_derivative(expr, coords, rates, accels=None):
    """d/dt of expr(coords, rates) along coords' = rates, rates' = accels."""
    out = sum(sp.diff(expr, c) * r for c, r in zip(coords, rates))
    if accels is not None:
        out += sum(sp.diff(expr, r) * a for r, a in zip(rates, accels))
    return out


def hip(leg):
    h = LEG_SIGN[leg] * P["L"] - P["e"]
    return sp.Matrix([x + h * sp.cos(th), y + h * sp.sin(th)])


def leg_angle(leg):
    return th + q[3 + leg]


def unit_axis(leg):
    g = leg_angle(leg)
    return sp.Matrix([sp.sin(g), -sp.cos(g)])  # hip -> toe


def unit_normal(leg):
    g = leg_angle(leg)
    return sp.Matrix([sp.cos(g), sp.sin(g)])  # d u / d g


def leg_com(leg):
    return hip(leg) + leg_param("d", leg) * unit_axis(leg)


def _velocity(r):
    return sp.Matrix([_time_derivative(ri, q, dq) for ri in r])


@functools.cache
def energies():
    """Symbolic (T, V_grav, V_springs)."""
    n_p = P["n_p"]
    T = (
        sp.Rational(1, 2) * P["m_t"] * (dq[0] ** 2 + dq[1] ** 2)
        + sp.Rational(1, 2) * P["I_t"] * dq[2] ** 2
    )
    V_grav = P["m_t"] * P["g"] * y
    V_spr = 0
    for leg in range(2):
        m_l, I_l, N = (leg_param(n, leg) for n in ("m_l", "I_l", "N"))
        vc = _velocity(leg_com(leg))
        w_leg = dq[2] + dq[3 + leg]
        w_j2 = dq[2] + dq[5 + leg]
        w_j1 = dq[2] + N * dq[5 + leg]
        T += (
            sp.Rational(1, 2) * n_p * m_l * (vc.dot(vc))
            + sp.Rational(1, 2) * n_p * I_l * w_leg**2
            + sp.Rational(1, 2) * n_p * leg_param("J2", leg) * w_j2**2
            + sp.Rational(1, 2) * n_p * leg_param("J1", leg) * w_j1**2
        )
        V_grav += n_p * m_l * P["g"] * leg_com(leg)[1]
        V_spr += (
            sp.Rational(1, 2) * n_p * leg_param("k", leg) * (leg_param("l0", leg) - lsym[leg]) ** 2
            + sp.Rational(1, 2) * n_p * leg_param("k_b", leg) * (q[5 + leg] - q[3 + leg]) ** 2
        )
    return sp.expand(T), V_grav, V_spr


@functools.cache
def symbolic_eom():
    """Symbolic (M, h, Q_grav) as SymPy matrices (not simplified)."""
    T, V_grav, _ = energies()
    n = len(q)
    p = [sp.diff(T, v) for v in dq]  # dT/d dq
    M = sp.Matrix(n, n, lambda i, j: sp.diff(p[i], dq[j]))
    # d/dt(dT/d dq_i) = sum_j d p_i/d q_j dq_j + (M ddq)_i
    h = sp.Matrix([_time_derivative(p[i], q, dq) - sp.diff(T, q[i]) for i in range(n)])
    Qg = sp.Matrix([-sp.diff(V_grav, qi) for qi in q])
    return M, h, Qg


@functools.cache
def symbolic_toe(leg):
    """Toe position, velocity, acceleration (2-vectors) with l a time-dependent variable."""
    z = list(q) + [lsym[leg]]
    dz = list(dq) + [dlsym[leg]]
    ddz = list(ddq) + [ddlsym[leg]]
    r = hip(leg) + lsym[leg] * unit_axis(leg)
    v = sp.Matrix([_time_derivative(ri, z, dz) for ri in r])
    a = sp.Matrix([_time_derivative(vi, z, dz, ddz) for vi in v])
    return r, v, a


# --- numeric functions (lambdified once, cached) -----------------------------------------
def _lam(args, expr):
    return sp.lambdify(args, expr, modules="numpy", cse=True)


@functools.cache
def _compiled():
    M, h, Qg = symbolic_eom()
    T, V_grav, V_spr = energies()
    f = {
        "M": _lam([q, prm], M),
        "h": _lam([q, dq, prm], h),
        "Qg": _lam([q, prm], Qg),
        "T": _lam([q, dq, prm], T),
        "V": _lam([q, lsym, prm], V_grav + V_spr),
    }
    for leg in range(2):
        r, v, a = symbolic_toe(leg)
        n = unit_normal(leg)
        f[("toe", leg)] = _lam([q, lsym[leg], prm], r)
        f[("toe_v", leg)] = _lam([q, dq, lsym[leg], dlsym[leg], prm], v)
        f[("toe_a", leg)] = _lam([q, dq, ddq, lsym[leg], dlsym[leg], ddlsym[leg], prm], a)
        f[("normal", leg)] = _lam([q], n)
    return f


def _pvec(params):
    missing = [k for k in PARAM_NAMES if k not in params]
    if missing:
        raise KeyError(f"params is missing {missing}")
    return [float(params[k]) for k in PARAM_NAMES]


def _vec(a, n):
    a = np.asarray(a, dtype=float)
    if a.shape != (n,):
        raise ValueError(f"expected a vector of length {n}, got shape {a.shape}")
    return list(a)


def mass_matrix(q_, params):
    """7 x 7 mass matrix M(q)."""
    return np.array(_compiled()["M"](_vec(q_, 7), _pvec(params)), dtype=float)


def coriolis(q_, dq_, params):
    """Velocity-product vector h(q, dq) (M ddq + h = Q), length 7."""
    return np.array(
        _compiled()["h"](_vec(q_, 7), _vec(dq_, 7), _pvec(params)), dtype=float
    ).reshape(7)


def gravity_force(q_, params):
    """Gravity generalized force -dV_grav/dq, length 7."""
    return np.array(_compiled()["Qg"](_vec(q_, 7), _pvec(params)), dtype=float).reshape(7)


def kinetic_energy(q_, dq_, params):
    return float(_compiled()["T"](_vec(q_, 7), _vec(dq_, 7), _pvec(params)))


def potential_energy(q_, l_, params):
    """Gravity + leg springs (lengths l = [l_b, l_f]) + belt springs."""
    return float(_compiled()["V"](_vec(q_, 7), _vec(l_, 2), _pvec(params)))


def toe_position(q_, l, params, leg):
    return np.array(
        _compiled()[("toe", leg)](_vec(q_, 7), float(l), _pvec(params)), dtype=float
    ).reshape(2)


def toe_velocity(q_, dq_, l, dl, params, leg):
    return np.array(
        _compiled()[("toe_v", leg)](_vec(q_, 7), _vec(dq_, 7), float(l), float(dl), _pvec(params)),
        dtype=float,
    ).reshape(2)


def toe_acceleration(q_, dq_, ddq_, l, dl, ddl, params, leg):
    return np.array(
        _compiled()[("toe_a", leg)](
            _vec(q_, 7), _vec(dq_, 7), _vec(ddq_, 7), float(l), float(dl), float(ddl), _pvec(params)
        ),
        dtype=float,
    ).reshape(2)


def leg_normal(q_, leg):
    """Unit vector perpendicular to the leg axis, n = du/dg = (cos g, sin g)."""
    return np.array(_compiled()[("normal", leg)](_vec(q_, 7)), dtype=float).reshape(2)


def _pair(value):
    """(back, front) of a RobotParameters field: one value or a pair."""
    return tuple(value) if isinstance(value, (tuple, list)) else (value, value)


def params_from_robot(robot, gears=True):
    """Named parameter dict from a ``scoutsim.RobotParameters`` (read field by field,
    independently of ``scoutsim._core.model.packing``; a per-leg field given as a (back, front)
    pair gives each leg its value). ``gears=False`` zeroes J1, J2 and k_b."""
    out = {
        "m_t": robot.torso_mass,
        "I_t": robot.torso_inertia,
        "n_p": float(robot.legs_per_virtual_leg),
        "L": robot.hip_spacing / 2.0,
        "e": robot.com_offset,
        "g": robot.gravity,
    }
    fields = {
        "m_l": "leg_mass",
        "I_l": "leg_inertia",
        "d": "leg_com_distance",
        "J1": "drive_gear_inertia",
        "J2": "driven_gear_inertia",
        "k": "leg_stiffness",
        "l0": "leg_rest_length",
        "k_b": "belt_stiffness",
    }
    for leg, sfx in enumerate(LEG_SUFFIX):
        for name, field in fields.items():
            value = _pair(getattr(robot, field))[leg]
            out[name + sfx] = value if gears or name not in ("J1", "J2", "k_b") else 0.0
        out["N" + sfx] = _pair(robot.planetary_ratio)[leg] * _pair(robot.sprocket_ratio)[leg]
    return out


def main():
    import time

    t0 = time.perf_counter()
    M, h, Qg = symbolic_eom()
    t1 = time.perf_counter()
    print(f"# derivation: {t1 - t0:.2f} s")
    print("# q = [" + ", ".join(Q_NAMES) + "]")
    print("# mass matrix M(q) (upper triangle, simplified; M is symmetric)")
    for i in range(7):
        for j in range(i, 7):
            e = sp.trigsimp(sp.factor_terms(sp.expand(sp.expand_trig(M[i, j]))))
            e = sp.simplify(e)
            if e != 0:
                print(f"M[{Q_NAMES[i]}, {Q_NAMES[j]}] = {e}")
    print("# velocity-product vector h(q, dq)")
    for i in range(7):
        e = sp.simplify(h[i])
        print(f"h[{Q_NAMES[i]}] = {e}")
    print("# gravity generalized force -dV_grav/dq")
    for i in range(7):
        print(f"Qg[{Q_NAMES[i]}] = {sp.simplify(Qg[i])}")
    print(f"# total: {time.perf_counter() - t0:.2f} s")


if __name__ == "__main__":
    main()
