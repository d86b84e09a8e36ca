"""Tests of scoutsim.analysis.gait (docs/specification.md section 8) on hand-built results with known answers."""

import dataclasses
import json
import math

import numpy as np
import pytest

import scoutsim
from scoutsim import SimulationResult
from scoutsim._core.model import layout as L
from scoutsim.analysis.gait import gait_metrics, stride_table
from scoutsim.analysis.stances import stance_intervals

DT = 1e-3
V = 1.3  # forward speed [m/s]
PITCH_AMP = 0.2  # [rad]
PITCH_F = 5.0  # [Hz]
H0, H_AMP, H_F = 0.30, 0.02, 3.0
BACK_STANCE = 0.2  # back stance ends at each back lift-off [s]
FRONT_BEFORE, FRONT_AFTER = 0.1, 0.15  # front stance straddles each back lift-off [s]

FIRST_KEYS = [
    "outcome",
    "mean_speed_m_s",
    "stride_frequency_hz",
    "duty_factor_back",
    "duty_factor_front",
    "pitch_max_deg",
    "pitch_min_deg",
    "height_max_m",
    "height_min_m",
    "max_friction_ratio",
    "n_steady_strides",
]
EXTRA_KEYS = [
    "t_end_s",
    "n_strides",
    "stride_period_cv",
    "steady_bounding",
    "motor_saturation_retraction_back",
    "motor_saturation_retraction_front",
    "max_belt_deflection_deg",
    "max_impact_impulse_ratio",
    "end_of_stance_slides",
    "model",
]
BEHAVIOUR_KEYS = ["behaviour", "behaviour_kind", "behaviour_detail"]
ENERGY_KEYS = [
    "electrical_energy_j",
    "copper_loss_j",
    "transmission_loss_j",
    "hip_work_j",
    "friction_loss_j",
    "impact_loss_j",
    "mechanical_energy_change_j",
    "energy_residual_j",
    "energy_relative_residual",
    "mean_electrical_power_w",
    "cost_of_transport",
]


def back_liftoffs(t_stop=7.6):
    """Slightly irregular back lift-off times, off the 1 kHz grid."""
    lo = [0.3003]
    k = 0
    while True:
        nxt = lo[-1] + 0.5 + 0.01 * math.sin(k)
        if nxt > t_stop:
            return np.array(lo)
        lo.append(nxt)
        k += 1


def make_result(
    duration=8.0, lo=None, outcome="completed", x_wiggle=0.0, extra_events=(), t_cut=None
):
    """A hand-built SimulationResult: x = V t (+ wiggle), sinusoidal height and pitch,
    back stance [lo - 0.2, lo], front stance [lo - 0.1, lo + 0.15] for each back lift-off."""
    n = int(round(duration / DT)) + 1
    t = np.arange(n) * DT
    if t_cut is not None:  # a fall: data stop with one off-grid sample at t_cut
        t = np.append(t[t < t_cut], t_cut)
    w_p, w_h, w_x = 2 * np.pi * PITCH_F, 2 * np.pi * H_F, 2 * np.pi * 3.0
    state = np.zeros((len(t), L.NS))
    state[:, L.IX] = V * t + x_wiggle * np.sin(w_x * t)
    state[:, L.NQ + L.IX] = V + x_wiggle * w_x * np.cos(w_x * t)
    state[:, L.IY] = H0 + H_AMP * np.sin(w_h * t)
    state[:, L.NQ + L.IY] = H_AMP * w_h * np.cos(w_h * t)
    state[:, L.ITH] = PITCH_AMP * np.sin(w_p * t)
    state[:, L.NQ + L.ITH] = PITCH_AMP * w_p * np.cos(w_p * t)
    state[:, L.IL_B] = state[:, L.IL_F] = 0.323
    lo = back_liftoffs() if lo is None else lo
    t_end = float(t[-1])
    rows = []
    for tl in lo:
        rows.append([tl - BACK_STANCE, L.EK_TOUCHDOWN, L.BACK, 0, 0, 0])
        rows.append([tl - BACK_STANCE / 2, L.EK_SLIDE_START, L.BACK, 0, 0, 0])  # not an end
        rows.append([tl - BACK_STANCE / 2 + 0.003, L.EK_CTRL_LIFTOFF, L.BACK, 0, 0, 0])
        rows.append([tl, L.EK_LIFTOFF, L.BACK, 0, 0, 0])
        rows.append([tl - FRONT_BEFORE, L.EK_TOUCHDOWN, L.FRONT, 0, 0, 0])
        if tl + FRONT_AFTER < t_end:
            rows.append([tl + FRONT_AFTER, L.EK_LIFTOFF, L.FRONT, 0, 0, 0])
    rows.extend(list(e) for e in extra_events)
    # transition-audit columns (energy before / after, violations): not used by the gait
    rows = [list(r) + [np.nan] * (L.NEVREC - len(r)) for r in rows]
    events = np.array(sorted(rows), dtype=float).reshape(-1, L.NEVREC)
    events = events[events[:, 0] <= t_end]
    return SimulationResult(
        t=t,
        state=state,
        aux=np.zeros((len(t), L.NAUX)),
        modes=np.zeros((len(t), 6), dtype=np.int8),
        events=events,
        outcome=outcome,
        t_end=t_end,
        stats={
            "max_friction_ratio": 0.42,
            "max_impact_impulse_ratio": 0.1,
            "end_of_stance_slides": 3.0,
        },
        provenance={"model": "I", "robot": dataclasses.asdict(scoutsim.RobotParameters())},
    )


def sampling_tol(amp, freq):
    """Worst-case shortfall of the sampled extreme of amp*sin(2 pi f t) at 1 kHz."""
    return amp * (1 - math.cos(math.pi * freq * DT)) + 1e-12


# -----------------------------------------------------------------------------------------
def test_stride_count_period_frequency_exact():
    lo = back_liftoffs()
    g = gait_metrics(make_result(lo=lo), transient_s=0.0)
    assert g.n_strides == len(lo) - 1
    for k, s in enumerate(g.strides):
        assert s.t_start == lo[k] and s.t_end == lo[k + 1]
        assert s.period_s == pytest.approx(lo[k + 1] - lo[k], rel=1e-14)
        assert s.stride_frequency_hz == pytest.approx(1.0 / (lo[k + 1] - lo[k]), rel=1e-14)


def test_duty_factors_from_event_times():
    lo = back_liftoffs()
    g = gait_metrics(make_result(lo=lo), transient_s=0.0)
    for k, s in enumerate(g.strides):
        period = lo[k + 1] - lo[k]
        # back stance [lo_{k+1} - 0.2, lo_{k+1}] lies inside the stride; the slide_start
        # in the middle of it does not end it
        assert s.duty_factor_back == pytest.approx(BACK_STANCE / period, rel=1e-12)
        # front stance straddles both boundaries: 0.15 s after the start, 0.1 s before end
        assert s.duty_factor_front == pytest.approx(
            (FRONT_AFTER + FRONT_BEFORE) / period, rel=1e-12
        )


def test_stance_intervals_and_open_stance_at_end():
    lo = back_liftoffs()
    t_td = lo[-1] + 0.05  # back never lifts off again
    duration = round(lo[-1] + 0.1, 3)  # ends inside the last front stance
    r = make_result(
        duration=duration, lo=lo, extra_events=[(t_td, L.EK_TOUCHDOWN, L.BACK, 0, 0, 0)]
    )
    assert r.t_end == pytest.approx(duration)
    back = stance_intervals(r, "back")
    assert back.shape == (len(lo) + 1, 2)
    np.testing.assert_allclose(back[:-1, 1], lo)
    np.testing.assert_allclose(back[:-1, 0], lo - BACK_STANCE)
    assert back[-1, 0] == t_td and back[-1, 1] == r.t_end
    front = stance_intervals(r, 1)
    assert front.shape == (len(lo), 2)
    np.testing.assert_allclose(front[:-1, 1], lo[:-1] + FRONT_AFTER)
    assert front[-1, 0] == lo[-1] - FRONT_BEFORE and front[-1, 1] == r.t_end


def test_leg_starting_in_stance():
    lo = back_liftoffs()
    r = make_result(lo=lo)
    r.events = np.vstack([[[0.05, L.EK_LIFTOFF, L.FRONT, 0, 0, 0] + [np.nan] * 3], r.events])
    front = stance_intervals(r, "front")
    assert front[0, 0] == r.t[0] and front[0, 1] == 0.05


def test_mean_speed_linear_and_hermite_accuracy():
    g = gait_metrics(make_result(), transient_s=0.0)
    for s in g.strides:
        assert s.mean_speed_m_s == pytest.approx(V, abs=1e-12)
    # x = V t + b sin(w t): interpolation at the off-grid event times must be accurate to
    # far better than linear interpolation (which would be off by ~1e-6 m/s here)
    b, w = 0.01, 2 * np.pi * 3.0
    g = gait_metrics(make_result(x_wiggle=b), transient_s=0.0)
    for s in g.strides:
        dx = V * (s.t_end - s.t_start) + b * (np.sin(w * s.t_end) - np.sin(w * s.t_start))
        assert s.mean_speed_m_s == pytest.approx(dx / s.period_s, abs=1e-8)


def test_pitch_and_height_extrema():
    g = gait_metrics(make_result(), transient_s=0.0)
    amp_deg = math.degrees(PITCH_AMP)
    for s in g.strides:  # every stride (>= 0.49 s) holds a full pitch and height cycle
        assert amp_deg - sampling_tol(amp_deg, PITCH_F) <= s.pitch_max_deg <= amp_deg + 1e-12
        assert -amp_deg - 1e-12 <= s.pitch_min_deg <= -amp_deg + sampling_tol(amp_deg, PITCH_F)
        assert H0 + H_AMP - sampling_tol(H_AMP, H_F) <= s.height_max_m <= H0 + H_AMP + 1e-12
        assert H0 - H_AMP - 1e-12 <= s.height_min_m <= H0 - H_AMP + sampling_tol(H_AMP, H_F)
    assert g.pitch_max_deg == pytest.approx(amp_deg, abs=sampling_tol(amp_deg, PITCH_F))
    assert g.height_min_m == pytest.approx(H0 - H_AMP, abs=sampling_tol(H_AMP, H_F))


def test_extrema_include_interpolated_endpoints():
    # a stride shorter than the sample spacing has no sample inside: the extremes come
    # from the interpolated endpoints, i.e. the pitch at the two event times
    lo = np.array([1.0002, 1.0007])
    g = gait_metrics(make_result(lo=lo), transient_s=0.0)
    assert g.n_strides == 1
    p = [math.degrees(PITCH_AMP * math.sin(2 * np.pi * PITCH_F * tt)) for tt in lo]
    s = g.strides[0]
    assert s.pitch_max_deg == pytest.approx(max(p), abs=1e-6)
    assert s.pitch_min_deg == pytest.approx(min(p), abs=1e-6)
    # pitch rises monotonically over [1.0002, 1.0397] (a quarter period starts at 1.0):
    # the extremes are at the off-grid endpoints, beyond every sample inside
    lo = np.array([1.0002, 1.0397])
    g = gait_metrics(make_result(lo=lo), transient_s=0.0)
    p = [math.degrees(PITCH_AMP * math.sin(2 * np.pi * PITCH_F * tt)) for tt in lo]
    s = g.strides[0]
    assert s.pitch_max_deg == pytest.approx(p[1], abs=1e-6)
    assert s.pitch_min_deg == pytest.approx(p[0], abs=1e-6)


def test_steady_selection_and_means():
    lo = back_liftoffs()
    g = gait_metrics(make_result(lo=lo), transient_s=2.0)
    expected = [k for k in range(len(lo) - 1) if lo[k] >= 2.0]
    assert g.n_steady_strides == len(expected) and len(g.steady_strides) == len(expected)
    assert [s.steady for s in g.strides] == [lo[k] >= 2.0 for k in range(len(lo) - 1)]
    periods = np.diff(lo)[expected]
    assert g.period_s == pytest.approx(periods.mean(), rel=1e-12)
    assert g.stride_frequency_hz == pytest.approx(np.mean(1 / periods), rel=1e-12)
    assert g.duty_factor_back == pytest.approx(np.mean(BACK_STANCE / periods), rel=1e-12)
    assert g.stride_period_cv == pytest.approx(periods.std() / periods.mean(), rel=1e-9)
    assert g.mean_speed_m_s == pytest.approx(V, abs=1e-12)
    assert g.is_steady_bounding()
    assert not g.is_steady_bounding(min_strides=len(expected) + 1)
    assert not g.is_steady_bounding(max_period_cv=0.5 * g.stride_period_cv)


def test_summary_keys_and_json():
    r = make_result()
    s = gait_metrics(r).summary(r)
    assert list(s)[: len(FIRST_KEYS)] == FIRST_KEYS
    assert list(s)[len(FIRST_KEYS) :] == EXTRA_KEYS + BEHAVIOUR_KEYS + ENERGY_KEYS
    assert all(s[k] is None for k in ENERGY_KEYS)  # made without the energy accounting
    json.dumps(s, allow_nan=False)
    assert s["outcome"] == "completed" and s["model"] == "I"
    assert s["max_friction_ratio"] == 0.42
    assert s["steady_bounding"] is True
    assert s["mean_speed_m_s"] == pytest.approx(V)
    assert s["end_of_stance_slides"] == 3
    assert r.summary() == s  # through SimulationResult.summary()


def test_no_steady_strides_gives_null():
    r = make_result()
    g = gait_metrics(r, transient_s=100.0)
    assert g.n_strides > 0 and g.n_steady_strides == 0
    s = g.summary(r)
    text = json.dumps(s, allow_nan=False)
    assert "NaN" not in text
    for k in FIRST_KEYS[1:9] + ["stride_period_cv"]:
        assert s[k] is None
    assert s["steady_bounding"] is False
    # and with no strides at all
    r0 = make_result(lo=np.array([1.0]))
    s0 = gait_metrics(r0).summary(r0)
    assert s0["n_strides"] == 0 and s0["mean_speed_m_s"] is None
    json.dumps(s0, allow_nan=False)


def test_fallen_run_is_not_steady_bounding():
    lo = back_liftoffs()
    r = make_result(lo=lo, outcome="fell", t_cut=5.5432)
    g = gait_metrics(r, transient_s=0.0)
    assert r.t[-1] == 5.5432 and r.t_end == 5.5432
    assert g.n_strides == np.count_nonzero(lo <= 5.5432) - 1
    assert g.n_steady_strides >= 7 and g.stride_period_cv < 0.05
    assert not g.is_steady_bounding()
    assert g.summary(r)["steady_bounding"] is False


def test_motor_saturation_fraction_and_belt_deflection():
    """Saturated = operating point on the current limit or on the torque-speed line."""
    r = make_result()
    rp = scoutsim.RobotParameters()
    o = L.BACK * L.NAUX_LEG
    r.modes[1000:2000, L.RM_LEG_STATE_B] = L.LS_RETRACTION
    r.modes[2000:2500, L.RM_LEG_STATE_B] = L.LS_BRAKE
    r.aux[:, L.A_VBATT] = rp.battery_voltage
    r.aux[:, o + L.A_CURRENT] = -3.0  # inside the limits
    r.aux[:, o + L.A_OMEGA_M] = -100.0
    r.aux[1000:1200, o + L.A_CURRENT] = -rp.current_limit  # on the current limit: 200
    # on the torque-speed line: R i + K_w w = -V_b  -> 50 samples
    w = -300.0
    r.aux[1200:1250, o + L.A_OMEGA_M] = w
    r.aux[1200:1250, o + L.A_CURRENT] = (
        -rp.battery_voltage - rp.speed_constant * w
    ) / rp.armature_resistance
    r.aux[1250:1260, o + L.A_CURRENT] = -0.9 * rp.current_limit  # near, but not on, a limit
    r.aux[2000:2500, o + L.A_CURRENT] = -rp.current_limit  # brake: does not count
    g = gait_metrics(r)
    assert g.motor_saturation_fraction(r, "back") == pytest.approx(0.25)
    assert g.motor_saturation_fraction(r, "front") is None  # never in retraction
    r.aux[3000, L.FRONT * L.NAUX_LEG + L.A_BELT] = -0.01
    r.aux[3100, L.BACK * L.NAUX_LEG + L.A_BELT] = 0.005
    assert g.max_belt_deflection_deg(r) == pytest.approx(math.degrees(0.01))
    s = g.summary(r)
    assert s["motor_saturation_retraction_back"] == pytest.approx(0.25)
    assert s["max_belt_deflection_deg"] == pytest.approx(math.degrees(0.01))


def test_stride_table_and_to_dict():
    lo = back_liftoffs()
    r = make_result(lo=lo)
    tab = stride_table(r, transient_s=2.0)
    n = len(lo) - 1
    assert all(len(v) == n for v in tab.values())
    np.testing.assert_allclose(tab["period_s"], np.diff(lo), rtol=1e-14)
    np.testing.assert_array_equal(tab["steady"], lo[:-1] >= 2.0)
    g = gait_metrics(r)
    d = g.to_dict()
    json.dumps(d, allow_nan=False)
    assert len(d["strides"]) == n
    assert dict(g.strides[0])["t_start"] == lo[0] == g.strides[0]["t_start"]


def test_bad_transient_rejected():
    with pytest.raises(ValueError):
        gait_metrics(make_result(), transient_s=-1.0)


# -----------------------------------------------------------------------------------------
def test_real_simulation_model_I():
    """On a simulated run: the duty factor of every stride (stance time / stride period,
    from the touchdown and lift-off events) equals the fraction of the stride's 1 kHz
    samples at which the plant's contact mode is not flight, to the sampling resolution:
    each stance piece inside a stride holds its length / DT samples, plus or minus one."""
    r = scoutsim.simulate(duration=1.0, model="I")
    g = gait_metrics(r, transient_s=0.0)
    s = r.summary()
    assert list(s)[: len(FIRST_KEYS)] == FIRST_KEYS
    assert set(EXTRA_KEYS) <= set(s)
    json.dumps(s, allow_nan=False)
    assert g.n_strides >= 3
    for st in g.strides:
        inside = (r.t >= st.t_start) & (r.t < st.t_end)
        for leg, duty in ((L.BACK, st.duty_factor_back), (L.FRONT, st.duty_factor_front)):
            sampled = np.count_nonzero(r.contact_mode(leg)[inside] != L.FLIGHT) * DT
            pieces = sum(1 for a, b in stance_intervals(r, leg) if a < st.t_end and b > st.t_start)
            assert pieces >= 1  # a bounding leg stands in every stride
            assert abs(duty * st.period_s - sampled) <= pieces * DT, (st.t_start, leg)
    # the event-based stances agree with the sampled plant contact mode away from the
    # event times (one sample of margin on either side)
    for leg in (0, 1):
        iv = stance_intervals(r, leg)
        cm = r.contact_mode(leg)
        inside = np.zeros(len(r.t), dtype=bool)
        near = np.zeros(len(r.t), dtype=bool)
        for a, b in iv:
            inside |= (r.t > a) & (r.t < b)
            near |= (np.abs(r.t - a) <= 1.5e-3) | (np.abs(r.t - b) <= 1.5e-3)
        assert np.all(cm[inside & ~near] != L.FLIGHT)
        assert np.all(cm[~inside & ~near] == L.FLIGHT)


def test_slow_transient_after_transient_time_is_not_steady():
    """Strides still converging after transient_s are excluded: steady = converged tail."""
    lo = [0.3003]
    periods = [0.40, 0.40, 0.40, 0.40, 0.40, 0.40, 0.37, 0.33] + [0.30] * 12
    for p in periods:
        lo.append(lo[-1] + p)
    r = make_result(duration=lo[-1] + 0.2, lo=np.array(lo))
    g = gait_metrics(r, transient_s=1.0)
    assert g.n_steady_strides == 12
    assert g.stride_period_cv == pytest.approx(0.0, abs=1e-12)
    assert g.period_s == pytest.approx(0.30)
    assert g.is_steady_bounding()


def test_an_interrupted_run_that_was_bounding_is_steady_bounding():
    """A run the user stopped while it bounded steadily (outcome "interrupted") counts as
    steady bounding, like the same run completed; a fall or a failure does not."""
    r = scoutsim.simulate(duration=5.0)
    assert r.gait().is_steady_bounding()
    for outcome, steady in (("interrupted", True), ("fell", False), ("numerical_failure", False)):
        forced = dataclasses.replace(r, outcome=outcome, _cache={})
        assert gait_metrics(forced).is_steady_bounding() is steady, outcome
        assert forced.summary()["steady_bounding"] is steady
