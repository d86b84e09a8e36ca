"""A rig log prepared for the fit (:class:`RigData`): which rig made it and how to replay
it, the legs that move, the logged motor-encoder angle [rad] and motor current [A] to
match, their sensor noise (the residuals' weights); and the rig replayed with trial
parameters (:func:`simulate_log`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..names import LEG_NAMES
from ..parameters import RobotParameters
from ..validation.experiment_log import ExperimentLog
from ..validation.log_format import LogError
from ..validation.log_reading import load_log
from .rigs import FlightSteps, FreeSwing, RigNoise, run_rig

__all__ = [
    "RigData",
    "prepare_log",
    "prepare_logs",
    "simulate_log",
    "MIN_MOTION_RAD",
    "FITTABLE_RIGS",
]

#: A leg whose logged angle spans less than this [rad] does not count as moving.
MIN_MOTION_RAD = 0.01
FITTABLE_RIGS = ("free-swing", "flight-steps")


@dataclass
class RigData:
    """One log prepared for fitting: the rig to replay and the signals to match."""

    log: ExperimentLog
    rig: object
    dt: float
    legs: tuple  # indices of the legs that move (fitted)
    angle: np.ndarray  # (n, 2) logged encoder angle [rad]
    current: np.ndarray | None  # (n, 2) logged current [A], or None if not used
    sigma_angle: float
    sigma_current: float
    touchdown_commands: np.ndarray | None = None

    @property
    def name(self) -> str:
        return self.log.name

    @property
    def n_residuals(self) -> int:
        n = self.angle.shape[0] * len(self.legs)
        return n * (2 if self.current is not None else 1)


def _meta_noise(log: ExperimentLog, robot: RobotParameters):
    """(sigma_angle [rad], sigma_current [A]) from the log's ``sensor_noise`` metadata
    (quantisation counted as q^2/12), or the :class:`RigNoise` defaults."""
    nz = log.meta.get("sensor_noise")
    d = RigNoise()
    if isinstance(nz, dict):
        try:
            d = RigNoise(
                **{
                    k: nz[k]
                    for k in ("encoder_counts_per_rev", "angle_rad", "current_a")
                    if k in nz
                }
            )
        except (TypeError, ValueError) as exc:
            raise LogError(
                f"{log.path or log.name}: metadata 'sensor_noise' = {nz!r} is not usable: {exc}",
                log.path,
            ) from None
    q = (
        2 * math.pi / (d.encoder_counts_per_rev * robot.leg(0).gear_ratio)
        if d.encoder_counts_per_rev > 0
        else 0.0
    )
    sa = math.sqrt(d.angle_rad**2 + q * q / 12.0)
    sc = d.current_a
    return (sa if sa > 0 else 1e-4), (sc if sc > 0 else 1e-2)


def _need_meta(log, cfg, key):
    if key not in cfg:
        raise LogError(
            f"{log.path or log.name}: metadata 'rig_config' has no '{key}', which a "
            f"{log.meta.get('rig')} log needs (see docs/identification.md)",
            log.path,
        )
    return cfg[key]


def prepare_log(
    log: ExperimentLog | str | Path,
    rig: str | None = None,
    robot: RobotParameters | None = None,
    use_current: bool | None = None,
) -> RigData:
    """Check a rig log and extract what the fit needs; raise :class:`LogError` naming the
    file, the column or metadata key, and why, if the log cannot support a fit."""
    if not isinstance(log, ExperimentLog):
        log = load_log(log)
    robot = robot or RobotParameters()
    where = log.path or log.name
    meta_rig = log.meta.get("rig")
    if rig is None:
        rig = meta_rig
        if rig is None:
            raise LogError(
                f"{where}: metadata key 'rig' missing: say which rig made the log "
                f"(one of {', '.join(FITTABLE_RIGS)}) in the log or with --rig",
                log.path,
            )
    elif meta_rig is not None and meta_rig != rig:
        raise LogError(f"{where}: the log was made on the '{meta_rig}' rig, not '{rig}'", log.path)
    if rig not in FITTABLE_RIGS:
        raise LogError(
            f"{where}: rig '{rig}' is not allowed for identification: must be one "
            f"of {', '.join(FITTABLE_RIGS)}",
            log.path,
        )
    cfg = log.meta.get("rig_config")
    if not isinstance(cfg, dict):
        raise LogError(
            f"{where}: metadata key 'rig_config' missing (the rig's configuration: "
            "toe mass, release angles, motor circuit, clamp height; see "
            "docs/identification.md)",
            log.path,
        )
    t = log.t
    dt = float(np.median(np.diff(t)))
    duration = float(t[-1] - t[0])
    if duration <= 20 * dt:
        raise LogError(
            f"{where}: column 't': the log covers only {duration:.4g} s; a rig log "
            "needs the whole response",
            log.path,
            "t",
        )
    angle = np.column_stack([log.leg_angle(0), log.leg_angle(1)])
    sa, sc = _meta_noise(log, robot)
    td = None
    rcfg: FreeSwing | FlightSteps
    try:
        if rig == "free-swing":
            rcfg = FreeSwing(
                release_angle_back=float(_need_meta(log, cfg, "release_angle_back")),
                release_angle_front=float(_need_meta(log, cfg, "release_angle_front")),
                toe_mass=float(_need_meta(log, cfg, "toe_mass")),
                motor=str(cfg.get("motor", "open")),
                duration=duration,
                clamp_height=float(cfg.get("clamp_height", 1.0)),
            )
            powered = rcfg.motor == "short"
        else:
            cols = ("touchdown_cmd_back_rad", "touchdown_cmd_front_rad")
            for c in cols:
                if not log.has(c):
                    raise LogError(
                        f"{where}: column '{c}' missing: a flight-steps log needs "
                        "the commanded touchdown angle of each leg per sample",
                        log.path,
                        c,
                    )
                bad = ~np.isfinite(log.columns[c])
                if bad.any():
                    k = int(np.argmax(bad))
                    raise LogError(
                        f"{where}: column '{c}', row {k + 1}: not a finite number",
                        log.path,
                        c,
                        k + 1,
                    )
            td = np.column_stack([log.columns[c] for c in cols])
            rcfg = FlightSteps(
                step_times=(0.0,),
                angles_back=(float(td[0, 0]),),
                angles_front=(float(td[0, 1]),),
                duration=duration,
                clamp_height=float(cfg.get("clamp_height", 1.0)),
                initial_angle_back=cfg.get("initial_angle_back"),
                initial_angle_front=cfg.get("initial_angle_front"),
            )
            powered = True
    except ValueError as exc:
        if isinstance(exc, LogError):
            raise
        raise LogError(f"{where}: metadata 'rig_config' is not usable: {exc}", log.path) from None
    moving = []
    for leg in range(len(LEG_NAMES)):
        span = float(np.ptp(angle[:, leg]))
        if span > max(MIN_MOTION_RAD, 20 * sa):
            moving.append(leg)
    if not moving:
        spans = ", ".join(f"{nm} {np.ptp(angle[:, i]):.3g} rad" for i, nm in enumerate(LEG_NAMES))
        raise LogError(
            f"{where}: column 'phi_back_rad' / 'phi_front_rad': no leg moves (angle "
            f"ranges {spans}, need more than {max(MIN_MOTION_RAD, 20 * sa):.3g} rad); "
            "a leg that never moves carries no information on the hip unit",
            log.path,
            "phi_back_rad",
        )
    current = None
    has_current = log.has("current_back_a") and log.has("current_front_a")
    if use_current is None:
        use_current = powered and has_current
    if use_current:
        if not has_current:
            raise LogError(
                f"{where}: column 'current_back_a' missing: the fit was asked to "
                "match the motor current",
                log.path,
                "current_back_a",
            )
        current = np.column_stack([log.motor_current(0), log.motor_current(1)])
    return RigData(
        log=log,
        rig=rcfg,
        dt=dt,
        legs=tuple(moving),
        angle=angle,
        current=current,
        sigma_angle=sa,
        sigma_current=sc,
        touchdown_commands=td,
    )


def prepare_logs(
    logs, rig: str | None, robot: RobotParameters, use_current: bool | None
) -> list[RigData]:
    """Every log of ``logs`` (one or a list of paths, :class:`ExperimentLog` objects or
    prepared :class:`RigData`) prepared for the fit (:func:`prepare_log`); LogError if
    there is none."""
    if isinstance(logs, (str, Path, ExperimentLog, RigData)):
        logs = [logs]
    data = [d if isinstance(d, RigData) else prepare_log(d, rig, robot, use_current) for d in logs]
    if not data:
        raise LogError("no logs given")
    return data


def simulate_log(data: RigData, robot: RobotParameters, integrator=None, derivatives=None):
    """(angle (n, 2), current (n, 2), result) of the rig replayed with ``robot``;
    ``derivatives``: an optional :class:`~scoutsim.simulation.sample_derivatives.SampleDerivatives`
    the replay fills."""
    res = run_rig(
        data.rig,
        robot,
        integrator=integrator,
        dt=data.dt,
        touchdown_commands=data.touchdown_commands,
        derivatives=derivatives,
    )
    n = data.angle.shape[0]
    ang = np.column_stack([res.motor_angle(0), res.motor_angle(1)])
    cur = np.column_stack([res.motor_current(0), res.motor_current(1)])
    if ang.shape[0] < n:  # a run that failed early: hold its last value (large residual)
        pad = n - ang.shape[0]
        ang = np.vstack([ang, np.repeat(ang[-1:], pad, axis=0)])
        cur = np.vstack([cur, np.repeat(cur[-1:], pad, axis=0)])
    return ang[:n], cur[:n], res
