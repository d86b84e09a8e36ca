"""Sobol' sensitivity indices of a model's outputs to its uncertain inputs
(:mod:`scoutsim.analysis.uncertainty`): the sampling design and the estimator.

The first-order index ``S1_i`` is the share of an output's variance that input ``i``
causes by itself, ``Var(E[Y | X_i]) / Var(Y)``; the total index ``ST_i`` the share it
takes part in, alone or with others, ``E[Var(Y | X_~i)] / Var(Y)``. An input that does not
enter the model has ``ST_i = 0``; ``ST_i - S1_i`` is what it does through interactions.

Design (Saltelli 2002, 2010): two base samples A and B of ``n`` rows each, the two halves
of one scrambled, seeded Sobol' sequence (:class:`scipy.stats.qmc.Sobol`) of dimension
2d, and for each input i the matrix AB_i: A with column i taken from B. The model runs
on the ``n (d + 2)`` rows of A, B and every AB_i. ``n`` is the base sample size; a power
of two keeps the Sobol' points balanced.

Estimator: :func:`scipy.stats.sobol_indices` (method ``saltelli_2010``: first order by
Saltelli et al. 2010, total order by Jansen 1999, the formulas of Saltelli et al. 2010,
Table 2 (b) and (f)) on the evaluations given as ``f_A``, ``f_B``, ``f_AB``, so the
caller controls the sampling; the outputs are centred on their mean first. Confidence
intervals: its ``bootstrap()`` (BCa bootstrap over the n base rows, ``n_resamples``
resamples) at ``confidence_level``; the bootstrap draws from NumPy's global generator,
which is seeded for the call and then put back as it was, so the intervals are the
same on every run with the same seed. An output that does not vary (zero variance)
gets indices 0 (SciPy's rule); an input whose column does not change the output at all
gets ``S1 = ST = 0`` exactly, and a zero-width interval.

References: A. Saltelli et al., "Variance based sensitivity analysis of model output.
Design and estimator for the total sensitivity index", Comput. Phys. Commun. 181 (2010)
259-270; M. J. W. Jansen, "Analysis of variance designs for model output", Comput. Phys.
Commun. 117 (1999) 35-43.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy import stats
from scipy.stats import qmc

__all__ = [
    "CONFIDENCE_LEVEL",
    "N_RESAMPLES",
    "SobolIndices",
    "sobol_design",
    "sobol_from_evaluations",
    "sobol_indices",
    "design_rows",
]

#: confidence level of the intervals (two-sided)
CONFIDENCE_LEVEL = 0.95
#: bootstrap resamples of the intervals (SciPy's default)
N_RESAMPLES = 999


@dataclass(frozen=True)
class SobolIndices:
    """Sobol' indices of ``k`` outputs to ``d`` inputs, each an array (k, d): first order
    ``S1`` and total ``ST``, and the half-widths of their confidence intervals
    ``S1_conf`` / ``ST_conf`` (half of high - low of the bootstrap interval at
    ``confidence_level``; the interval itself is ``S1_low`` .. ``S1_high``)."""

    S1: np.ndarray
    ST: np.ndarray
    S1_low: np.ndarray
    S1_high: np.ndarray
    ST_low: np.ndarray
    ST_high: np.ndarray
    n: int
    confidence_level: float

    @property
    def S1_conf(self) -> np.ndarray:
        return 0.5 * (self.S1_high - self.S1_low)

    @property
    def ST_conf(self) -> np.ndarray:
        return 0.5 * (self.ST_high - self.ST_low)


def sobol_design(d: int, n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """The base samples ``(A, B)`` in the unit cube, each (n, d): the two halves of the
    first ``n`` points of a scrambled Sobol' sequence of dimension 2d seeded with
    ``seed`` (as :func:`scipy.stats.sobol_indices` draws them)."""
    if d < 1:
        raise ValueError(f"d = {d!r} is not allowed: at least one input")
    if not (isinstance(n, (int, np.integer)) and n >= 2):
        raise ValueError(f"n = {n!r} is not allowed: a whole number >= 2 (a power of two)")
    u = qmc.Sobol(2 * d, scramble=True, seed=np.random.default_rng(seed)).random(n)
    return u[:, :d], u[:, d:]


def design_rows(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Every row the model runs on, ((d + 2) n, d): A, then B, then AB_1 ... AB_d (AB_i:
    A with column i from B)."""
    n, d = A.shape
    rows = [A, B]
    for i in range(d):
        ab = A.copy()
        ab[:, i] = B[:, i]
        rows.append(ab)
    return np.vstack(rows)


def sobol_from_evaluations(
    values: np.ndarray,
    d: int,
    *,
    seed: int = 0,
    confidence_level: float = CONFIDENCE_LEVEL,
    n_resamples: int = N_RESAMPLES,
) -> SobolIndices:
    """Indices from the model's values on the rows of :func:`design_rows`.

    Parameters
    ----------
    values : array ((d + 2) n,) or ((d + 2) n, k): the outputs on the rows of A, B,
        AB_1 ... AB_d in that order; every value finite.
    d : number of inputs.
    seed : seeds the bootstrap of the intervals.
    confidence_level, n_resamples : of the bootstrap intervals.
    """
    y = np.asarray(values, dtype=float)
    y = y.reshape(len(y), -1)
    m, k = y.shape
    if m % (d + 2) or m < 2 * (d + 2):
        raise ValueError(
            f"values has {m} rows: must be n (d + 2) = n x {d + 2} rows, n >= 2 (design_rows)"
        )
    if not np.all(np.isfinite(y)):
        raise ValueError("values must all be finite: the estimator needs every row of A, B, AB")
    n = m // (d + 2)
    if d == 1 and k == 1:  # (SciPy squeezes one output of one input to a scalar)
        return _first_output(
            sobol_from_evaluations(
                np.hstack([y, y]),
                d,
                seed=seed,
                confidence_level=confidence_level,
                n_resamples=n_resamples,
            )
        )
    blocks = y.T.reshape(k, d + 2, n)  # (output, block, base row)
    func: dict[Literal["f_A", "f_B", "f_AB"], np.ndarray] = {
        "f_A": blocks[:, 0, :],
        "f_B": blocks[:, 1, :],
        "f_AB": np.moveaxis(blocks[:, 2:, :], 1, 0),  # (d, k, n)
    }
    res = stats.sobol_indices(func=func, n=n)
    saved = np.random.get_state()
    try:  # (the bootstrap draws from NumPy's global generator)
        np.random.seed(seed)
        with warnings.catch_warnings():  # (a degenerate interval: handled below)
            warnings.simplefilter("ignore", RuntimeWarning)
            warnings.simplefilter("ignore", stats.DegenerateDataWarning)
            boot = res.bootstrap(confidence_level=confidence_level, n_resamples=n_resamples)
    finally:
        np.random.set_state(saved)

    def shaped(a) -> np.ndarray:
        return np.asarray(a, dtype=float).reshape(k, d)

    s1, st = shaped(res.first_order), shaped(res.total_order)
    with np.errstate(invalid="ignore"):
        ci1, cit = boot.first_order.confidence_interval, boot.total_order.confidence_interval
        lo1, hi1, lot, hit = (shaped(ci1.low), shaped(ci1.high), shaped(cit.low), shaped(cit.high))
    # where BCa has no interval (NaN: a degenerate or skewed bootstrap distribution, e.g.
    # an input without effect, an output of few distinct values) the percentile interval
    # of the same bootstrap distribution; for an input without effect it is the point
    alpha = 0.5 * (1.0 - confidence_level)
    for lo, hi, dist in (
        (lo1, hi1, boot.first_order.bootstrap_distribution),
        (lot, hit, boot.total_order.bootstrap_distribution),
    ):
        with warnings.catch_warnings():  # (resamples without variance: NaN, left out)
            warnings.simplefilter("ignore", RuntimeWarning)
            q = np.nanquantile(
                np.asarray(dist, dtype=float).reshape(k, d, -1), [alpha, 1 - alpha], axis=-1
            )
        bad = ~(np.isfinite(lo) & np.isfinite(hi))
        lo[bad], hi[bad] = q[0][bad], q[1][bad]
    for lo, hi, v in ((lo1, hi1, s1), (lot, hit, st)):  # (no finite resample at all)
        still = ~(np.isfinite(lo) & np.isfinite(hi))
        lo[still], hi[still] = v[still], v[still]
    return SobolIndices(s1, st, lo1, hi1, lot, hit, n, confidence_level)


def _first_output(ix: SobolIndices) -> SobolIndices:
    arrays = {f: getattr(ix, f)[:1] for f in ("S1", "ST", "S1_low", "S1_high", "ST_low", "ST_high")}
    return SobolIndices(**arrays, n=ix.n, confidence_level=ix.confidence_level)


def sobol_indices(
    func,
    bounds,
    *,
    n: int = 1024,
    seed: int = 0,
    confidence_level: float = CONFIDENCE_LEVEL,
    n_resamples: int = N_RESAMPLES,
) -> SobolIndices:
    """First-order and total Sobol' indices of ``func`` over uniform inputs, with
    bootstrap confidence intervals (module docstring: design and estimator).

    Parameters
    ----------
    func : callable, (m, d) array of inputs -> (m,) or (m, k) outputs; called once, on
        the ``n (d + 2)`` rows of A, B and AB_1 ... AB_d.
    bounds : sequence of d ``(low, high)``: input i uniform on [low, high).
    n : base sample size (rows of A and of B), a power of two; ``n (d + 2)`` evaluations.
    seed : seeds the Sobol' sequence and the bootstrap.
    confidence_level : of the intervals (default 0.95).
    n_resamples : bootstrap resamples (default 999).

    Returns
    -------
    SobolIndices : arrays (k, d) (k = 1 for a (m,) output).
    """
    b = np.asarray(bounds, dtype=float).reshape(-1, 2)
    if not np.all(b[:, 0] < b[:, 1]):
        raise ValueError(f"bounds = {bounds!r} is not allowed: each low must be below its high")
    d = len(b)
    A, B = sobol_design(d, n, seed)
    x = qmc.scale(design_rows(A, B), b[:, 0], b[:, 1])
    values = np.asarray(func(x), dtype=float)
    if values.shape[0] != len(x):
        raise ValueError(f"func returned {values.shape[0]} rows for {len(x)} inputs")
    return sobol_from_evaluations(
        values, d, seed=seed, confidence_level=confidence_level, n_resamples=n_resamples
    )
