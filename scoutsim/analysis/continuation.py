"""Pseudo-arclength continuation of a solution branch ``r(u, lam) = 0`` in one parameter,
and the test functions that name what happens to a periodic orbit's multipliers along it.

The branch is a curve in (u, lam). From a point on it the next is predicted along the
curve's tangent (the null vector of ``[dr/du, dr/dlam]``) by a step ``h`` of arclength and
corrected by Gauss-Newton on ``r = 0`` together with the arclength condition
``t . (w - w_predicted) = 0`` (Keller 1977; Allgower and Georg, "Introduction to numerical
continuation methods", 2003, ch. 2). Unlike stepping the parameter (natural-parameter
continuation) it turns round a fold, where the parameter reaches an extreme and the
branch comes back. The residual may have more components than unknowns as long as it is
consistent (a conservative orbit's four apex residuals in two touchdown angles): the
correction is then the least-squares step, which converges quadratically on a zero
residual. The step is halved when the corrector fails and grown when it converges fast.

Along a branch of periodic orbits, :func:`crossing_kind` names a change in the number of
multipliers outside the unit circle between two neighbours: a real multiplier through +1
(a fold or branch point), through -1 (a period doubling) or a complex pair (a torus,
Neimark-Sacker, bifurcation); :func:`locate_crossing` finds where by bisection along the
arclength, and :func:`crossings_between` finds each of several crossings between the same
two neighbours in turn. :func:`locate_fold` finds where the parameter turns (a fold),
whatever the multipliers do there.

Units: those of u and lam (the arclength mixes them; scale them to comparable sizes).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = [
    "BranchStep",
    "ContinuationSettings",
    "pseudo_arclength",
    "correct",
    "crossing_kind",
    "locate_crossing",
    "crossings_between",
    "locate_fold",
    "multipliers_outside",
]

#: r(w) -> (residual (m,), Jacobian (m, n + 1)) at w = (u, lam); raises to say "no point".
Residual = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class ContinuationSettings:
    """Steps and tolerances of :func:`pseudo_arclength`.

    step : first arclength step; min_step, max_step : its bounds (the branch is given up
        when a step below ``min_step`` does not converge).
    tol : the corrector stops when max |r| < tol.
    max_iter : corrector iterations per step.
    max_points : points computed at most.
    """

    step: float = 0.05
    min_step: float = 1e-5
    max_step: float = 0.2
    tol: float = 1e-11
    max_iter: int = 8
    max_points: int = 400

    def __post_init__(self) -> None:
        for name in ("step", "min_step", "max_step", "tol"):
            if not getattr(self, name) > 0.0:
                raise ValueError(f"{name} = {getattr(self, name)}: must be > 0")
        if not self.min_step <= self.step <= self.max_step:
            raise ValueError(
                f"step = {self.step}: must lie in [min_step, max_step] = "
                f"[{self.min_step}, {self.max_step}]"
            )


@dataclass(frozen=True)
class BranchStep:
    """A point of the branch: ``w = (u, lam)``, the unit tangent there (oriented along the
    direction of travel), the corrector's residual and iterations."""

    w: np.ndarray
    tangent: np.ndarray
    residual: float
    iterations: int

    @property
    def parameter(self) -> float:
        return float(self.w[-1])


def _null_vector(J: np.ndarray) -> np.ndarray:
    """Unit vector spanning the null space of J (m, n + 1) of rank n: the last right
    singular vector."""
    _, _, vt = np.linalg.svd(J)
    return vt[-1]


def correct(residual: Residual, w_pred, tangent, tol: float, max_iter: int):
    """Gauss-Newton on ``r(w) = 0`` and ``tangent . (w - w_pred) = 0`` from ``w_pred``.
    Returns (w, Jacobian there, max |r|, iterations), or None if it does not converge
    (or ``residual`` raises)."""
    w = np.array(w_pred, dtype=float)
    t = np.asarray(tangent, dtype=float)
    for it in range(max_iter + 1):
        try:
            r, J = residual(w)
        except (ArithmeticError, RuntimeError, ValueError):
            return None
        res = float(np.max(np.abs(r)))
        if not np.isfinite(res):
            return None
        if res < tol:
            return w, J, res, it
        if it == max_iter:
            return None
        A = np.vstack((J, t))
        b = -np.concatenate((r, [t @ (w - w_pred)]))
        w = w + np.linalg.lstsq(A, b, rcond=None)[0]
    return None


def pseudo_arclength(
    residual: Residual,
    w0,
    *,
    parameter_range: tuple[float, float],
    direction: float = 1.0,
    settings: ContinuationSettings | None = None,
    progress: Callable[[BranchStep], None] | None = None,
) -> tuple[list[BranchStep], str]:
    """Follow the branch through the point ``w0 = (u0, lam0)`` (a solution: corrected
    first with lam fixed) in the direction where lam grows (``direction`` +1) or falls
    (-1), until lam leaves ``parameter_range`` (the last point is corrected onto the
    bound), the corrector fails at the smallest step, or ``max_points``.

    Returns (the points, why it stopped: "range", "lost: ..." or "max_points").
    """
    s = settings or ContinuationSettings()
    lo, hi = parameter_range
    w0 = np.asarray(w0, dtype=float)
    e_lam = np.zeros(len(w0))
    e_lam[-1] = 1.0
    first = correct(residual, w0, e_lam, s.tol, s.max_iter + 4)
    if first is None:
        return [], f"lost: no solution at the start, {_param_text(w0[-1])}"
    w, J, res, it = first
    t = _null_vector(J)
    if t[-1] * direction < 0:
        t = -t
    points = [BranchStep(w, t, res, it)]
    if progress:
        progress(points[-1])
    h = s.step
    while len(points) < s.max_points:
        step = correct(residual, w + h * t, t, s.tol, s.max_iter)
        if step is None:
            h *= 0.5
            if h < s.min_step:
                return (
                    points,
                    f"lost: the corrector failed at the smallest step, {_param_text(w[-1])}",
                )
            continue
        w_new, J, res, it = step
        t_new = _null_vector(J)
        if t_new @ t < 0:
            t_new = -t_new
        lam = w_new[-1]
        if not lo <= lam <= hi:
            bound = hi if lam > hi else lo
            frac = (bound - w[-1]) / (lam - w[-1])
            pred = w + frac * (w_new - w)
            pred[-1] = bound  # the corrector keeps the parameter where the prediction has it
            end = correct(residual, pred, e_lam, s.tol, s.max_iter + 4)
            if end is not None:
                points.append(BranchStep(end[0], _oriented(end[1], t), end[2], end[3]))
                if progress:
                    progress(points[-1])
            return points, "range"
        w, t = w_new, t_new
        points.append(BranchStep(w, t, res, it))
        if progress:
            progress(points[-1])
        if it <= 3:
            h = min(1.5 * h, s.max_step)
    return points, "max_points"


def _oriented(J, t):
    v = _null_vector(J)
    return v if v @ t >= 0 else -v


def _param_text(lam: float) -> str:
    return f"parameter {lam:.6g}"


def multipliers_outside(multipliers, trivial: int = 0) -> np.ndarray:
    """The multipliers with the ``trivial`` ones nearest +1 removed (a conservative
    orbit's energy multiplier), sorted by decreasing modulus."""
    m = np.asarray(multipliers, dtype=complex)
    keep = list(m)
    for _ in range(trivial):
        keep.pop(int(np.argmin(np.abs(np.asarray(keep) - 1.0))))
    keep_arr = np.asarray(keep)
    return keep_arr[np.argsort(-np.abs(keep_arr), kind="stable")]


def crossing_kind(
    before,
    after,
    trivial: int = 0,
    parameter_turns: bool = False,
    imaginary_tol: float = 1e-5,
) -> str:
    """What crossed the unit circle between the multipliers ``before`` and ``after`` of two
    neighbouring orbits of a branch ("" if the number outside it did not change):

    * a real multiplier through +1: "fold" if the branch's parameter turns there
      (``parameter_turns``: the tangent's parameter component changes sign), otherwise
      "branch point" (another branch crosses this one, e.g. a symmetry-breaking
      pitchfork);
    * through -1: "period doubling";
    * a complex pair: "torus" (Neimark-Sacker).

    ``trivial`` multipliers nearest +1 are left out (1 for the energy multiplier of a
    conservative orbit). A multiplier counts as complex when its imaginary part exceeds
    ``imaginary_tol`` times its modulus: next to a double multiplier (a crossing at +1 that
    meets the energy multiplier) the computed eigenvalues split by about the square root of
    the Jacobian's error (1e-6 for 1e-12), which must not read as a complex pair."""
    b = multipliers_outside(before, trivial)
    a = multipliers_outside(after, trivial)
    out_b, out_a = int(np.sum(np.abs(b) > 1.0)), int(np.sum(np.abs(a) > 1.0))
    if out_a == out_b:
        return ""
    lam = a if out_a > out_b else b
    m = lam[int(np.argmin(np.abs(np.abs(lam) - 1.0)))]
    if abs(m.imag) > imaginary_tol * max(1.0, abs(m)):
        return "torus"
    if m.real < 0:
        return "period doubling"
    return "fold" if parameter_turns else "branch point"


def _bisect_chord(residual, before, after, same_side, tol, max_iter, bisections):
    """Bisection of the chord from ``before`` to ``after`` on the predicate
    ``same_side(point)`` (true on ``before``'s side), each trial point corrected onto the
    branch perpendicular to the chord: the last points found on either side, or None if a
    trial point cannot be corrected."""
    chord = after.w - before.w
    normal = chord / np.linalg.norm(chord)
    a, b, side_a, side_b = 0.0, 1.0, before, after
    for _ in range(bisections):
        mid = 0.5 * (a + b)
        got = correct(residual, before.w + mid * chord, normal, tol, max_iter)
        if got is None:
            return None
        w, J, res, it = got
        point = BranchStep(w, _oriented(J, before.tangent), res, it)
        if same_side(point):
            a, side_a = mid, point
        else:
            b, side_b = mid, point
    return side_a, side_b


def locate_crossing(
    residual: Residual,
    before: BranchStep,
    after: BranchStep,
    multipliers: Callable[[np.ndarray], np.ndarray],
    *,
    trivial: int = 0,
    tol: float = 1e-11,
    max_iter: int = 8,
    bisections: int = 30,
) -> tuple[BranchStep, BranchStep] | None:
    """Where, between ``before`` and ``after``, the number of multipliers outside the unit
    circle first changes from its value at ``before``: bisection of the chord between them,
    each trial point corrected onto the branch perpendicular to the chord.
    ``multipliers(w)`` gives the multipliers at a point of the branch. Returns the two
    branch points either side of the change (within 2^-bisections of the chord), or None
    if a trial point cannot be corrected."""
    n_b = _count(multipliers(before.w), trivial)
    return _bisect_chord(
        residual,
        before,
        after,
        lambda point: _count(multipliers(point.w), trivial) == n_b,
        tol,
        max_iter,
        bisections,
    )


def crossings_between(
    residual: Residual,
    before: BranchStep,
    after: BranchStep,
    multipliers: Callable[[np.ndarray], np.ndarray],
    *,
    trivial: int = 0,
    most: int = 6,
) -> list[tuple[str, BranchStep]]:
    """Every change of the number of multipliers outside the unit circle between two
    neighbouring points, in order along the branch, each located
    (:func:`locate_crossing`) and named from the multipliers on its two sides
    (:func:`crossing_kind`): [(kind, the point just past it), ...]. Several crossings
    between the same neighbours (a complex pair entering the circle and one of the pair
    leaving it on the real axis a moment later) are found one after the other, up to
    ``most``; crossings that cancel in number between the neighbours are not seen (the
    step bounds that)."""
    out: list[tuple[str, BranchStep]] = []
    n_after = _count(multipliers(after.w), trivial)
    lo = before
    for _ in range(most):
        if _count(multipliers(lo.w), trivial) == n_after:
            break
        got = locate_crossing(residual, lo, after, multipliers, trivial=trivial)
        if got is None:
            break
        side_a, side_b = got
        kind = crossing_kind(
            multipliers(side_a.w),
            multipliers(side_b.w),
            trivial=trivial,
            parameter_turns=side_a.tangent[-1] * side_b.tangent[-1] < 0,
        )
        out.append((kind, side_b))
        lo = side_b
    return out


def locate_fold(
    residual: Residual,
    before: BranchStep,
    after: BranchStep,
    *,
    tol: float = 1e-11,
    max_iter: int = 8,
    bisections: int = 30,
) -> BranchStep | None:
    """The turning point of the parameter between two neighbours whose tangents' parameter
    components have opposite signs (a fold: the branch comes back), by bisection of the
    chord on that sign. Returns the point nearest the turn (the one of the last two whose
    tangent's parameter component is smaller in size), or None if the signs agree or a
    trial point cannot be corrected."""
    if before.tangent[-1] * after.tangent[-1] >= 0:
        return None
    sides = _bisect_chord(
        residual,
        before,
        after,
        lambda point: point.tangent[-1] * before.tangent[-1] > 0,
        tol,
        max_iter,
        bisections,
    )
    if sides is None:
        return None
    return min(sides, key=lambda point: abs(point.tangent[-1]))


def _count(multipliers, trivial: int) -> int:
    return int(np.sum(np.abs(multipliers_outside(multipliers, trivial)) > 1.0))
