"""The experiment's measurement chain, simulated (docs/specification.md section 8; paper Sec. IV.B).

On Scout II, torso pitch and COM height were measured with two laser range finders at the
front and back ends of the torso, and the laser data were low-pass filtered at 15 Hz after
the fact via FFT; hip torques were estimated from the motor currents as ``N eta K_T i``.
This module reproduces that chain so that a simulation can be turned into exactly what the
robot would have logged (:func:`to_log`), and compared with a log like with like.

    log = to_log(result)                       # noise-free
    log = to_log(result, noise=SensorNoise(), seed=1)

Laser geometry: see :mod:`scoutsim.validation.log_format` ("Laser geometry").

Low-pass (:func:`fft_lowpass`): zero-phase, applied in the frequency domain with
``numpy.fft``. Gain 1 below ``cutoff - transition/2``, 0 above ``cutoff + transition/2``,
a raised cosine in between (gain 1/2 at the cut-off); ``transition_hz = 0`` is a
brick-wall. Default 15 Hz with a 5 Hz transition (pass band to 12.5 Hz, stop band from
17.5 Hz): a smooth cut keeps the filter's impulse response short, so edge effects die out
within about 0.3 s of the ends of a record. Before the FFT the record is extended at each
end by up to ``pad_s`` (1 s) of its odd reflection about the end value (continuous value
and slope, as ``scipy.signal.filtfilt``'s padding), which avoids the wrap-around jump of a
plain FFT; the extension is dropped afterwards. Within ``EDGE_S`` of either end the result
is affected by the unknown signal outside the record; stride analysis ignores strides there.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from ..names import LEG_NAMES
from ..parameters import RobotParameters
from .experiment_log import ExperimentLog
from .torso_sensors import (
    EDGE_S,
    LaserGeometry,
    fft_lowpass,
    laser_ranges,
    lowpass_gain,
    pitch_height_from_lasers,
)

__all__ = [
    "LaserGeometry",
    "SensorNoise",
    "laser_ranges",
    "pitch_height_from_lasers",
    "fft_lowpass",
    "lowpass_gain",
    "torque_from_current",
    "torque_per_amp",
    "to_log",
    "EDGE_S",
]


@dataclass(frozen=True)
class SensorNoise:
    """Standard deviations of white Gaussian sensor noise added by :func:`to_log`
    (defaults: a plausible small-robot sensor suite [assumed]).

    laser_m : laser range noise [m]; angle_rad, rate_rad_s : encoder angle / rate noise;
    current_a : current-sense noise [A].
    """

    laser_m: float = 1.0e-3
    angle_rad: float = 2.0e-3
    rate_rad_s: float = 0.05
    current_a: float = 0.1


def torque_per_amp(robot, leg=None):
    """N eta K_T [N m/A] of a RobotParameters or its dict (``provenance["robot"]``): of leg
    ``leg`` ("back" / 0, "front" / 1), or, for ``leg`` None, the one value of both legs, or
    [back, front] when their motors or transmissions differ."""
    if isinstance(robot, dict):
        robot = RobotParameters(**robot)
    if leg is not None:
        return float(robot.leg(leg).torque_per_amp)
    back, front = (float(robot.leg(i).torque_per_amp) for i in (0, 1))
    return back if back == front else [back, front]


def torque_from_current(current, robot, leg=0) -> np.ndarray:
    """Hip torque per physical leg of leg ``leg`` estimated from motor current,
    ``N eta K_T i`` [N m]."""
    return torque_per_amp(robot, leg) * np.asarray(current, dtype=float)


def _on_grid(result):
    """Indices of the samples on the controller grid (drops a final off-grid sample of a run
    that fell or failed)."""
    t = np.asarray(result.t, dtype=float)
    dt = float((result.provenance or {}).get("control_period_s") or 1e-3)
    k = t / dt
    return np.flatnonzero(np.abs(k - np.round(k)) < 1e-6)


def to_log(
    result,
    noise: SensorNoise | dict | None = None,
    seed=None,
    geometry: LaserGeometry | None = None,
    lowpass_hz: float | None = 15.0,
    lowpass_transition_hz: float = 5.0,
    source: str | None = None,
    notes: str = "",
    synthetic: bool = True,
) -> ExperimentLog:
    """What the robot would have logged during the simulated run ``result``.

    Columns: laser ranges (from the simulated pitch and height, :func:`laser_ranges`), leg
    angles and rates as the hip encoders see them (motor-side angle alpha for Model II when
    the controller senses the motor angle, as the robot's encoders sit on the motors; phi
    otherwise), motor currents, controller leg states, leg lengths. Optional white Gaussian
    noise (``noise``: :class:`SensorNoise` or a dict of its fields; ``seed`` for numpy's
    default_rng) is added to the sensors, never to the leg states. The log's metadata holds
    the geometry, the low-pass setting (applied by :attr:`ExperimentLog.pitch`), N eta K_T,
    ``synthetic = True`` and the simulation's provenance.
    """
    geometry = geometry or LaserGeometry()
    k = _on_grid(result)
    prov = result.provenance or {}
    t = np.asarray(result.t, dtype=float)[k]
    robot = prov.get("robot")
    ctrl = prov.get("controller") or {}
    encoder_on_motor = prov.get("model") == "II" and bool(ctrl.get("sense_motor_angle", True))

    def sampled(series):
        return np.asarray(series, dtype=float)[k]

    rf, rb = laser_ranges(sampled(result.height), sampled(result.pitch), geometry)
    cols = {"t": t, "laser_front_m": rf, "laser_back_m": rb}
    for leg, name in enumerate(LEG_NAMES):
        if encoder_on_motor:
            angle, rate = result.motor_angle(leg), result.motor_angle_rate(leg)
        else:
            angle, rate = result.leg_angle(leg), result.leg_rate(leg)
        cols[f"phi_{name}_rad"] = sampled(angle)
        cols[f"dphi_{name}_rad_s"] = sampled(rate)
    for leg, name in enumerate(LEG_NAMES):
        cols[f"current_{name}_a"] = sampled(result.motor_current(leg))
    for leg, name in enumerate(LEG_NAMES):
        cols[f"leg_state_{name}"] = np.asarray(result.leg_state(leg), dtype=float)[k]
    for leg, name in enumerate(LEG_NAMES):
        cols[f"leg_length_{name}_m"] = sampled(result.leg_length(leg))
    if noise is not None:
        nz = noise if isinstance(noise, SensorNoise) else SensorNoise(**dict(noise))
        rng = np.random.default_rng(seed)
        n = t.shape[0]
        for c in cols:
            sd = (
                nz.laser_m
                if c.startswith("laser_")
                else nz.angle_rad
                if c.startswith("phi_")
                else nz.rate_rad_s
                if c.startswith("dphi_")
                else nz.current_a
                if c.startswith("current_")
                else 0.0
            )
            if sd > 0:
                cols[c] = cols[c] + rng.normal(0.0, sd, n)
    meta = {
        "source": source
        or f"scoutsim {prov.get('scoutsim_version', '')} simulation, model {prov.get('model')}",
        "synthetic": bool(synthetic),
        "notes": notes,
        "laser_half_spacing_m": geometry.half_spacing_m,
        "laser_mount_offset_m": geometry.mount_offset_m,
        "lowpass_hz": lowpass_hz,
        "lowpass_transition_hz": lowpass_transition_hz,
        "torque_per_amp_nm_a": torque_per_amp(robot) if robot else None,
        "encoder": "motor-side angle alpha" if encoder_on_motor else "leg angle phi",
        "sensor_noise": None
        if noise is None
        else asdict(noise if isinstance(noise, SensorNoise) else SensorNoise(**dict(noise))),
        "noise_seed": seed if (seed is None or isinstance(seed, int)) else str(seed),
        "simulation": {
            "model": prov.get("model"),
            "outcome": result.outcome,
            "t_end_s": float(result.t_end),
            "friction_coefficient": prov.get("friction_coefficient"),
            "initial_state": prov.get("initial_state"),
            "robot": robot,
        },
    }
    return ExperimentLog(columns=cols, meta=meta, path=None)


def to_log_like(result, like: ExperimentLog | None = None) -> ExperimentLog:
    """:func:`to_log` (noise-free) with the laser geometry and filter of the log ``like``
    (its metadata), or the defaults without one: a simulation measured the way an
    experiment was."""
    kw: dict[str, Any] = {}
    if like is not None:
        kw = dict(
            geometry=LaserGeometry(
                float(like.meta["laser_half_spacing_m"]), float(like.meta["laser_mount_offset_m"])
            ),
            lowpass_hz=like.meta.get("lowpass_hz"),
            lowpass_transition_hz=float(like.meta.get("lowpass_transition_hz") or 0.0),
        )
    return to_log(result, **kw)
