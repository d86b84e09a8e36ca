"""The allocation-free evaluation (model.evaluate.evaluate_ws) reproduces the reference
implementation (tests/_core/model/reference_evaluator.py, which states every force law itself), with
and without the effects beyond the paper's models, on the bench rigs, and with a battery
internal resistance; a command update on the kept factors equals a fresh evaluation; the
motor current is odd in command and speed; and the stiff-Jacobian factors capture the
belt-damper eigenvalues of Model II."""

import math

import numpy as np
import pytest

import scoutsim
from scoutsim import InitialState, RobotParameters
from scoutsim._core.model import evaluate as D
from scoutsim._core.model import layout as L
from scoutsim._core.model import workspace as W
from scoutsim._core.model.packing import robot_array

from ..sample_modes import sample_modes
from . import reference_evaluator as ref
from .reference_evaluator import evaluate_reference

MASSLESS = RobotParameters(leg_mass=0.0, leg_inertia=0.0, leg_damping=0.0)

#: Every effect beyond the paper's models switched on (docs/model.md, "Effects beyond the
#: paper's models"; values of the order of the virtual Scout II's, with a play small enough
#: that the belt is both slack and stretched within a short run).
EFFECTS = dict(
    belt_backlash=math.radians(0.5),
    leg_friction_force=6.0,
    leg_friction_side_load_coefficient=0.05,
    leg_damping_angle_coefficient=0.5 / math.radians(30.0) ** 2,
    gearbox_idle_loss_torque=0.3,
    gearbox_load_loss_coefficient=0.05,
)
EFFECTS_ROBOT = RobotParameters(**EFFECTS)
#: ... and a battery with internal resistance (specification.md section 4)
BATTERY_ROBOT = RobotParameters(battery_resistance=0.1, **EFFECTS)
#: A robot whose back and front legs differ in every leg, hip-unit and motor quantity (the
#: effects beyond the paper's models too), with its torso COM ahead of the hips' midpoint
#: and a battery with internal resistance: each leg's law must read its own leg's values.
UNEQUAL_ROBOT = RobotParameters(
    com_offset=0.03,
    battery_resistance=0.1,
    leg_mass=(1.0, 0.8),
    leg_inertia=(0.0052, 0.004),
    leg_com_distance=(0.16, 0.14),
    leg_rest_length=(0.323, 0.31),
    leg_stiffness=(3520.0, 3900.0),
    leg_damping=(55.0, 62.0),
    planetary_ratio=(5.0, 4.6),
    sprocket_ratio=(20.4, 21.0),
    gearbox_efficiency=(0.8, 0.75),
    sprocket_efficiency=(0.816, 0.85),
    drive_gear_inertia=(2.4e-6, 2.0e-6),
    driven_gear_inertia=(0.0118, 0.0135),
    joint_stiction=(0.021, 0.03),
    joint_damping=(3.5e-5, 5e-5),
    belt_stiffness=(401.0, 370.0),
    belt_damping=(0.23, 0.3),
    torque_constant=(0.0302, 0.028),
    speed_constant=(0.0302, 0.029),
    armature_resistance=(0.611, 0.7),
    current_limit=(12.0, 11.0),
    belt_backlash=(math.radians(0.5), math.radians(0.8)),
    leg_friction_force=(6.0, 4.0),
    leg_friction_side_load_coefficient=(0.05, 0.08),
    leg_damping_angle_coefficient=(0.5 / math.radians(30.0) ** 2, 0.3 / math.radians(30.0) ** 2),
    gearbox_idle_loss_torque=(0.3, 0.2),
    gearbox_load_loss_coefficient=(0.05, 0.07),
)

#: Factor on the velocities of the slow copy of each sampled state: it puts the motor
#: speeds into the blending band of the transmission losses (|w_m| < 1 rad/s) and the
#: stance legs' length rates into the friction's linear band (|dl/dt| < 1 mm/s).
SLOW = 1e-3


def _cases(robot, model, mu, rig=None, **kw):
    """Parameters and (state, modes, anchors, command) samples of a short run; ``rig``:
    bench-rig options of robot_array (clamps, motor circuit) for the evaluations (the
    run itself is free)."""
    r = scoutsim.simulate(robot, duration=0.4, model=model, friction_coefficient=mu, **kw)
    P = robot_array(
        robot,
        model,
        friction_coefficient=mu,
        passive_touchdown_angles=kw.get("passive_touchdown_angles", (0.0, 0.0)),
        passive_touchdown_world=True,
        pitch_limit=1.0,
        **(rig or {}),
    )
    out = []
    for n in range(0, len(r.t), 5):
        s = r.state[n].copy()
        mi, mf, cmd = sample_modes(r, n, 1 if n % 2 else -1)
        out.append((s, mi, mf, cmd))
    return P, out


def _slow(s):
    """The state s with its velocities scaled by SLOW (positions and leg lengths kept)."""
    s = s.copy()
    s[L.NQ : 2 * L.NQ] *= SLOW
    return s


def _mode_variants(mi, P):
    """The recorded modes and the motor-joint and contact modes substituted (every mode of
    the model is evaluated at every sampled state); on a rig with the torso clamped the
    legs are in flight (a pinned toe would make the clamp's rows redundant)."""
    contacts = (None, [L.STRUT, L.STICK], [L.SLIDE, L.FLIGHT])
    if P[L.P_CLAMP_TORSO] > 0.5:
        contacts = ([L.FLIGHT, L.FLIGHT],)
    for motor in ([0, 0], [1, -1], [0, 1]):
        for contact in contacts:
            mi2 = mi.copy()
            mi2[2:4] = motor
            if contact is not None:
                mi2[0:2] = contact
            yield mi2


def _mismatch(x, y):
    """Largest difference of y from x in units of the allowed round-off: evaluate_ws solves
    the KKT system differently (gear coordinates eliminated first, then Schur complements
    on the structured mass matrix instead of a pivoted LU of the whole system): equally
    exact, so the two differ by round-off only: 1e-10 relative, and a few ulps (64 eps) of
    the vector's scale absolute, for entries that are zero up to round-off."""
    fl = 64 * np.finfo(float).eps * max(np.max(np.abs(x)), 1.0)
    return np.max(np.abs(x - y) / (1e-10 * np.abs(x) + fl))


def _regimes(P, mi, cmd, ds, aux):
    """The regimes of the actuator, transmission and leg laws that one evaluation (the
    reference's outputs ds, aux in modes mi) exercises, as a set of labels."""
    out = set()
    model = int(P[L.P_MODEL])
    vb = aux[L.A_VBATT]
    for leg in range(2):
        o = leg * L.NAUX_LEG
        contact = mi[L.MI_CONTACT_B + leg]
        ld = ds[L.IL_B + leg]
        band = ref.LEG_FRICTION_BAND
        if contact in (L.STICK, L.SLIDE):
            out.add(
                "leg rate > band"
                if ld > band
                else "leg rate < -band"
                if ld < -band
                else "leg rate in band"
                if ld != 0.0
                else "leg rate 0"
            )
        elif contact == L.FLIGHT and P[L.P_MASSLESS] < 0.5:
            out.add(
                "flight rate > band"
                if ld > band
                else "flight rate in band"
                if ld > 0.0
                else "flight rate 0"
            )
        if model == L.MODEL_PASSIVE or int(P[L.P_CIRCUIT]) != L.CIRCUIT_AMPLIFIER:
            continue
        om = aux[o + L.A_OMEGA_M]
        blend = ref.LOSS_BLEND_BAND
        out.add(
            "motor speed > 1"
            if om >= blend
            else "motor speed < -1"
            if om <= -blend
            else "motor speed in blend band"
        )
        i = aux[o + L.A_CURRENT]
        i_cmd = cmd[leg] / (P[L.P_N + leg] * P[L.P_ETA + leg] * P[L.P_KT + leg])
        if abs(om) >= blend and i != 0.0:
            out.add("motoring" if i * om > 0.0 else "back-driven")
        line = [(sgn * vb - P[L.P_KW + leg] * om) / P[L.P_RA + leg] for sgn in (1.0, -1.0)]
        if abs(i) == P[L.P_IMAX + leg]:
            out.add("current at i_max")
        elif model != L.MODEL_IDEAL and any(abs(i - v) <= 1e-12 * abs(v) for v in line):
            out.add("current on the speed line")
        elif i == i_cmd:
            out.add("current as commanded")
        if model == L.MODEL_II:
            half_play = 0.5 * P[L.P_BACKLASH + leg]
            out.add("belt stretched" if abs(aux[o + L.A_BELT]) > half_play else "belt slack")
    if vb < P[L.P_VB] - 0.5:
        out.add("battery sags")
    return out


#: regimes every parity run with the effects beyond the paper switched on must exercise
LEG_REGIMES = {
    "leg rate > band",
    "leg rate < -band",
    "leg rate in band",
    "flight rate > band",
    "flight rate in band",
}
MOTOR_REGIMES = {
    "motor speed > 1",
    "motor speed < -1",
    "motor speed in blend band",
    "motoring",
    "back-driven",
    "current at i_max",
    "current as commanded",
}


def _parity(P, cases):
    """Worst mismatch (in units of the allowed round-off, _mismatch) of evaluate_ws against
    the reference over the sampled states, their slow copies and every mode variant, and
    the regimes exercised."""
    wk, wA, piv = W.new_eval_workspace()
    st = np.zeros((L.NS, 2 * D.NSTIFF))
    worst = 0.0
    regimes = set()
    for s0, mi, mf, cmd in cases:
        for s in (s0, _slow(s0)):
            for mi2 in _mode_variants(mi, P):
                d1 = np.zeros(L.NS)
                a1 = np.zeros(L.NAUX)
                d2 = np.zeros(L.NS)
                a2 = np.zeros(L.NAUX)
                ok1 = evaluate_reference(s, P, mi2, mf, cmd, d1, a1)
                ok2 = D.evaluate_ws(s, P, mi2, mf, cmd, d2, a2, (wk, wA, piv, st), True, st, True)
                assert ok1 == ok2
                worst = max(worst, _mismatch(d1, d2), _mismatch(a1, a2))
                regimes |= _regimes(P, mi2, cmd, d1, a1)
    return worst, regimes


CONFIGS = [
    (RobotParameters(), "II", 0.8, {}),
    (RobotParameters(), "I", 0.8, {}),
    (RobotParameters(), "ideal", math.inf, {}),
    (
        MASSLESS,
        "passive",
        math.inf,
        dict(
            initial_state=InitialState(y=0.36, theta=0.0, dx=0.5, dtheta=0.3),
            passive_touchdown_angles=(0.05, 0.05),
        ),
    ),
    (EFFECTS_ROBOT, "II", 0.8, {}),
    (EFFECTS_ROBOT, "I", 0.8, {}),
    (EFFECTS_ROBOT, "ideal", 0.8, {}),
    (EFFECTS_ROBOT, "II", 0.8, dict(rig=dict(motor_circuit="short"))),
    (EFFECTS_ROBOT, "II", 0.8, dict(rig=dict(motor_circuit="open", clamp_torso=True))),
    (
        EFFECTS_ROBOT,
        "I",
        0.8,
        dict(rig=dict(motor_circuit="short", clamp_torso=True, clamp_legs=True)),
    ),
    (UNEQUAL_ROBOT, "II", 0.8, {}),
    (UNEQUAL_ROBOT, "I", 0.8, {}),
    (UNEQUAL_ROBOT, "ideal", 0.8, {}),
]


@pytest.mark.parametrize("robot,model,mu,kw", CONFIGS)
def test_evaluate_ws_matches_reference(robot, model, mu, kw):
    """The optimized right-hand side equals the reference evaluator (its own statement of
    every force law and of the KKT system) to round-off, in every mode, at states of a
    short run and at slow copies of them; with the effects beyond the paper switched on,
    the states exercise each regime of their laws (both sides of the belt's play, leg
    rates of both signs and inside the friction's linear band, motor speeds inside and
    beyond the loss blending band, motoring and back-driven, current at its limit); the
    bench rig's motor circuits and clamps are evaluated at the same states."""
    P, cases = _cases(robot, model, mu, **kw)
    worst, regimes = _parity(P, cases)
    assert worst < 1.0
    if robot in (EFFECTS_ROBOT, UNEQUAL_ROBOT) and "rig" not in kw:
        assert LEG_REGIMES | MOTOR_REGIMES <= regimes
        if model != "ideal":
            assert "current on the speed line" in regimes
        if model == "II":
            assert {"belt slack", "belt stretched"} <= regimes


@pytest.mark.parametrize("model", ["II", "I"])
def test_battery_voltage_matches_reference(model):
    """With a battery internal resistance shared by all motors (V_b = V_oc - R_b I_b,
    I_b = P / V_b; specification.md section 4) and every other effect on, evaluate_ws
    equals the reference (which solves for V_b by its own root finding), also where a
    motor's current is on its torque-speed line, so that the power drawn depends on V_b
    itself; the battery sags by more than 0.5 V."""
    P, cases = _cases(BATTERY_ROBOT, model, 0.8)
    worst, regimes = _parity(P, cases)
    assert {"battery sags", "current on the speed line"} <= regimes
    assert worst < 1.0


def _flight_currents(evaluator, P, w, tau):
    """Motor currents (back, front) that ``evaluator`` gives with both legs in flight, the
    back motor at speed w [rad/s] and command tau [N m], the front one at -w and -tau."""
    s = np.zeros(L.NS)
    s[L.IY] = 0.6
    s[L.IL_B] = P[L.P_L0 + L.BACK]
    s[L.IL_F] = P[L.P_L0 + L.FRONT]
    s[L.NQ + L.IPHB] = w / P[L.P_N + L.BACK]
    s[L.NQ + L.IPHF] = -w / P[L.P_N + L.FRONT]
    mi = np.zeros(L.NMI, dtype=np.int64)
    ds = np.zeros(L.NS)
    aux = np.zeros(L.NAUX)
    evaluator(s, P, mi, np.zeros(L.NMF), np.array([tau, -tau]), ds, aux)
    return np.array([aux[L.A_CURRENT], aux[L.NAUX_LEG + L.A_CURRENT]])


@pytest.mark.parametrize("evaluator", [evaluate_reference, D.evaluate])
def test_motor_current_is_odd_in_command_and_speed(evaluator):
    """The amplifier, the motor and the battery are symmetric under reversing the current,
    the voltage and the speed (specification.md section 4): reversing the command and the
    motor speed reverses the current, at speeds up to twice (V_b + R_A i_max) / K_w
    (beyond it neither limit lets the other hold) and commands up to beyond the
    current limit (Model I)."""
    P = robot_array(RobotParameters(), "I", friction_coefficient=0.8)
    w_both = (P[L.P_VB] + P[L.P_RA] * P[L.P_IMAX]) / P[L.P_KW]  # (equal legs: the back's)
    for w in np.linspace(-2.0, 2.0, 41) * w_both:
        for tau in (-40.0, -5.0, 0.0, 5.0, 40.0):
            i_plus = _flight_currents(evaluator, P, w, tau)
            i_minus = _flight_currents(evaluator, P, -w, -tau)
            assert np.allclose(i_plus, -i_minus, rtol=1e-12, atol=1e-12)


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
        ok1 = D.evaluate_ws(s, P, mi, mf, cmd, d1, a1, (wk, wA, piv, st1), True, st1, True)
        ok2 = D.evaluate_ws(s, P, mi, mf, cmd, d2, a2, (wk, wA, piv, st2), True, st2, False)
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
        D.evaluate_ws(s, P, mi, mf, cmd, f0, aux, (wk, wA, piv, st), True, st, True)
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
        Js = st[:, : D.NSTIFF] @ st[:, D.NSTIFF :].T
        lam_s = np.sort(np.linalg.eigvals(Js).real)[:2]
        assert np.all(lam_full < -3000.0)
        assert np.allclose(lam_s, lam_full, rtol=0.05)
        assert np.max(np.abs(np.linalg.eigvals(J - Js))) < 500.0


def test_ark_method_matches_reference_model_ii():
    """The experimental linearly implicit ARK4(3) path reproduces DOPRI5 (Model II)."""
    out = {}
    for m in ("dopri5", "ark4"):
        out[m] = scoutsim.simulate(
            duration=1.0,
            model="II",
            friction_coefficient=0.8,
            integrator=scoutsim.IntegratorSettings(method=m, rtol=1e-8, atol=1e-9),
        )
    a, b = out["dopri5"], out["ark4"]
    assert a.outcome == b.outcome == "completed"
    assert len(a.events) == len(b.events)
    assert np.max(np.abs(a.events[:, 0] - b.events[:, 0])) < 1e-6
    for fa, fb in ((a.pitch, b.pitch), (a.height, b.height)):
        assert np.max(np.abs(fa - fb)) <= 1e-5 * np.max(np.abs(fa))


#: In Model I and the ideal variant the hip torque loads the leg's sliding joint sideways,
#: so with the side-load friction on a new command changes the leg force too, and the
#: integrators take a fresh evaluation instead of the command update (docs/model.md):
#: those runs keep every effect but that one. In Model II the belt, not the command,
#: loads the leg.
NO_SIDE_LOAD_ROBOT = RobotParameters(
    battery_resistance=0.1, **{**EFFECTS, "leg_friction_side_load_coefficient": 0.0}
)
COMMAND_CONFIGS = CONFIGS[:3] + [
    (EFFECTS_ROBOT, "II", 0.8, {}),
    (BATTERY_ROBOT, "II", 0.8, {}),
    (NO_SIDE_LOAD_ROBOT, "I", 0.8, {}),
    (NO_SIDE_LOAD_ROBOT, "ideal", 0.8, {}),
]


@pytest.mark.parametrize("robot,model,mu,kw", COMMAND_CONFIGS)
def test_command_change_equals_fresh_evaluation(robot, model, mu, kw):
    """A new command applied to the kept KKT factors (evaluate_command_change, used at every
    control sample) gives the derivative and outputs of a fresh evaluation, to round-off,
    also with the battery resistance and the transmission losses (the delivered torque is
    then not linear in the command)."""
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
            D.evaluate_ws(s, P, mi2, mf, cmd, d1, a1, (wk, wA, piv, st), True, st, True)
            d0 = d1.copy()
            new = cmd + rng.normal(0.0, 10.0, 2)
            ok2 = D.evaluate_command_change(P, mi2, new, d2, a2, wk, wA, piv)
            ok1 = D.evaluate_ws(s, P, mi2, mf, new, d1, a1, (wk, wA, piv, st), False, st, True)
            assert ok1 == ok2
            changed += not np.allclose(d0, d1)  # the new command does act
            worst = max(worst, _mismatch(d1, d2), _mismatch(a1, a2))
    # (a stuck motor or a saturated current can leave the derivative as it was)
    assert changed > len(cases) // 2
    assert worst < 1.0


@pytest.mark.parametrize("robot,model,mu,kw", CONFIGS)
def test_evaluated_state_is_the_projection(robot, model, mu, kw):
    """The state an evaluation projected (evaluated_state, which the step loop takes for an
    accepted step's end instead of projecting it again) is the projection of the state it
    was given, bit for bit, in every mode; the pitch's sine and cosine it returns are those
    of the state, and the event functions computed with them equal event_values'."""
    from scoutsim._core.model.kinematics import project_state
    from scoutsim._core.numerics.events import event_values, event_values_at

    P, cases = _cases(robot, model, mu, **kw)
    ew = (*W.new_eval_workspace(), np.zeros((L.NS, 2 * D.NSTIFF)))
    rng = np.random.default_rng(3)
    moved = 0
    for s, mi, mf, cmd in cases:
        # move the dependent coordinates off their constraints so that projecting changes them
        s = s + 1e-3 * rng.standard_normal(L.NS)
        for mi2 in _mode_variants(mi, P):
            ds, aux = np.zeros(L.NS), np.zeros(L.NAUX)
            D.evaluate_ws(s, P, mi2, mf, cmd, ds, aux, ew, False, ew[3], True)
            got = np.full(L.NS, np.nan)
            sth, cth = D.evaluated_state(ew, got)
            want = s.copy()
            project_state(want, P, mi2, mf)
            moved += not np.array_equal(want, s)
            assert got.tobytes() == want.tobytes()
            assert (sth, cth) == (math.sin(want[L.ITH]), math.cos(want[L.ITH]))
            e1, e2 = np.zeros(L.NEV), np.zeros(L.NEV)
            event_values_at(got, aux, P, mi2, e1, sth, cth)
            event_values(want, aux, P, mi2, e2)
            assert e1.tobytes() == e2.tobytes()
    assert moved > 0  # the projection was exercised, not only the identity
