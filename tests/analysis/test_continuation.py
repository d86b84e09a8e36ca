"""Pseudo-arclength continuation (scoutsim.analysis.continuation) on curves known in closed
form, and the names it gives to multipliers crossing the unit circle."""

import numpy as np
import pytest

from scoutsim.analysis.continuation import (
    ContinuationSettings,
    crossing_kind,
    locate_crossing,
    pseudo_arclength,
)


def _parabola(w):
    """r(u, lam) = u^2 - lam: lam has a fold (a minimum) at u = 0."""
    u, lam = w
    return np.array([u * u - lam]), np.array([[2.0 * u, -1.0]])


def test_continuation_turns_round_a_fold():
    """Stepping lam could not pass lam = 0 on lam = u^2; the arclength does, and every
    point lies on the curve."""
    steps, why = pseudo_arclength(
        _parabola, [-1.0, 1.0], parameter_range=(-1.0, 2.0), direction=-1.0,
        settings=ContinuationSettings(step=0.05, max_step=0.1),
    )  # fmt: skip
    assert why == "range"
    u = np.array([s.w[0] for s in steps])
    lam = np.array([s.parameter for s in steps])
    np.testing.assert_allclose(lam, u * u, atol=1e-11)
    assert u[0] == pytest.approx(-1.0) and u[-1] == pytest.approx(np.sqrt(2.0), abs=1e-9)
    assert lam[-1] == pytest.approx(2.0, abs=1e-12)  # the last point lands on the bound
    turns = np.sign([s.tangent[1] for s in steps])
    assert turns[0] < 0 < turns[-1]  # the parameter falls, then rises: the fold is passed


def test_overdetermined_consistent_residual_is_followed():
    """Two equations of rank one (the second a multiple of the first) in (u, lam), as the
    passive orbit's four residuals in two angles: the least-squares corrector follows the
    curve u = lam^3."""

    def r(w):
        u, lam = w
        f = u - lam**3
        return np.array([f, 2.0 * f]), np.array([[1.0, -3 * lam**2], [2.0, -6 * lam**2]])

    steps, why = pseudo_arclength(r, [0.0, 0.0], parameter_range=(0.0, 1.0))
    assert why == "range"
    for s in steps:
        assert abs(s.w[0] - s.w[1] ** 3) < 1e-11


def test_lost_branch_says_where():
    def r(w):
        if w[1] > 0.5:
            raise ArithmeticError("no solution here")
        return np.array([w[0] - w[1]]), np.array([[1.0, -1.0]])

    steps, why = pseudo_arclength(r, [0.0, 0.0], parameter_range=(0.0, 1.0))
    assert why.startswith("lost:") and f"parameter {steps[-1].parameter:.6g}" in why
    assert 0.49 < steps[-1].parameter <= 0.5


@pytest.mark.parametrize(
    "before, after, turns, kind",
    [
        ([0.5, 0.9 + 0.3j, 0.9 - 0.3j], [0.5, 1.0 + 0.3j, 1.0 - 0.3j], False, "torus"),
        ([-0.9, 0.5], [-1.1, 0.5], False, "period doubling"),
        ([0.9, 0.5], [1.1, 0.5], False, "branch point"),
        ([0.9, 0.5], [1.1, 0.5], True, "fold"),
        ([1.1, 0.5], [0.9, 0.5], False, "branch point"),
        ([0.9, 0.5], [0.95, 0.5], False, ""),
        # the energy multiplier 1 left out: the pair alone decides
        ([1.0, 1.2, 0.3], [1.0, 0.9, 0.3], False, "branch point"),
    ],
)
def test_crossing_kind_names_what_crossed_the_unit_circle(before, after, turns, kind):
    trivial = 1 if len(before) == 3 and before[0] == 1.0 else 0
    assert crossing_kind(before, after, trivial=trivial, parameter_turns=turns) == kind


def test_locate_crossing_finds_the_parameter_where_a_multiplier_is_one():
    """On the branch u = lam with the multiplier exp(u - 0.3), the crossing of the unit
    circle is at lam = 0.3."""

    def r(w):
        return np.array([w[0] - w[1]]), np.array([[1.0, -1.0]])

    steps, _ = pseudo_arclength(r, [0.0, 0.0], parameter_range=(0.0, 1.0))
    mult = lambda w: np.array([np.exp(w[0] - 0.3)])  # noqa: E731
    k = next(i for i, s in enumerate(steps) if s.w[0] > 0.3)
    got = locate_crossing(r, steps[k - 1], steps[k], mult)
    assert got is not None
    before, after = got
    assert before.parameter < 0.3 <= after.parameter
    assert after.parameter == pytest.approx(0.3, abs=1e-8)


def test_two_crossings_between_the_same_neighbours_are_both_found():
    """A complex pair entering the unit circle at lam = 0.3 and, after meeting on the real
    axis, one of them leaving it through +1 at lam = 0.345, between two neighbours 0.2 and
    0.5: both are located and named."""
    from scoutsim.analysis.continuation import BranchStep, crossings_between

    def r(w):
        return np.array([w[0] - w[1]]), np.array([[1.0, -1.0]])

    def mult(w):
        lam = w[1]
        if lam < 0.33:  # a complex pair of modulus 1.3 - lam
            m = 1.3 - lam
            return np.array([m * np.exp(0.2j), m * np.exp(-0.2j)])
        return np.array([0.97 + 2.0 * (lam - 0.33), 0.5 + 0j])

    t = np.array([1.0, 1.0]) / np.sqrt(2.0)
    before = BranchStep(np.array([0.2, 0.2]), t, 0.0, 0)
    after = BranchStep(np.array([0.5, 0.5]), t, 0.0, 0)
    found = crossings_between(r, before, after, mult)
    assert [k for k, _ in found] == ["torus", "branch point"]
    assert found[0][1].parameter == pytest.approx(0.3, abs=1e-8)
    assert found[1][1].parameter == pytest.approx(0.345, abs=1e-8)


def test_locate_fold_finds_the_turn_of_the_parameter():
    """On lam = u^2 the parameter turns at u = 0: located between the two points either
    side, where no multiplier is involved."""
    from scoutsim.analysis.continuation import locate_fold

    steps, _ = pseudo_arclength(
        _parabola, [-1.0, 1.0], parameter_range=(-1.0, 2.0), direction=-1.0,
        settings=ContinuationSettings(step=0.05, max_step=0.1),
    )  # fmt: skip
    k = next(i for i, s in enumerate(steps) if s.tangent[1] > 0)
    fold = locate_fold(_parabola, steps[k - 1], steps[k])
    assert fold is not None
    assert fold.w[0] == pytest.approx(0.0, abs=1e-6) and fold.parameter == pytest.approx(
        0.0, abs=1e-11
    )
    assert locate_fold(_parabola, steps[0], steps[1]) is None  # no turn between these
