"""The family of passive bounding orbits in the apex pitch rate
(scoutsim.analysis.passive_family): it passes through the orbits docs/orbits.md tabulates,
and the crossings it reports are where the multipliers say."""

import math

import numpy as np
import pytest

from scoutsim.analysis.continuation import correct
from scoutsim.analysis.passive_family import passive_family
from scoutsim.analysis.passive_orbits import passive_bounding_orbit


@pytest.fixture(scope="module")
def family():
    return passive_family(1.3, 0.35, (math.radians(40.0), math.radians(160.0)))


def test_branch_covers_the_range(family):
    assert family.stopped == "range"
    p = [r["pitch_rate_deg"] for r in family.rows if not r["bifurcation"]]
    assert p[0] == pytest.approx(40.0, abs=1e-9) and p[-1] == pytest.approx(160.0, abs=1e-9)
    assert np.all(np.diff(p) > 0)  # no fold in this range: the pitch rate only grows


@pytest.mark.parametrize("w_deg", [50.0, 100.0, 150.0])
def test_branch_passes_through_the_documented_orbits(family, w_deg):
    """Between its neighbouring points the branch's touchdown angles bracket the orbit
    solved at that pitch rate by Levenberg-Marquardt (passive_bounding_orbit), within the
    linear-interpolation error."""
    orb = passive_bounding_orbit(1.3, 0.35, math.radians(w_deg))
    rows = [r for r in family.rows if not r["bifurcation"]]
    p = np.array([r["pitch_rate_deg"] for r in rows])
    for key, k in (("touchdown_angle_back_deg", 0), ("touchdown_angle_front_deg", 1)):
        interp = np.interp(w_deg, p, [r[key] for r in rows])
        assert interp == pytest.approx(math.degrees(orb.touchdown_angles[k]), abs=0.05)


def test_torus_crossing_is_where_the_complex_pair_has_modulus_one(family):
    torus = [r for r in family.bifurcations if r["bifurcation"] == "torus"]
    assert len(torus) == 1
    row = torus[0]
    pair = [complex(*m) for m in row["multipliers"] if abs(m[1]) > 1e-9]
    assert len(pair) == 2
    assert abs(abs(pair[0]) - 1.0) < 1e-6
    # independently: the orbits solved 0.5 deg/s either side have the pair inside, outside
    w = row["pitch_rate_deg"]
    for dw, inside in ((-0.5, True), (0.5, False)):
        m = passive_bounding_orbit(1.3, 0.35, math.radians(w + dw)).multipliers
        pair = [x for x in m if abs(x.imag) > 1e-9]
        assert (abs(pair[0]) < 1.0) == inside


def test_branch_point_is_a_real_multiplier_at_one_without_a_turn(family):
    """Below the torus a real multiplier passes +1 while the pitch rate keeps growing: a
    branch point, not a fold. There it meets the energy multiplier: a double multiplier +1
    whose computed eigenvalues carry errors of order sqrt(Jacobian error) ~ 1e-6, hence
    the 1e-5."""
    bp = [r for r in family.bifurcations if r["bifurcation"] == "branch point"]
    assert len(bp) == 1
    m = np.array([complex(*x) for x in bp[0]["multipliers"]])
    assert np.min(np.abs(m - 1.0)) < 1e-5
    assert not any(r["bifurcation"] == "fold" for r in family.rows)
    # independently: 0.5 deg/s either side, one more / one fewer multiplier above 1
    w = bp[0]["pitch_rate_deg"]
    above = []
    for dw in (-0.5, 0.5):
        m = passive_bounding_orbit(1.3, 0.35, math.radians(w + dw)).multipliers
        m = np.delete(m, np.argmin(np.abs(m - 1.0)))  # the energy multiplier
        above.append(int(np.sum(np.abs(m) > 1.0)))
    assert above == [2, 1]


def test_rows_are_orbits(family):
    """Each row is a fixed point of the apex map: the corrector started at it with the
    pitch rate fixed does not move it."""
    from scoutsim.analysis.passive_family import _residual
    from scoutsim.analysis.passive_reference import passive_robot

    residual = _residual(1.3, 0.35, passive_robot(), 1e-12, {})
    for r in family.rows[::7]:
        w = np.array([*np.radians([r["touchdown_angle_back_deg"], r["touchdown_angle_front_deg"]]),
                      math.radians(r["pitch_rate_deg"])])  # fmt: skip
        got = correct(residual, w, np.array([0.0, 0.0, 1.0]), 1e-11, 4)
        assert got is not None and got[3] <= 1
        assert np.max(np.abs(got[0] - w)) < 1e-9
