"""Strides and gait metrics of a bounding run (docs/specification.md section 8; paper Sec. IV).

A **stride** runs from one back-leg lift-off to the next (docs/specification.md section 8; paper Sec. IV.C:
"steady state strides defined by the back leg lift-off event"). For every stride this module
computes the quantities the paper compares between simulation and experiment (Fig. 12):
stride frequency, duty factor of each virtual leg, maximum and minimum torso pitch and COM
height, and the mean forward speed. Steady-state averages are taken over the strides that
begin after an initial transient.

All times are the plant's continuous-time event times (``result.events``), not controller
samples: a stance starts at a ``"touchdown"`` event of a leg and ends at the next
``"liftoff"`` event of the same leg. Other plant events (``"slide_start"``, ``"stick"``,
strut events, ...) and the controller's own detections (``"controller_touchdown"``, ...) do
not start or end a stance.

Units: seconds, metres, m/s, Hz, degrees for angles in the metrics (the time series are in
radians), amperes for currents.

Public API
----------
gait_metrics(result, transient_s=2.0) -> GaitMetrics
stance_intervals(result, leg) -> (k, 2) array of [touchdown, lift-off] times [s]
stride_table(result, transient_s=2.0) -> dict of column arrays (one row per stride)
Stride, GaitMetrics, SUMMARY_KEYS, STRIDE_METRICS
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field, fields

import numpy as np

from ..model import layout as L

__all__ = ["gait_metrics", "stance_intervals", "stride_table", "stride_energy", "Stride",
           "GaitMetrics", "SUMMARY_KEYS", "SUMMARY_EXTRA_KEYS", "SUMMARY_ENERGY_KEYS",
           "STRIDE_METRICS", "STRIDE_ENERGY_METRICS"]

#: Keys that :meth:`GaitMetrics.summary` returns first, in this order.
SUMMARY_KEYS = ("outcome", "mean_speed_m_s", "stride_frequency_hz", "duty_factor_back",
                "duty_factor_front", "pitch_max_deg", "pitch_min_deg", "height_max_m",
                "height_min_m", "max_friction_ratio", "n_steady_strides")
#: Keys that follow :data:`SUMMARY_KEYS` in :meth:`GaitMetrics.summary`, in this order.
SUMMARY_EXTRA_KEYS = ("t_end_s", "n_strides", "stride_period_cv", "steady_bounding",
                      "motor_saturation_retraction_back", "motor_saturation_retraction_front",
                      "max_belt_deflection_deg", "max_impact_impulse_ratio",
                      "end_of_stance_slides", "model")
#: Keys that follow :data:`SUMMARY_EXTRA_KEYS` in :meth:`GaitMetrics.summary`: what the
#: gait costs (all None for a run made without the energy accounting).
SUMMARY_ENERGY_KEYS = ("electrical_energy_j", "copper_loss_j", "transmission_loss_j",
                       "hip_work_j", "friction_loss_j", "impact_loss_j",
                       "mechanical_energy_change_j", "energy_residual_j",
                       "energy_relative_residual", "mean_electrical_power_w",
                       "cost_of_transport")
#: Per-stride numeric metrics that are averaged over the steady strides.
STRIDE_METRICS = ("period_s", "stride_frequency_hz", "duty_factor_back", "duty_factor_front",
                  "pitch_max_deg", "pitch_min_deg", "height_max_m", "height_min_m",
                  "mean_speed_m_s")

#: Per-stride energy fields of :class:`Stride` (None without the energy accounting).
STRIDE_ENERGY_METRICS = ("electrical_energy_j", "copper_loss_j", "transmission_loss_j",
                         "hip_work_j", "friction_loss_j", "impact_loss_j",
                         "mechanical_energy_change_j", "energy_residual_j", "distance_m",
                         "mean_electrical_power_w", "cost_of_transport")

#: Current mismatch [A] above which the amplifier/motor limit counts as active.
SATURATION_TOLERANCE_A = 1e-6

_LEGS = {"back": 0, "front": 1, 0: 0, 1: 1}


def _leg(leg) -> int:
    try:
        return _LEGS[leg]
    except (KeyError, TypeError):
        raise ValueError(f"leg = {leg!r} is not allowed: must be 'back' or 'front'") from None


def _json_float(v):
    """float(v), or None if v is None, NaN or infinite (JSON has no NaN/inf)."""
    if v is None:
        return None
    v = float(v)
    return v if math.isfinite(v) else None


def _json_number(v):
    """Like :func:`_json_float`, but integral values become int (counts in ``stats``)."""
    v = _json_float(v)
    if v is not None and v.is_integer():
        return int(v)
    return v


def _events(result) -> np.ndarray:
    ev = np.asarray(result.events, dtype=float)
    if ev.size == 0:
        return np.zeros((0, L.NEVREC))
    return ev.reshape(-1, ev.shape[-1])


# -----------------------------------------------------------------------------------------
# interpolation
# -----------------------------------------------------------------------------------------
def _hermite(t, y, dy, te):
    """Cubic Hermite interpolation of samples ``y`` with derivatives ``dy`` at times ``te``.

    Parameters
    ----------
    t : (n,) array
        Sample times [s], non-decreasing.
    y, dy : (n,) arrays
        Values and their time derivatives at the samples.
    te : float or array
        Query times [s]; clamped to [t[0], t[-1]].

    Returns
    -------
    ndarray
        Interpolated values, same shape as ``te``. For a smooth signal sampled at 1 kHz the
        error is O(h^4) (about 1e-12 m for the torso position of a bounding run).
    """
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    dy = np.asarray(dy, dtype=float)
    te = np.asarray(te, dtype=float)
    n = t.shape[0]
    if n == 0:
        return np.full(te.shape, np.nan)
    if n == 1:
        return np.full(te.shape, y[0])
    tc = np.clip(te, t[0], t[-1])
    i = np.clip(np.searchsorted(t, tc, side="right") - 1, 0, n - 2)
    h = t[i + 1] - t[i]
    ok = h > 0.0
    hs = np.where(ok, h, 1.0)
    s = np.where(ok, (tc - t[i]) / hs, 0.0)
    s2 = s * s
    s3 = s2 * s
    h00 = 2 * s3 - 3 * s2 + 1
    h10 = s3 - 2 * s2 + s
    h01 = -2 * s3 + 3 * s2
    h11 = s3 - s2
    out = h00 * y[i] + h10 * hs * dy[i] + h01 * y[i + 1] + h11 * hs * dy[i + 1]
    # a zero-length interval (duplicate sample time): take the later sample
    return np.where(ok, out, y[np.minimum(i + 1, n - 1)])


def _velocity(result, index):
    return np.asarray(result.state, dtype=float)[:, L.NQ + index]


# -----------------------------------------------------------------------------------------
# stances
# -----------------------------------------------------------------------------------------
def stance_intervals(result, leg) -> np.ndarray:
    """Stance intervals of one virtual leg from the plant's contact events.

    A stance starts at a ``"touchdown"`` event and ends at the next ``"liftoff"`` event of
    the same leg (continuous-time event times; docs/specification.md section 8). A ``"slide_start"`` or any other
    event does not end a stance. A stance still open at the end of the data ends at
    ``result.t_end``. If the first contact event of the leg is a lift-off, the leg started
    the run on the ground and that stance starts at the first sample time ``result.t[0]``.

    Parameters
    ----------
    result : SimulationResult
    leg : {"back", "front", 0, 1}

    Returns
    -------
    (k, 2) ndarray
        Rows ``[t_touchdown, t_liftoff]`` [s], in time order.
    """
    li = _leg(leg)
    ev = _events(result)
    m = (ev[:, 2] == li) & np.isin(ev[:, 1], (L.EK_TOUCHDOWN, L.EK_LIFTOFF))
    sel = ev[m]
    sel = sel[np.argsort(sel[:, 0], kind="stable")]
    t0 = float(result.t[0]) if len(result.t) else 0.0
    out = []
    start = None
    for i, row in enumerate(sel):
        kind = int(row[1])
        if kind == L.EK_TOUCHDOWN:
            if start is None:
                start = float(row[0])
        else:  # lift-off
            if start is not None:
                out.append((start, float(row[0])))
                start = None
            elif i == 0:
                out.append((t0, float(row[0])))
    if start is not None:
        out.append((start, max(float(result.t_end), start)))
    return np.array(out, dtype=float).reshape(-1, 2)


def stance_overlap(intervals: np.ndarray, a: float, b: float) -> float:
    """Total length [s] of the intersection of ``intervals`` with [a, b]."""
    if intervals.shape[0] == 0 or b <= a:
        return 0.0
    lo = np.maximum(intervals[:, 0], a)
    hi = np.minimum(intervals[:, 1], b)
    return float(np.sum(np.clip(hi - lo, 0.0, None)))


# -----------------------------------------------------------------------------------------
# strides
# -----------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Stride:
    """Metrics of one stride, back-leg lift-off to the next (docs/specification.md section 8; paper Sec. IV).

    Supports attribute access (``s.period_s``) and mapping access (``s["period_s"]``,
    ``dict(s)``).

    Attributes
    ----------
    index : int
        Stride number, 0 for the stride starting at the first back-leg lift-off.
    t_start, t_end : float
        Back-leg lift-off times bounding the stride [s].
    period_s : float
        t_end - t_start [s].
    stride_frequency_hz : float
        1 / period_s [Hz] (paper's omega_s).
    duty_factor_back, duty_factor_front : float
        Stance time of that virtual leg inside [t_start, t_end] divided by the period [-]
        (paper's beta), from the continuous-time touchdown / lift-off events.
    pitch_max_deg, pitch_min_deg : float
        Extremes of the torso pitch over the samples inside the stride and the two
        endpoints (interpolated) [deg], nose up positive.
    height_max_m, height_min_m : float
        Extremes of the torso COM height, likewise [m].
    mean_speed_m_s : float
        (x(t_end) - x(t_start)) / period [m/s], x at the event times by cubic Hermite
        interpolation of the sampled position and forward speed.
    steady : bool
        The stride starts at or after the transient and ends before the data end.

    The energy of the stride (None unless the run accounted for its energy,
    ``simulate(energy=True)``) is taken between the control samples nearest to its two
    back-leg lift-offs (``energy_t_start``, ``energy_t_end`` [s]; consecutive strides share
    their boundary sample, so the strides' energies add up to the energy over their
    samples), both virtual legs and every motor of each together:

    electrical_energy_j : float
        Electrical energy into the motor terminals [J] (docs/model.md "Work-energy balance").
    copper_loss_j, transmission_loss_j : float
        Motor copper losses R_A i^2; transmission losses (the paper's constant efficiency,
        signed, and the optional load-dependent losses) [J]. With the hip work they make up
        the electrical energy.
    hip_work_j : float
        Work of the delivered hip torques on the legs [J].
    friction_loss_j : float
        Every friction and damper of the mechanism: motor joint, belt damper, leg damper
        and sliding joint, sliding toes [J].
    impact_loss_j : float
        Kinetic energy lost in the touchdown impacts in [energy_t_start, energy_t_end) [J].
    mechanical_energy_change_j : float
        Change of the mechanical energy (kinetic, gravity, leg and belt springs) [J].
    energy_residual_j : float
        hip_work - friction - constraint work - impacts - mechanical change [J]: the
        integration error of the stride's mechanical balance.
    distance_m : float
        x at energy_t_end less x at energy_t_start [m].
    mean_electrical_power_w : float
        electrical_energy_j over the time between the two samples [W] (Model I / II).
    cost_of_transport : float
        The balance's input (electrical energy for Model I / II, hip work for the ideal
        actuator) over m g distance_m, m the robot's total mass [-].
    """

    index: int
    t_start: float
    t_end: float
    period_s: float
    stride_frequency_hz: float
    duty_factor_back: float
    duty_factor_front: float
    pitch_max_deg: float
    pitch_min_deg: float
    height_max_m: float
    height_min_m: float
    mean_speed_m_s: float
    steady: bool
    energy_t_start: float | None = None
    energy_t_end: float | None = None
    electrical_energy_j: float | None = None
    copper_loss_j: float | None = None
    transmission_loss_j: float | None = None
    hip_work_j: float | None = None
    friction_loss_j: float | None = None
    impact_loss_j: float | None = None
    mechanical_energy_change_j: float | None = None
    energy_residual_j: float | None = None
    distance_m: float | None = None
    mean_electrical_power_w: float | None = None
    cost_of_transport: float | None = None

    def to_dict(self) -> dict:
        """JSON-safe dict (plain int / float / bool; NaN or inf become None)."""
        d = {}
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name == "index":
                d[f.name] = int(v)
            elif f.name == "steady":
                d[f.name] = bool(v)
            else:
                d[f.name] = _json_float(v)
        return d

    # mapping protocol, so that a stride also behaves like the dict it describes
    def keys(self):
        return [f.name for f in fields(self)]

    def __getitem__(self, key):
        if key not in self.keys():
            raise KeyError(key)
        return getattr(self, key)


def _extrema(t, y, dy, a, b):
    """(max, min) of samples of y strictly inside (a, b) plus y(a), y(b) interpolated."""
    ends = _hermite(t, y, dy, np.array([a, b]))
    i0 = np.searchsorted(t, a, side="right")
    i1 = np.searchsorted(t, b, side="left")
    vals = np.concatenate([ends, y[i0:i1]])
    return float(np.max(vals)), float(np.min(vals))


def _strides(result, transient_s, stances):
    t = np.asarray(result.t, dtype=float)
    lo = np.sort(result.event_times("liftoff", "back").astype(float))
    if len(lo) < 2 or len(t) == 0:
        return []
    x = np.asarray(result.x, dtype=float)
    dx = _velocity(result, L.IX)
    th = np.asarray(result.pitch, dtype=float)
    dth = _velocity(result, L.ITH)
    hy = np.asarray(result.height, dtype=float)
    dhy = _velocity(result, L.IY)
    t_end_run = float(result.t_end)
    xs = _hermite(t, x, dx, lo)
    cumulative = {}
    out = []
    for k in range(len(lo) - 1):
        a, b = float(lo[k]), float(lo[k + 1])
        period = b - a
        if not period > 0.0:
            continue  # duplicate event time: not a stride
        pmax, pmin = _extrema(t, th, dth, a, b)
        hmax, hmin = _extrema(t, hy, dhy, a, b)
        out.append(Stride(
            index=len(out), t_start=a, t_end=b, period_s=period,
            stride_frequency_hz=1.0 / period,
            duty_factor_back=stance_overlap(stances[0], a, b) / period,
            duty_factor_front=stance_overlap(stances[1], a, b) / period,
            pitch_max_deg=math.degrees(pmax), pitch_min_deg=math.degrees(pmin),
            height_max_m=hmax, height_min_m=hmin,
            mean_speed_m_s=float(xs[k + 1] - xs[k]) / period,
            steady=bool(a >= transient_s and b <= t_end_run),
            **stride_energy(result, a, b, cumulative)))
    return out


def _input_and_weight(result):
    """(the balance's input flow, m g [N]) of the run: "electrical" for Model I / II,
    "hip_work" for the ideal actuator; (None, None) for the passive model or without the
    robot in the provenance."""
    prov = result.provenance or {}
    robot = prov.get("robot")
    model = prov.get("model")
    if not robot or model not in ("I", "II", "ideal"):
        return None, None
    from ..parameters import RobotParameters
    params = RobotParameters(**robot)
    return ("electrical" if model in ("I", "II") else "hip_work",
            params.total_mass * params.gravity)


def _nearest_sample(t, te: float) -> int:
    i = int(np.searchsorted(t, te))
    if i >= len(t):
        return len(t) - 1
    if i > 0 and te - t[i - 1] <= t[i] - te:
        return i - 1
    return i


def stride_energy(result, a: float, b: float, cumulative: dict | None = None) -> dict:
    """The energy fields of :class:`Stride` for the stride from ``a`` to ``b`` [s] (the
    run's samples nearest to them); {} if the run has no ``energy_series``.
    ``cumulative``: a dict in which the run's cumulative energies by destination
    (``result.cumulative_energy``) are kept from one stride to the next."""
    if getattr(result, "energy_series", None) is None or len(result.t) < 2:
        return {}
    t = np.asarray(result.t, dtype=float)
    i, j = _nearest_sample(t, a), _nearest_sample(t, b)
    if j <= i:
        return {}
    cumulative = {} if cumulative is None else cumulative

    def delta(name):
        if name not in cumulative:
            cumulative[name] = result.cumulative_energy(name)
        return float(cumulative[name][j] - cumulative[name][i])

    imp = result.impacts()
    impacts = float(imp[(imp[:, 0] >= t[i]) & (imp[:, 0] < t[j]), 4].sum())
    mech = float(result.energy[j] - result.energy[i])
    hip = delta("hip_work")
    friction = delta("friction")
    distance = float(result.x[j] - result.x[i])
    input_name, weight = _input_and_weight(result)
    electrical = input_name == "electrical"
    out = {"energy_t_start": float(t[i]), "energy_t_end": float(t[j]),
           "electrical_energy_j": delta("electrical") if electrical else None,
           "copper_loss_j": delta("copper") if electrical else None,
           "transmission_loss_j": delta("transmission") if electrical else None,
           "hip_work_j": hip, "friction_loss_j": friction, "impact_loss_j": impacts,
           "mechanical_energy_change_j": mech,
           "energy_residual_j": hip - friction - delta("constraint") - impacts - mech,
           "distance_m": distance}
    out["mean_electrical_power_w"] = (out["electrical_energy_j"] / float(t[j] - t[i])
                                      if electrical else None)
    out["cost_of_transport"] = (delta(input_name) / (weight * distance)
                                if input_name is not None and distance > 0 else None)
    return out


# -----------------------------------------------------------------------------------------
# the metrics object
# -----------------------------------------------------------------------------------------
@dataclass
class GaitMetrics:
    """Strides and steady-state gait metrics of one run (docs/specification.md section 8; paper Sec. IV, Fig. 12).

    Build with :func:`gait_metrics`. The mean attributes (``mean_speed_m_s``,
    ``stride_frequency_hz``, ``duty_factor_back``, ...; see :data:`STRIDE_METRICS`) are the
    means over the steady strides of the per-stride values; pitch and height means are
    means of the per-stride extrema, as the paper reports. They are None when there is no
    steady stride.

    Attributes
    ----------
    strides : list of Stride
        All complete strides (back-leg lift-off to the next), in time order.
    transient_s : float
        Strides starting before this time [s] are not steady.
    outcome : str
        The run's outcome ("completed", "fell", ...).
    t_end : float
        Time the run reached [s].
    stance : dict
        ``{"back": (k, 2) array, "front": ...}`` stance intervals [s]
        (:func:`stance_intervals`).
    means : dict
        Metric name -> mean over the steady strides (None if there are none).
    """

    strides: list
    transient_s: float
    outcome: str
    t_end: float
    stance: dict
    means: dict = field(default_factory=dict)

    def __post_init__(self):
        steady = self.steady_strides
        self.means = {k: (float(np.mean([s[k] for s in steady])) if steady else None)
                      for k in STRIDE_METRICS}

    # -- counts and steady strides --------------------------------------------------------
    @property
    def steady_strides(self) -> list:
        """Strides with ``steady`` True."""
        return [s for s in self.strides if s.steady]

    @property
    def n_strides(self) -> int:
        return len(self.strides)

    @property
    def n_steady_strides(self) -> int:
        return len(self.steady_strides)

    # -- steady-state means (None without steady strides) --------------------------------
    @property
    def period_s(self):
        """Mean stride period over the steady strides [s]."""
        return self.means["period_s"]

    @property
    def stride_frequency_hz(self):
        """Mean of the per-stride frequencies 1/period over the steady strides [Hz]."""
        return self.means["stride_frequency_hz"]

    @property
    def duty_factor_back(self):
        """Mean back-leg duty factor over the steady strides [-]."""
        return self.means["duty_factor_back"]

    @property
    def duty_factor_front(self):
        """Mean front-leg duty factor over the steady strides [-]."""
        return self.means["duty_factor_front"]

    @property
    def pitch_max_deg(self):
        """Mean of the per-stride maximum pitch over the steady strides [deg]."""
        return self.means["pitch_max_deg"]

    @property
    def pitch_min_deg(self):
        """Mean of the per-stride minimum pitch over the steady strides [deg]."""
        return self.means["pitch_min_deg"]

    @property
    def height_max_m(self):
        """Mean of the per-stride maximum COM height over the steady strides [m]."""
        return self.means["height_max_m"]

    @property
    def height_min_m(self):
        """Mean of the per-stride minimum COM height over the steady strides [m]."""
        return self.means["height_min_m"]

    @property
    def mean_speed_m_s(self):
        """Mean of the per-stride mean forward speeds over the steady strides [m/s]."""
        return self.means["mean_speed_m_s"]

    @property
    def stride_period_cv(self):
        """Coefficient of variation std/mean of the steady stride periods [-].

        Population standard deviation (ddof = 0); None without steady strides."""
        steady = self.steady_strides
        if not steady:
            return None
        p = np.array([s.period_s for s in steady])
        return float(np.std(p) / np.mean(p))

    def is_steady_bounding(self, min_strides: int = 7, max_period_cv: float = 0.05) -> bool:
        """Whether the run is steady bounding.

        True iff the robot did not fall and the integration did not fail (outcome
        "completed", or "interrupted": stopped by the user while it ran), there are at least
        ``min_strides`` steady strides (the paper used >= 7 per run, Sec. IV.C) and the
        stride-period coefficient of variation is at most ``max_period_cv``.
        """
        if (self.outcome not in ("completed", "interrupted")
                or self.n_steady_strides < min_strides):
            return False
        cv = self.stride_period_cv
        return cv is not None and cv <= max_period_cv

    # -- actuator diagnostics -------------------------------------------------------------
    @staticmethod
    def motor_saturation_fraction(result, leg):
        """Fraction of stance-retraction samples at which the motor works on its limits.

        Not the paper's Fig. 11 statement ("the motors are saturated most of the time"),
        which covers the whole step (tests/test_paper_claims.py measures that). A sample with
        controller leg state stance-retraction (``leg_state == 1``) counts as saturated
        when the motor's operating point lies on the boundary of what the amplifier and
        motor can deliver (docs/specification.md section 4): on the current limit, |i| >= (1 - 1e-3) i_max, or
        on the torque-speed line, |R_A i + K_w w_m| >= (1 - 1e-3) V_b. The retraction
        law (eqs. 2-5) commands exactly that boundary, so this measures how much of the
        retraction the motor spends there rather than below it (eq. 5's zero torque, or
        a commanded torque inside the limits).

        Parameters
        ----------
        result : SimulationResult
        leg : {"back", "front", 0, 1}

        Returns
        -------
        float or None
            In [0, 1]; None if the leg never was in stance-retraction or the robot
            parameters are not in the provenance.
        """
        li = _leg(leg)
        robot = (result.provenance or {}).get("robot")
        if not robot:
            return None
        m = result.leg_state(li) == L.LS_RETRACTION
        n = int(np.count_nonzero(m))
        if n == 0:
            return None
        i = np.asarray(result.motor_current(li))[m]
        w = np.asarray(result.motor_speed(li))[m]
        vb = np.asarray(result.battery_voltage)[m]
        on_current = np.abs(i) >= (1.0 - 1e-3) * robot["current_limit"]
        v_term = robot["armature_resistance"] * i + robot["speed_constant"] * w
        on_voltage = np.abs(v_term) >= (1.0 - 1e-3) * vb
        return float(np.count_nonzero(on_current | on_voltage) / n)

    @staticmethod
    def max_belt_deflection_deg(result):
        """Largest |belt deflection alpha - phi| of both legs over the run [deg] (Model II;
        0 for the other variants); None if there are no samples."""
        if len(result.t) == 0:
            return None
        b = np.concatenate([np.asarray(result.belt_deflection(0)),
                            np.asarray(result.belt_deflection(1))])
        return _json_float(math.degrees(float(np.max(np.abs(b)))))

    # -- export ---------------------------------------------------------------------------
    def summary(self, result) -> dict:
        """JSON-safe run summary (docs/specification.md section 8; paper Fig. 12 quantities).

        Keys, in order: :data:`SUMMARY_KEYS` (outcome, steady-state means, the maximum
        ratio |tangential|/normal ground force ``max_friction_ratio`` from
        ``result.stats``, the number of steady strides), then :data:`SUMMARY_EXTRA_KEYS`,
        then what the gait costs, :data:`SUMMARY_ENERGY_KEYS` (:meth:`energy_summary`).
        Missing or non-finite values are None (JSON null), never NaN.

        Parameters
        ----------
        result : SimulationResult
            The run these metrics were computed from.
        """
        stats = result.stats or {}
        prov = result.provenance or {}
        out = {"outcome": self.outcome}
        for k in SUMMARY_KEYS[1:9]:
            out[k] = _json_float(self.means[k])
        out["max_friction_ratio"] = _json_float(stats.get("max_friction_ratio"))
        out["n_steady_strides"] = self.n_steady_strides
        out["t_end_s"] = _json_float(self.t_end)
        out["n_strides"] = self.n_strides
        out["stride_period_cv"] = _json_float(self.stride_period_cv)
        out["steady_bounding"] = bool(self.is_steady_bounding())
        out["motor_saturation_retraction_back"] = _json_float(
            self.motor_saturation_fraction(result, 0))
        out["motor_saturation_retraction_front"] = _json_float(
            self.motor_saturation_fraction(result, 1))
        out["max_belt_deflection_deg"] = self.max_belt_deflection_deg(result)
        out["max_impact_impulse_ratio"] = _json_float(stats.get("max_impact_impulse_ratio"))
        out["end_of_stance_slides"] = _json_number(stats.get("end_of_stance_slides"))
        out["model"] = prov.get("model")
        out.update(self.energy_summary(result))
        return out

    def energy_summary(self, result) -> dict:
        """What the run's gait costs (the keys of :data:`SUMMARY_ENERGY_KEYS`), JSON-safe.

        Over the whole run (``result.energy_flows``; a streamed run's too, though its
        result holds only its end), in J: ``electrical_energy_j`` into the motor
        terminals, ``copper_loss_j``, ``transmission_loss_j`` (signed; the three make up
        the electrical energy with ``hip_work_j``), ``hip_work_j``, ``friction_loss_j``
        (every friction and damper of the mechanism), ``impact_loss_j`` (touchdown
        impacts), ``mechanical_energy_change_j`` and the balance's ``energy_residual_j``
        (input less every term; ``energy_relative_residual``: relative to the input), as
        :meth:`~scoutsim.result.SimulationResult.energy_balance` gives them.

        Over the steady strides (from the first steady stride's start to the last one's
        end, the samples nearest to the back-leg lift-offs): ``mean_electrical_power_w``
        [W] and ``cost_of_transport`` = E / (m g d) [-], E the balance's input (electrical
        energy for Model I / II, hip work for the ideal actuator), m the robot's total
        mass (``RobotParameters.total_mass``), g gravity, d the distance the torso
        travelled; None without steady strides.

        Every key is None when the run was made without the energy accounting
        (``simulate(energy=False)``, ``scoutsim run --no-energy``); the electrical keys
        are None for the ideal actuator and the passive model (no electrical side), the
        cost of transport for the passive model (no input)."""
        out = dict.fromkeys(SUMMARY_ENERGY_KEYS)
        if getattr(result, "energy_flows", None) is None:
            return out
        b = result.energy_balance()
        electrical = b.model in ("I", "II")
        friction = sum(b.term(n) for n in ("joint_friction", "belt_damper", "leg_damper",
                                           "leg_friction", "toe_sliding"))
        out.update({
            "electrical_energy_j": b.input_J if electrical else None,
            "copper_loss_j": b.term("copper") if electrical else None,
            "transmission_loss_j": b.term("transmission") if electrical else None,
            "hip_work_j": b.hip_work_J, "friction_loss_j": friction,
            "impact_loss_j": b.term("impacts"),
            "mechanical_energy_change_j": b.term("mechanical_change"),
            "energy_residual_j": b.residual_J,
            "energy_relative_residual": b.relative_residual})
        steady = [st for st in self.steady_strides if st.distance_m is not None]
        if steady:
            span = sum(st.energy_t_end - st.energy_t_start for st in steady)
            distance = sum(st.distance_m for st in steady)
            if electrical:
                out["mean_electrical_power_w"] = sum(st.electrical_energy_j
                                                     for st in steady) / span
            input_name, weight = _input_and_weight(result)
            if input_name is not None and distance > 0:
                energy = sum(st.electrical_energy_j if electrical else st.hip_work_j
                             for st in steady)
                out["cost_of_transport"] = energy / (weight * distance)
        return {k: _json_float(v) for k, v in out.items()}

    def to_dict(self) -> dict:
        """JSON-safe dict: transient, outcome, counts, means, period CV and all strides."""
        return {"transient_s": float(self.transient_s), "outcome": self.outcome,
                "t_end_s": _json_float(self.t_end), "n_strides": self.n_strides,
                "n_steady_strides": self.n_steady_strides,
                "means": {k: _json_float(v) for k, v in self.means.items()},
                "stride_period_cv": _json_float(self.stride_period_cv),
                "strides": [s.to_dict() for s in self.strides]}


def converged_tail(strides, tol):
    """Keep ``steady`` only for the contiguous final run of candidate strides whose period
    lies within ``tol`` (relative) of the median period of the last seven candidates: the
    gait has converged there. Earlier strides are transient however late they start."""
    cand = [i for i, st in enumerate(strides) if st.steady]
    if not cand:
        return strides
    ref = float(np.median([strides[i].period_s for i in cand[-7:]]))
    first = len(strides)
    for i in reversed(cand):
        if abs(strides[i].period_s - ref) <= tol * ref and (first == len(strides) or i == first - 1):
            first = i
        else:
            break
    return [dataclasses.replace(st, steady=(i >= first and st.steady))
            for i, st in enumerate(strides)]


def gait_metrics(result, transient_s: float = 2.0, period_tolerance: float = 0.05) -> GaitMetrics:
    """Split a run into strides and compute the gait metrics (docs/specification.md section 8; paper Sec. IV).

    Parameters
    ----------
    result : SimulationResult
        The run (``t``, ``state``, ``events``, ``outcome``, ``t_end``, ``stats``,
        ``provenance``).
    transient_s : float
        Strides that start before this time [s] are part of the transient and excluded
        from the steady-state means (default 2 s).
    period_tolerance : float
        Steady strides are the final contiguous strides (after ``transient_s``) whose
        period is within this fraction of the median of the last seven (default 5 %):
        a slow transient is not averaged into the steady state.

    Returns
    -------
    GaitMetrics
        All strides (back-leg lift-off to the next back-leg lift-off), their metrics and
        the means over the steady strides.
    """
    if not (isinstance(transient_s, (int, float)) and math.isfinite(transient_s)
            and transient_s >= 0):
        raise ValueError(f"transient_s = {transient_s!r} is not allowed: must be a finite "
                         "number >= 0")
    if not (isinstance(period_tolerance, (int, float)) and 0 < period_tolerance < 1):
        raise ValueError(f"period_tolerance = {period_tolerance!r} is not allowed: must be "
                         "in (0, 1)")
    stances = (stance_intervals(result, 0), stance_intervals(result, 1))
    strides = converged_tail(_strides(result, float(transient_s), stances), period_tolerance)
    return GaitMetrics(strides=strides, transient_s=float(transient_s),
                       outcome=str(result.outcome), t_end=float(result.t_end),
                       stance={"back": stances[0], "front": stances[1]})


def stride_table(result, transient_s: float = 2.0) -> dict:
    """Per-stride metrics as columns, one row per stride (for CSV export / DataFrames).

    Parameters
    ----------
    result : SimulationResult
    transient_s : float
        As in :func:`gait_metrics` [s].

    Returns
    -------
    dict of str -> ndarray
        Columns ``index`` (int), ``t_start``, ``t_end`` [s], the metrics of
        :data:`STRIDE_METRICS` (units in their names), for a run with the energy
        accounting ``energy_t_start``, ``energy_t_end`` [s] and
        :data:`STRIDE_ENERGY_METRICS` (NaN where a stride's is None), and ``steady``
        (bool); each of length ``n_strides``.
    """
    strides = gait_metrics(result, transient_s).strides
    cols = {"index": np.array([s.index for s in strides], dtype=int),
            "t_start": np.array([s.t_start for s in strides], dtype=float),
            "t_end": np.array([s.t_end for s in strides], dtype=float)}
    for k in STRIDE_METRICS:
        cols[k] = np.array([s[k] for s in strides], dtype=float)
    if strides and strides[0].energy_t_start is not None:
        for k in ("energy_t_start", "energy_t_end") + STRIDE_ENERGY_METRICS:
            cols[k] = np.array([np.nan if s[k] is None else s[k] for s in strides],
                               dtype=float)
    cols["steady"] = np.array([s.steady for s in strides], dtype=bool)
    return cols
