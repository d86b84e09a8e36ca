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

The parts have their own modules: :mod:`~scoutsim.analysis.stances` (stance intervals
from the contact events), :mod:`~scoutsim.analysis.strides` (the :class:`Stride` record,
the split into strides, the converged tail), :mod:`~scoutsim.analysis.stride_energy`
(what a stride costs) and :mod:`~scoutsim.result.interpolation` (values between
samples). This module holds the metrics of a whole run and re-exports the public names.

Public API
----------
gait_metrics(result, transient_s=2.0) -> GaitMetrics
stance_intervals(result, leg) -> (k, 2) array of [touchdown, lift-off] times [s]
stride_table(result, transient_s=2.0) -> dict of column arrays (one row per stride)
Stride, GaitMetrics, SUMMARY_KEYS, STRIDE_METRICS
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..names import leg_index
from ..parameters import RobotParameters
from ..result.stride_record import record_strides, retraction_saturation
from .behaviour import classify_behaviour
from .stances import stance_intervals, stance_overlap, stances_of_contacts
from .stride_energy import input_and_weight, stride_energy
from .strides import (
    MIN_STEADY_STRIDES,
    PERIOD_TOLERANCE,
    STRIDE_ENERGY_METRICS,
    STRIDE_METRICS,
    Stride,
    converged_tail,
    json_float,
    split_strides,
)

__all__ = [
    "gait_metrics",
    "stance_intervals",
    "stride_table",
    "stride_energy",
    "Stride",
    "GaitMetrics",
    "SUMMARY_KEYS",
    "SUMMARY_EXTRA_KEYS",
    "SUMMARY_BEHAVIOUR_KEYS",
    "SUMMARY_ENERGY_KEYS",
    "STRIDE_METRICS",
    "STRIDE_ENERGY_METRICS",
    "stance_overlap",
    "converged_tail",
]

#: Keys that :meth:`GaitMetrics.summary` returns first, in this order.
SUMMARY_KEYS = (
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
)
#: Keys that follow :data:`SUMMARY_KEYS` in :meth:`GaitMetrics.summary`, in this order.
SUMMARY_EXTRA_KEYS = (
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
)
#: Keys that follow :data:`SUMMARY_EXTRA_KEYS` in :meth:`GaitMetrics.summary`: what the run
#: did (:func:`~scoutsim.analysis.behaviour.classify_behaviour`): the sentence, its kind
#: and the counts it was decided from (with the time and the advice).
SUMMARY_BEHAVIOUR_KEYS = ("behaviour", "behaviour_kind", "behaviour_detail")
#: Keys that follow :data:`SUMMARY_BEHAVIOUR_KEYS` in :meth:`GaitMetrics.summary`: what the
#: gait costs (all None for a run made without the energy accounting).
SUMMARY_ENERGY_KEYS = (
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
)

#: Current mismatch [A] above which the amplifier/motor limit counts as active.
SATURATION_TOLERANCE_A = 1e-6


def _json_number(v):
    """Like :func:`json_float`, but integral values become int (counts in ``stats``)."""
    v = json_float(v)
    if v is not None and v.is_integer():
        return int(v)
    return v


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
        self.means = {
            k: (float(np.mean([s[k] for s in steady])) if steady else None) for k in STRIDE_METRICS
        }

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

    def is_steady_bounding(
        self, min_strides: int = MIN_STEADY_STRIDES, max_period_cv: float = 0.05
    ) -> bool:
        """Whether the run is steady bounding.

        True iff the robot did not fall and the integration did not fail (outcome
        "completed", or "interrupted": stopped by the user while it ran), there are at least
        ``min_strides`` steady strides (the paper used >= 7 per run, Sec. IV.C) and the
        stride-period coefficient of variation is at most ``max_period_cv``.
        """
        if self.outcome not in ("completed", "interrupted") or self.n_steady_strides < min_strides:
            return False
        cv = self.stride_period_cv
        return cv is not None and cv <= max_period_cv

    def behaviour(self, result):
        """What the run did: steady bounding, or what instead
        (:func:`~scoutsim.analysis.behaviour.classify_behaviour`, from these strides)."""
        return classify_behaviour(result, self)

    # -- actuator diagnostics -------------------------------------------------------------
    @staticmethod
    def motor_saturation_fraction(result, leg):
        """Fraction of stance-retraction samples at which the motor works on its limits.

        Not the paper's Fig. 11 statement ("the motors are saturated most of the time"),
        which covers the whole step (tests/test_paper_claims.py measures that). A sample with
        controller leg state stance-retraction (``LegState.RETRACTION``) counts as saturated
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
        li = leg_index(leg)
        record = getattr(result, "stride_record", None)
        if record is not None and record.saturation is not None:  # from every sample
            n, n_saturated = record.saturation[li]
        else:
            robot = (result.provenance or {}).get("robot")
            if not robot:
                return None
            n, n_saturated = retraction_saturation(result, li, RobotParameters(**robot).leg(li))
        if n == 0:
            return None
        return float(n_saturated / n)

    @staticmethod
    def max_belt_deflection_deg(result):
        """Largest |belt deflection alpha - phi| of both legs over the run [deg] (Model II;
        0 for the other variants); None if there are no samples."""
        record = getattr(result, "stride_record", None)
        if record is not None and record.belt_deflection_max is not None:  # every sample
            return json_float(math.degrees(record.belt_deflection_max))
        if len(result.t) == 0:
            return None
        b = np.concatenate(
            [np.asarray(result.belt_deflection(0)), np.asarray(result.belt_deflection(1))]
        )
        return json_float(math.degrees(float(np.max(np.abs(b)))))

    # -- export ---------------------------------------------------------------------------
    def summary(self, result) -> dict:
        """JSON-safe run summary (docs/specification.md section 8; paper Fig. 12 quantities).

        Keys, in order: :data:`SUMMARY_KEYS` (outcome, steady-state means, the maximum
        ratio |tangential|/normal ground force ``max_friction_ratio`` from
        ``result.stats``, the number of steady strides), then :data:`SUMMARY_EXTRA_KEYS`,
        then what the run did, :data:`SUMMARY_BEHAVIOUR_KEYS` (``behaviour``: the
        sentence, e.g. "steady bounding at 1.39 m/s, 4.27 Hz (76 steady strides)" or
        "fell at t = 0.66 s: the torso touched the ground, after 0 strides";
        ``behaviour_kind``: one of :data:`~scoutsim.analysis.behaviour.BEHAVIOUR_KINDS`;
        ``behaviour_detail``: :meth:`Behaviour.to_dict
        <scoutsim.analysis.behaviour.Behaviour.to_dict>` without the sentence and kind:
        the time, the advice and the counts), then what the gait costs, :data:`SUMMARY_ENERGY_KEYS` (:meth:`energy_summary`).
        Missing or non-finite values are None (JSON null), never NaN.

        Parameters
        ----------
        result : SimulationResult
            The run these metrics were computed from.
        """
        stats = result.stats or {}
        prov = result.provenance or {}
        out: dict[str, Any] = {"outcome": self.outcome}
        for k in SUMMARY_KEYS[1:9]:
            out[k] = json_float(self.means[k])
        out["max_friction_ratio"] = json_float(stats.get("max_friction_ratio"))
        out["n_steady_strides"] = self.n_steady_strides
        out["t_end_s"] = json_float(self.t_end)
        out["n_strides"] = self.n_strides
        out["stride_period_cv"] = json_float(self.stride_period_cv)
        out["steady_bounding"] = bool(self.is_steady_bounding())
        out["motor_saturation_retraction_back"] = json_float(
            self.motor_saturation_fraction(result, 0)
        )
        out["motor_saturation_retraction_front"] = json_float(
            self.motor_saturation_fraction(result, 1)
        )
        out["max_belt_deflection_deg"] = self.max_belt_deflection_deg(result)
        out["max_impact_impulse_ratio"] = json_float(stats.get("max_impact_impulse_ratio"))
        out["end_of_stance_slides"] = _json_number(stats.get("end_of_stance_slides"))
        out["model"] = prov.get("model")
        what = self.behaviour(result).to_dict()
        out["behaviour"] = what.pop("text")
        out["behaviour_kind"] = what.pop("kind")
        out["behaviour_detail"] = what
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
        :meth:`~scoutsim.result.simulation_result.SimulationResult.energy_balance` gives them.

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
        friction = sum(
            b.term(n)
            for n in ("joint_friction", "belt_damper", "leg_damper", "leg_friction", "toe_sliding")
        )
        out.update(
            {
                "electrical_energy_j": b.input_J if electrical else None,
                "copper_loss_j": b.term("copper") if electrical else None,
                "transmission_loss_j": b.term("transmission") if electrical else None,
                "hip_work_j": b.hip_work_J,
                "friction_loss_j": friction,
                "impact_loss_j": b.term("impacts"),
                "mechanical_energy_change_j": b.term("mechanical_change"),
                "energy_residual_j": b.residual_J,
                "energy_relative_residual": b.relative_residual,
            }
        )
        steady = [st for st in self.steady_strides if st.distance_m is not None]
        if steady:
            span = sum(st.energy_t_end - st.energy_t_start for st in steady)
            distance = sum(st.distance_m for st in steady)
            if electrical:
                out["mean_electrical_power_w"] = sum(st.electrical_energy_j for st in steady) / span
            input_name, weight = input_and_weight(result)
            if input_name is not None and distance > 0:
                energy = sum(
                    st.electrical_energy_j if electrical else st.hip_work_j for st in steady
                )
                out["cost_of_transport"] = energy / (weight * distance)
        return {k: json_float(v) for k, v in out.items()}

    def to_dict(self) -> dict:
        """JSON-safe dict: transient, outcome, counts, means, period CV and all strides."""
        return {
            "transient_s": float(self.transient_s),
            "outcome": self.outcome,
            "t_end_s": json_float(self.t_end),
            "n_strides": self.n_strides,
            "n_steady_strides": self.n_steady_strides,
            "means": {k: json_float(v) for k, v in self.means.items()},
            "stride_period_cv": json_float(self.stride_period_cv),
            "strides": [s.to_dict() for s in self.strides],
        }


def gait_metrics(
    result, transient_s: float = 2.0, period_tolerance: float = PERIOD_TOLERANCE
) -> GaitMetrics:
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
    if not (
        isinstance(transient_s, (int, float)) and math.isfinite(transient_s) and transient_s >= 0
    ):
        raise ValueError(
            f"transient_s = {transient_s!r} is not allowed: must be a finite number >= 0"
        )
    if not (isinstance(period_tolerance, (int, float)) and 0 < period_tolerance < 1):
        raise ValueError(
            f"period_tolerance = {period_tolerance!r} is not allowed: must be in (0, 1)"
        )
    record = record_strides(result)
    if getattr(result, "stride_record", None) is not None:  # the whole run's contacts
        t_first = record.t_first if record.t_first is not None else 0.0
        stances = tuple(
            stances_of_contacts(*record.contact_log(leg), t_first, float(result.t_end))
            for leg in (0, 1)
        )
    else:
        stances = (stance_intervals(result, 0), stance_intervals(result, 1))
    strides = converged_tail(
        split_strides(result, float(transient_s), stances, record), period_tolerance
    )
    return GaitMetrics(
        strides=strides,
        transient_s=float(transient_s),
        outcome=str(result.outcome),
        t_end=float(result.t_end),
        stance={"back": stances[0], "front": stances[1]},
    )


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
    cols = {
        "index": np.array([s.index for s in strides], dtype=int),
        "t_start": np.array([s.t_start for s in strides], dtype=float),
        "t_end": np.array([s.t_end for s in strides], dtype=float),
    }
    for k in STRIDE_METRICS:
        cols[k] = np.array([s[k] for s in strides], dtype=float)
    if strides and strides[0].energy_t_start is not None:
        for k in ("energy_t_start", "energy_t_end") + STRIDE_ENERGY_METRICS:
            cols[k] = np.array([np.nan if s[k] is None else s[k] for s in strides], dtype=float)
    cols["steady"] = np.array([s.steady for s in strides], dtype=bool)
    return cols
