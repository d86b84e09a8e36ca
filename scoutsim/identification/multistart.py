"""The search for the best fit. Stick/slip makes the cost rough, so it starts globally:
scrambled-Sobol points in the search box (``scipy.stats.qmc``), the starting robot's
values and an optional given start are evaluated, the ``n_local`` best are refined by
weighted nonlinear least squares (``scipy.optimize.least_squares``, trust-region
reflective, in ln p), and the best optimum is polished by one more local fit.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy import optimize
from scipy.stats import qmc

from ..parameters import RobotParameters
from .parameter_vector import SearchBox

__all__ = ["start_points", "score_starts", "starts_table", "refine"]


def start_points(
    base: RobotParameters, sb: SearchBox, start: dict | None, n_starts: int, seed: int
) -> list:
    """(label, x) of every start: the starting robot's values (clipped to the box; the
    box's centre for a value of 0), ``start`` {name: value [SI]} if given, and ``n_starts``
    points of a scrambled Sobol sequence (``seed``) in the box."""
    names, box, xlo, xhi = sb
    p = len(names)
    cands = []
    x_nom = np.clip(
        [
            math.log(v) if v > 0 else 0.5 * (a + b)
            for v, (a, b) in zip((float(getattr(base, n)) for n in names), box)
        ],
        xlo,
        xhi,
    )
    cands.append(("start robot", np.array(x_nom, dtype=float)))
    if start:
        xs = np.array([math.log(float(start.get(n, math.exp(x)))) for n, x in zip(names, x_nom)])
        cands.append(("given start", np.clip(xs, xlo, xhi)))
    if n_starts > 0:
        m = int(math.ceil(math.log2(max(n_starts, 1))))
        pts = qmc.Sobol(d=p, scramble=True, seed=seed).random_base2(m)[:n_starts]
        for k, u in enumerate(pts):
            cands.append((f"sobol {k + 1}", xlo + u * (xhi - xlo)))
    return cands


def score_starts(residuals, cands: list, progress=None) -> list:
    """(cost, label, x) of every start, cheapest first; cost = |r|^2 / 2."""
    scored = []
    for label, x in cands:
        r = residuals(x)
        scored.append((0.5 * float(r @ r), label, x))
        if progress:
            progress(f"start {label}: cost {scored[-1][0]:.4g}")
    scored.sort(key=lambda e: e[0])
    return scored


def starts_table(scored: list, names: list) -> list:
    """The starts as dicts (label, cost, parameter values [SI]) for the report."""
    return [
        {"label": lbl, "cost": c, "x": {n: float(math.exp(v)) for n, v in zip(names, x)}}
        for c, lbl, x in scored
    ]


def refine(residuals, scored: list, starts_info: list, sb: SearchBox, settings, progress=None):
    """The best least-squares optimum (``scipy.optimize.OptimizeResult``) from the
    ``settings.n_local`` cheapest starts (each one's refined cost noted in
    ``starts_info``), polished by one more local fit from it."""
    xlo, xhi = sb.xlo, sb.xhi
    diff_step, max_nfev = settings.diff_step, settings.max_nfev
    jac: Any = residuals.jacobian if settings.jacobian == "exact" else "2-point"
    best = None
    for c0, label, x0 in scored[: max(1, settings.n_local)]:
        sol = optimize.least_squares(
            residuals,
            x0,
            bounds=(xlo, xhi),
            method="trf",
            x_scale=1.0,
            diff_step=diff_step,
            jac=jac,
            max_nfev=max_nfev,
        )
        for si in starts_info:
            if si["label"] == label:
                si["refined_cost"] = float(sol.cost)
        if progress:
            progress(f"refined {label}: cost {c0:.4g} -> {sol.cost:.4g} ({sol.nfev} evaluations)")
        if best is None or sol.cost < best.cost:
            best = sol
    if best is None:
        raise ValueError("scored is empty: refine needs at least one start")
    # polish: one more local fit from the best optimum with a fresh trust region (a
    # stick/slip kink can stall trf's trust region before the minimum)
    sol = optimize.least_squares(
        residuals,
        best.x,
        bounds=(xlo, xhi),
        method="trf",
        x_scale=1.0,
        diff_step=diff_step,
        jac=jac,
        max_nfev=max_nfev,
    )
    if progress:
        progress(f"polished: cost {best.cost:.4g} -> {sol.cost:.4g}")
    if sol.cost < best.cost:
        best = sol
    return best
