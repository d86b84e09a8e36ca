"""The uncertainty of the fit at the optimum: the residual variance, the Jacobian in
x = ln p, its singular directions checked against the real cost, and the covariance of x.

Uncertainty
-----------
At the optimum, with J the (weighted) Jacobian in x and s^2 = |r|^2 / (n - p) the residual
variance, cov(x) = s^2 (J^T J)^-1 (computed from the SVD of J; directions with singular
values below 1e-10 of the largest get infinite variance). The confidence interval of p is
``exp(x +- t_{n-p, (1+c)/2} sd(x))``: a linearised interval, honest when the errors are
independent and the model is locally linear over the interval (tested by coverage over
repeated noise draws, tests/identification).

Before the intervals are trusted, every singular direction v_k of J is checked against
the real cost: the linear model says a step t along v_k raises the cost by (S_k t)^2 / 2;
the cost is evaluated at the interval's ends x +- t_q s / S_k v_k, and a direction along
which it rises by less than ``flat_ratio`` (1/4) of that, or by more than 4 times, is
*undetermined* (infinite variance): the quadratic model behind the interval does not hold
there. This catches what finite differences alone cannot: a combination the model does
not depend on at all (with the torso clamped only J_2 + N^2 J_1 enters,
docs/specification.md section 5, a curved valley in ln J_1, ln J_2) still shows a small
nonzero singular value from the stencil's curvature, which would give a false interval;
along the straight singular direction the cost then rises thousands of times faster than
predicted, because the valley curves away from it.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from scipy import stats

from .parameter_vector import SearchBox

__all__ = ["Optimum", "Spread", "optimum", "jacobian", "flat_directions", "covariance", "spread"]


class Optimum(NamedTuple):
    """The best fit and its residual statistics."""

    x: np.ndarray  # (p,) ln p at the optimum
    r: np.ndarray  # weighted residuals there [-]
    s2: float  # residual variance s^2 = |r|^2 / (n - p) [-]
    cost: float  # |r|^2 / 2 [-]
    zq: float  # Student-t quantile t_{n-p, (1+c)/2} of the intervals


class Spread(NamedTuple):
    """The uncertainty of x = ln p at the optimum."""

    S: np.ndarray  # (k,) singular values of the weighted Jacobian
    Vt: np.ndarray  # (k, p) its right singular vectors (rows)
    flat: np.ndarray  # (k,) bool: the direction is undetermined
    ratios: list  # cost rise over the interval / linear prediction, per direction
    cov_det: np.ndarray  # (p, p) covariance of x from the determined directions only
    cov: np.ndarray  # (p, p) covariance, inf where a flat direction reaches
    spans: dict  # flat direction index -> its length across the search box [ln p]
    sd: np.ndarray  # (p,) standard deviation of x
    corr: np.ndarray  # (p, p) correlation of x


def optimum(residuals, x, nres: int, p: int, confidence: float) -> Optimum:
    """Residuals, residual variance, cost and interval quantile at ``x`` (``nres``
    residuals, ``p`` parameters, intervals of level ``confidence``)."""
    r = residuals(x)
    dof = max(nres - p, 1)
    s2 = float(r @ r) / dof
    c_opt = 0.5 * float(r @ r)
    zq = float(stats.t.ppf(0.5 + 0.5 * confidence, dof))
    return Optimum(x, r, s2, c_opt, zq)


def jacobian(residuals, x, sb: SearchBox, jac_step: float) -> np.ndarray:
    """Jacobian of the residuals at ``x`` by central differences (step ``jac_step`` in
    ln p, kept inside the box by shifting the stencil)."""
    xlo, xhi = sb.xlo, sb.xhi
    cols = []
    for i in range(len(sb.names)):
        h = jac_step
        xp = x.copy()
        xm = x.copy()
        xp[i] = min(x[i] + h, xhi[i])
        xm[i] = max(xp[i] - 2 * h, xlo[i])
        cols.append((residuals(xp) - residuals(xm)) / (xp[i] - xm[i]))
    return np.column_stack(cols)


def flat_directions(residuals, opt: Optimum, sb: SearchBox, S, Vt, flat_ratio: float):
    """(flat, ratios): the curvature check of every singular direction. The linear model
    says that moving t along the singular vector v_k raises the cost by (S_k t)^2 / 2; a
    direction along which the cost rises far less over the interval is flat (the data do
    not determine it, however large S_k looked) and gets infinite variance."""
    x, s2, c_opt, zq = opt.x, opt.s2, opt.cost, opt.zq
    xlo, xhi = sb.xlo, sb.xhi
    tol = 1e-10 * (S[0] if S.size else 0.0)
    flat = np.zeros(S.size, dtype=bool)
    ratios = []
    for k in range(S.size):
        if S[k] <= tol:
            flat[k] = True
            ratios.append(0.0)
            continue
        w = zq * math.sqrt(s2) / S[k]
        acts, preds = [], []
        for sgn in (1.0, -1.0):
            xt = np.clip(x + sgn * w * Vt[k], xlo, xhi)
            t = float(np.dot(xt - x, Vt[k]))
            if abs(t) < 1e-12:
                continue
            rt = residuals(xt)
            acts.append(0.5 * float(rt @ rt) - c_opt)
            preds.append(0.5 * (S[k] * t) ** 2)
        rho = (sum(acts) / sum(preds)) if preds else 0.0
        ratios.append(rho)
        if rho < flat_ratio or rho > 1.0 / flat_ratio:
            flat[k] = True
    return flat, ratios


def covariance(opt: Optimum, sb: SearchBox, S, Vt, flat):
    """(cov_det, cov, spans): the covariance of x from the determined directions,
    s^2 V diag(1 / S^2) V^T, and the same with every parameter a flat direction involves
    made undetermined (inf), with the length of each flat direction across the box."""
    x, s2, zq = opt.x, opt.s2, opt.zq
    xlo, xhi = sb.xlo, sb.xhi
    inv = np.where(flat, np.inf, 1.0 / np.where(flat, 1.0, S) ** 2)
    with np.errstate(invalid="ignore"):
        cov_det = np.einsum("ik,k,jk->ij", Vt.T, np.where(flat, 0.0, inv), Vt.T) * s2
        cov = cov_det.copy()
        # a flat direction makes every parameter it involves undetermined: followed
        # across the search box it moves parameter i by |v_ki| D_k; if that exceeds the
        # parameter's own half-width, the interval would only hold conditionally
        half_det = zq * np.sqrt(np.clip(np.diag(cov_det), 0.0, np.inf))
        spans = {}
        for k in np.flatnonzero(flat):
            v = Vt[k]
            with np.errstate(divide="ignore", invalid="ignore"):
                tmax = np.where(v > 0, (xhi - x) / v, np.where(v < 0, (xlo - x) / v, np.inf))
                tmin = np.where(v > 0, (xlo - x) / v, np.where(v < 0, (xhi - x) / v, -np.inf))
            D = float(np.min(tmax) - np.max(tmin))
            spans[int(k)] = D
            touched = (np.abs(v) > 0.05) | (np.abs(v) * D > half_det)
            cov[np.ix_(touched, touched)] = np.inf
    return cov_det, cov, spans


def spread(residuals, opt: Optimum, sb: SearchBox, jac_step: float, flat_ratio: float) -> Spread:
    """The uncertainty of x at the optimum: Jacobian (:func:`jacobian`), its SVD, the
    curvature check (:func:`flat_directions`), the covariance (:func:`covariance`),
    standard deviations and correlations."""
    J = jacobian(residuals, opt.x, sb, jac_step)
    U, S, Vt = np.linalg.svd(J, full_matrices=False)
    flat, ratios = flat_directions(residuals, opt, sb, S, Vt, flat_ratio)
    cov_det, cov, spans = covariance(opt, sb, S, Vt, flat)
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, np.inf))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(sd, sd)
    return Spread(S, Vt, flat, ratios, cov_det, cov, spans, sd, corr)
