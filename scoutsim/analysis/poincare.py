"""Poincaré analysis shared by the passive and the controlled orbits
(:mod:`scoutsim.analysis.orbits`): the error of a return map that is not defined at a
point, the central-difference Jacobian of a map, and the Floquet multipliers of a fixed
point (eigenvalues of the linearised map; < 1 in modulus: the orbit is stable).

Units: those of the map's section coordinates (SI, angles in rad); multipliers are
dimensionless.
"""

from __future__ import annotations

import numpy as np

__all__ = ["MapError", "fd_jacobian", "floquet_multipliers"]


class MapError(RuntimeError):
    """The return map is not defined here (fall, no stance, no apex in double flight)."""


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
