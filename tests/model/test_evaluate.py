"""The allocation-free evaluation (model.evaluate.evaluate_ws) reproduces the reference
implementation (tests/model/reference_evaluator.py), and its stiff-Jacobian factors capture the
belt-damper eigenvalues of Model II."""

import math

import numpy as np
import pytest

import scoutsim
from scoutsim import InitialState, RobotParameters
from scoutsim.model import evaluate as D
from scoutsim.model import workspace as W
from scoutsim.model import layout as L
from scoutsim.model.packing import robot_array

from .reference_evaluator import evaluate_reference

MASSLESS = RobotParameters(leg_mass=0.0, leg_inertia=0.0, leg_damping=0.0)


def _cases(robot, model, mu, **kw):
    r = scoutsim.simulate(robot, duration=0.4, model=model, friction_coefficient=mu, **kw)
    P = robot_array(robot, model, friction_coefficient=mu,
                    passive_touchdown_angles=kw.get("passive_touchdown_angles", (0.0, 0.0)),
                    passive_touchdown_world=True, pitch_limit=1.0)
    out = []
    for n in range(0, len(r.t), 5):
        s = r.state[n].copy()
        mi = np.zeros(L.NMI, dtype=np.int64)
        mf = np.zeros(L.NMF)
        mi[L.MI_CONTACT_B:L.MI_CONTACT_B + 2] = r.modes[n, L.RM_CONTACT_B:L.RM_CONTACT_B + 2]
        mi[L.MI_MOTOR_B:L.MI_MOTOR_B + 2] = r.modes[n, L.RM_MOTOR_B:L.RM_MOTOR_B + 2]
        mi[L.MI_SLIDE_DIR_B:L.MI_SLIDE_DIR_B + 2] = 1 if n % 2 else -1
        for leg in range(2):
            mf[leg] = r.aux[n, leg * L.NAUX_LEG + L.A_TOE_X]
        cmd = np.array([r.aux[n, L.A_TAU_CMD], r.aux[n, L.NAUX_LEG + L.A_TAU_CMD]])
        out.append((s, mi, mf, cmd))
    return P, out


CONFIGS = [
    (RobotParameters(), "II", 0.8, {}),
    (RobotParameters(), "I", 0.8, {}),
    (RobotParameters(), "ideal", math.inf, {}),
    (MASSLESS, "passive", math.inf,
     dict(initial_state=InitialState(y=0.36, theta=0.0, dx=0.5, dtheta=0.3),
          passive_touchdown_angles=(0.05, 0.05))),
]


@pytest.mark.parametrize("robot,model,mu,kw", CONFIGS)
def test_evaluate_ws_matches_reference(robot, model, mu, kw):
    P, cases = _cases(robot, model, mu, **kw)
    wk, wA, piv = W.new_eval_workspace()
    st = np.zeros((L.NS, 2 * D.NSTIFF))
    worst = 0.0
    for s, mi, mf, cmd in cases:
        for motor in ([0, 0], [1, -1], [0, 1]):
            for contact in (None, [L.STRUT, L.STICK], [L.SLIDE, L.FLIGHT]):
                mi2 = mi.copy()
                mi2[2:4] = motor
                if contact is not None:
                    mi2[0:2] = contact
                d1 = np.zeros(L.NS)
                a1 = np.zeros(L.NAUX)
                d2 = np.zeros(L.NS)
                a2 = np.zeros(L.NAUX)
                ok1 = evaluate_reference(s, P, mi2, mf, cmd, d1, a1)
                ok2 = D.evaluate_ws(s, P, mi2, mf, cmd, d2, a2, wk, wA, piv, True, st, True)
                assert ok1 == ok2
                for x, y in ((d1, d2), (a1, a2)):
                    # evaluate_ws solves the KKT system differently (gear coordinates
                    # eliminated first, then Schur complements on the structured mass
                    # matrix instead of a pivoted LU of the whole system): equally exact,
                    # so the two differ by round-off only: 1e-10 relative, and a few ulps
                    # (64 eps) of the vector's scale absolute, for entries that are zero
                    # up to round-off
                    fl = 64 * np.finfo(float).eps * max(np.max(np.abs(x)), 1.0)
                    worst = max(worst, np.max(np.abs(x - y) / (1e-10 * np.abs(x) + fl)))
    assert worst < 1.0


def test_inner_stage_evaluation_skips_only_the_outputs():
    """want_aux=False (the integrators' inner stages) gives the same derivative and stiff
    factors bit for bit and leaves the outputs untouched (except the KKT flag)."""
    P, cases = _cases(RobotParameters(), "II", 0.8)
    wk, wA, piv = W.new_eval_workspace()
    for s, mi, mf, cmd in cases:
        st1 = np.zeros((L.NS, 2 * D.NSTIFF))
        st2 = np.zeros((L.NS, 2 * D.NSTIFF))
        d1, d2 = np.zeros(L.NS), np.zeros(L.NS)
        a1 = np.zeros(L.NAUX)
        a2 = np.full(L.NAUX, 7.0)
        ok1 = D.evaluate_ws(s, P, mi, mf, cmd, d1, a1, wk, wA, piv, True, st1, True)
        ok2 = D.evaluate_ws(s, P, mi, mf, cmd, d2, a2, wk, wA, piv, True, st2, False)
        assert ok1 == ok2
        assert np.array_equal(d1, d2) and np.array_equal(st1, st2)
        assert a2[L.A_KKT_OK] == a1[L.A_KKT_OK]
        assert np.all(np.delete(a2, L.A_KKT_OK) == 7.0)


def test_stiff_factors_capture_belt_eigenvalues():
    """U V^T has (nearly) the two fastest eigenvalues of the full Jacobian, and what it
    leaves to the explicit part is not stiff."""
    P, cases = _cases(RobotParameters(), "II", 0.8)
    wk, wA, piv = W.new_eval_workspace()
    st = np.zeros((L.NS, 2 * D.NSTIFF))
    aux = np.zeros(L.NAUX)
    for s, mi, mf, cmd in cases[::6]:
        f0 = np.zeros(L.NS)
        D.evaluate_ws(s, P, mi, mf, cmd, f0, aux, wk, wA, piv, True, st, True)
        J = np.zeros((L.NS, L.NS))
        for j in range(L.NS):
            e = 1e-7 * max(1.0, abs(s[j]))
            sp = s.copy()
            sp[j] += e
            sm = s.copy()
            sm[j] -= e
            dp = np.zeros(L.NS)
            dm = np.zeros(L.NS)
            D.evaluate(sp, P, mi, mf, cmd, dp, aux)
            D.evaluate(sm, P, mi, mf, cmd, dm, aux)
            J[:, j] = (dp - dm) / (2 * e)
        lam_full = np.sort(np.linalg.eigvals(J).real)[:2]
        Js = st[:, :D.NSTIFF] @ st[:, D.NSTIFF:].T
        lam_s = np.sort(np.linalg.eigvals(Js).real)[:2]
        assert np.all(lam_full < -3000.0)
        assert np.allclose(lam_s, lam_full, rtol=0.05)
        assert np.max(np.abs(np.linalg.eigvals(J - Js))) < 500.0


def test_ark_method_matches_reference_model_ii():
    """The experimental linearly implicit ARK4(3) path reproduces DOPRI5 (Model II)."""
    out = {}
    for m in ("dopri5", "ark4"):
        out[m] = scoutsim.simulate(duration=1.0, model="II", friction_coefficient=0.8,
                                   integrator=scoutsim.IntegratorSettings(method=m, rtol=1e-8,
                                                                          atol=1e-9))
    a, b = out["dopri5"], out["ark4"]
    assert a.outcome == b.outcome == "completed"
    assert len(a.events) == len(b.events)
    assert np.max(np.abs(a.events[:, 0] - b.events[:, 0])) < 1e-6
    for fa, fb in ((a.pitch, b.pitch), (a.height, b.height)):
        assert np.max(np.abs(fa - fb)) <= 1e-5 * np.max(np.abs(fa))


@pytest.mark.parametrize("robot,model,mu,kw", CONFIGS[:3])
def test_command_change_equals_fresh_evaluation(robot, model, mu, kw):
    """A new command applied to the kept KKT factors (evaluate_command_change, used at every
    control sample) gives the derivative and outputs of a fresh evaluation, to round-off."""
    P, cases = _cases(robot, model, mu, **kw)
    wk, wA, piv = W.new_eval_workspace()
    st = np.zeros((L.NS, 2 * D.NSTIFF))
    rng = np.random.default_rng(1)
    worst = 0.0
    changed = 0
    for s, mi, mf, cmd in cases:
        for motor in ([0, 0], [1, -1]):
            mi2 = mi.copy()
            mi2[2:4] = motor
            d1, a1 = np.zeros(L.NS), np.zeros(L.NAUX)
            d2, a2 = np.zeros(L.NS), np.zeros(L.NAUX)
            D.evaluate_ws(s, P, mi2, mf, cmd, d1, a1, wk, wA, piv, True, st, True)
            d0 = d1.copy()
            new = cmd + rng.normal(0.0, 10.0, 2)
            ok2 = D.evaluate_command_change(P, mi2, new, d2, a2, wk, wA, piv)
            ok1 = D.evaluate_ws(s, P, mi2, mf, new, d1, a1, wk, wA, piv, False, st, True)
            assert ok1 == ok2
            changed += not np.allclose(d0, d1)   # the new command does act
            for x, y in ((d1, d2), (a1, a2)):
                fl = 64 * np.finfo(float).eps * max(np.max(np.abs(x)), 1.0)
                worst = max(worst, np.max(np.abs(x - y) / (1e-10 * np.abs(x) + fl)))
    # (a stuck motor or a saturated current can leave the derivative as it was)
    assert changed > len(cases) // 2
    assert worst < 1.0
