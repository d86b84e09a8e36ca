"""Strides of a run and the metrics of each (docs/specification.md section 8; paper
Sec. IV).

A **stride** runs from one back-leg lift-off to the next (paper Sec. IV.C: "steady state
strides defined by the back leg lift-off event"). :class:`Stride` holds what the paper
compares between simulation and experiment (Fig. 12): period and stride frequency, duty
factor of each virtual leg, maximum and minimum torso pitch and COM height, mean forward
speed, and what the stride costs (:mod:`scoutsim.analysis.stride_energy`).
:func:`converged_tail` marks as steady the final strides whose period has converged.

Units: seconds, metres, m/s, Hz, degrees for the pitch extremes, J and W for the energy.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, fields

import numpy as np

from ..result.stride_record import record_strides
from .stances import stance_overlap
from .stride_energy import StrideCosts

__all__ = [
    "Stride",
    "converged_tail",
    "STRIDE_METRICS",
    "STRIDE_ENERGY_METRICS",
    "MIN_STEADY_STRIDES",
    "PERIOD_TOLERANCE",
]

#: Steady strides that make a run steady bounding (the paper used at least 7 per run,
#: Sec. IV.C).
MIN_STEADY_STRIDES = 7
#: Relative spread of the stride periods within which a gait has converged (5 %).
PERIOD_TOLERANCE = 0.05

#: Per-stride numeric metrics that are averaged over the steady strides.
STRIDE_METRICS = (
    "period_s",
    "stride_frequency_hz",
    "duty_factor_back",
    "duty_factor_front",
    "pitch_max_deg",
    "pitch_min_deg",
    "height_max_m",
    "height_min_m",
    "mean_speed_m_s",
)

#: Per-stride energy fields of :class:`Stride` (None without the energy accounting).
STRIDE_ENERGY_METRICS = (
    "electrical_energy_j",
    "copper_loss_j",
    "transmission_loss_j",
    "hip_work_j",
    "friction_loss_j",
    "impact_loss_j",
    "mechanical_energy_change_j",
    "energy_residual_j",
    "distance_m",
    "mean_electrical_power_w",
    "cost_of_transport",
)


def json_float(v):
    """float(v), or None if v is None, NaN or infinite (JSON has no NaN/inf)."""
    if v is None:
        return None
    v = float(v)
    return v if math.isfinite(v) else None


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
                d[f.name] = json_float(v)
        return d

    # mapping protocol, so that a stride also behaves like the dict it describes
    def keys(self):
        return [f.name for f in fields(self)]

    def __getitem__(self, key):
        if key not in self.keys():
            raise KeyError(key)
        return getattr(self, key)


def split_strides(result, transient_s, stances, record=None):
    """The strides of ``result`` (:class:`Stride` in time order) from its
    :class:`~scoutsim.result.stride_record.StrideRecord` (``record``, default
    :func:`~scoutsim.result.stride_record.record_strides` of the result) and the stance
    intervals of its two virtual legs (``stances``); strides that start before
    ``transient_s`` [s] are not steady."""
    record = record_strides(result) if record is None else record
    lift, inner = record.liftoffs, record.interior
    lo = lift["t"]
    if len(lo) < 2 or record.n_samples == 0:
        return []
    t_end_run = float(result.t_end)
    # each stride's stances, found once for all strides: the rows of each leg's intervals
    # (disjoint, in time order) that end at or after the stride's start and begin at or
    # before its end, so that the split is linear in the run's length
    meets = [
        (
            np.searchsorted(iv[:, 1], lo[:-1], side="left"),
            np.searchsorted(iv[:, 0], lo[1:], side="right"),
        )
        for iv in stances
    ]
    costs = StrideCosts(result, record)
    out = []
    for k in range(len(lo) - 1):
        a, b = float(lo[k]), float(lo[k + 1])
        legs = [iv[first[k] : last[k]] for iv, (first, last) in zip(stances, meets)]
        period = b - a
        if not period > 0.0:
            continue  # duplicate event time: not a stride
        pitch = np.array([lift["pitch"][k], lift["pitch"][k + 1], inner["pitch_max"][k]])
        pitch_low = np.array([lift["pitch"][k], lift["pitch"][k + 1], inner["pitch_min"][k]])
        height = np.array([lift["height"][k], lift["height"][k + 1], inner["height_max"][k]])
        height_low = np.array([lift["height"][k], lift["height"][k + 1], inner["height_min"][k]])
        out.append(
            Stride(
                index=len(out),
                t_start=a,
                t_end=b,
                period_s=period,
                stride_frequency_hz=1.0 / period,
                duty_factor_back=stance_overlap(legs[0], a, b) / period,
                duty_factor_front=stance_overlap(legs[1], a, b) / period,
                pitch_max_deg=math.degrees(float(np.max(pitch))),
                pitch_min_deg=math.degrees(float(np.min(pitch_low))),
                height_max_m=float(np.max(height)),
                height_min_m=float(np.min(height_low)),
                mean_speed_m_s=float(lift["x"][k + 1] - lift["x"][k]) / period,
                steady=bool(a >= transient_s and b <= t_end_run),
                **costs.of(k),
            )
        )
    return out


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
        if abs(strides[i].period_s - ref) <= tol * ref and (
            first == len(strides) or i == first - 1
        ):
            first = i
        else:
            break
    return [
        dataclasses.replace(st, steady=(i >= first and st.steady)) for i, st in enumerate(strides)
    ]
