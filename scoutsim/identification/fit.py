"""Identification of the Model II hip-unit parameters from rig logs
(docs/identification.md).

    result = identify([log1, log2], params=["drive_gear_inertia", "joint_stiction", ...])
    print(result.report())
    result.save("out/")                      # identified.json + fit figures

The fit
-------
Weighted nonlinear least squares (``scipy.optimize.least_squares``, trust-region
reflective) of the simulated against the logged motor-encoder angle of every leg that
moves, and of the motor current where the rig drives current (flight steps, shorted
free swing), each residual divided by its sensor noise:

    r = [(alpha_sim(t_k; p) - alpha_log(t_k)) / sigma_angle,  (i_sim - i_log) / sigma_i]

The simulation is the rig's own run (:func:`scoutsim.identification.rigs.run_rig`) with
the trial parameters. The parameters are fitted as ``x = ln p`` (all are positive and span
decades), inside a search box (default: a factor 10 either side of the starting robot's
value). Stick/slip makes the cost rough, so the search starts globally: ``n_starts``
scrambled-Sobol points in the box (``scipy.stats.qmc``) plus the starting robot's values are
evaluated, and the ``n_local`` best are refined by least squares; the best optimum wins.

Uncertainty
-----------
At the optimum, with J the (weighted) Jacobian in x and s^2 = |r|^2 / (n - p) the residual
variance, cov(x) = s^2 (J^T J)^-1 (computed from the SVD of J; directions with singular
values below 1e-10 of the largest get infinite variance). The confidence interval of p is
``exp(x +- t_{n-p, (1+c)/2} sd(x))``: a linearised interval, honest when the errors are
independent and the model is locally linear over the interval (tested by coverage over
repeated noise draws, tests/identification).

Before the intervals are trusted, every singular direction v_k of J is checked against
the real cost: the linear model says a step t along v_k raises the cost by (S_k t)^2 / 2;
the cost is evaluated at the interval's ends x +- t_q s / S_k v_k, and a direction along
which it rises by less than ``flat_ratio`` (1/4) of that, or by more than 4 times, is
*undetermined* (infinite variance): the quadratic model behind the interval does not hold
there. This catches what finite differences alone cannot: a combination the model does
not depend on at all (with the torso clamped only J_2 + N^2 J_1 enters, docs/specification.md section 5, a
curved valley in ln J_1, ln J_2) still shows a small nonzero singular value from the
stencil's curvature, which would give a false interval; along the straight singular
direction the cost then rises thousands of times faster than predicted, because the
valley curves away from it.

Identifiability
---------------
A parameter counts as *identifiable* by the given logs when no flat direction involves it,
its interval spans at most a factor ``max_interval_ratio`` (default 2, i.e. roughly
+-35 %) and the fit did not end on the search box's edge. Otherwise it is reported as not identifiable, with the reason; the
report also lists strongly correlated pairs (|rho| > 0.95) and the singular values and
directions of the scaled Jacobian (the combination of log-parameters the data do not
determine).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy import optimize, stats
from scipy.stats import qmc

from ..parameters import RobotParameters, validate_robot
from ..integrator import IntegratorSettings
from ..validation.logs import ExperimentLog, LogError, load_log
from .rigs import DEFAULT_PARAMS, HIP_PARAMETERS, FlightSteps, FreeSwing, RigNoise, run_rig

__all__ = ["identify", "IdentificationResult", "FittedParameter", "RigData", "prepare_log",
           "DEFAULT_PARAMS", "default_bounds"]

#: Search box for parameters whose starting value is 0 (the transmission losses).
_ZERO_START_BOX = {"gearbox_idle_loss_torque": (1e-3, 2.0),
                   "gearbox_load_loss_coefficient": (1e-3, 0.5)}
#: A leg whose logged angle spans less than this [rad] does not count as moving.
MIN_MOTION_RAD = 0.01
FITTABLE_RIGS = ("free-swing", "flight-steps")


def default_bounds(name: str, value: float, factor: float = 10.0) -> tuple[float, float]:
    """Default search box of one parameter: (value/factor, value*factor), or a fixed box
    for the loss parameters that start at 0."""
    if value > 0:
        lo, hi = value / factor, value * factor
        if name == "gearbox_load_loss_coefficient":
            hi = min(hi, 0.9)
        return lo, hi
    if name in _ZERO_START_BOX:
        return _ZERO_START_BOX[name]
    raise ValueError(f"bounds[{name!r}]: the starting value is {value}; give a search box "
                     "(lo, hi) with 0 < lo < hi")


# -----------------------------------------------------------------------------------------
# data
# -----------------------------------------------------------------------------------------
@dataclass
class RigData:
    """One log prepared for fitting: the rig to replay and the signals to match."""

    log: ExperimentLog
    rig: object
    dt: float
    legs: tuple                    # indices of the legs that move (fitted)
    angle: np.ndarray              # (n, 2) logged encoder angle [rad]
    current: np.ndarray | None     # (n, 2) logged current [A], or None if not used
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
            d = RigNoise(**{k: nz[k] for k in ("encoder_counts_per_rev", "angle_rad",
                                               "current_a") if k in nz})
        except (TypeError, ValueError) as exc:
            raise LogError(f"{log.path or log.name}: metadata 'sensor_noise' = {nz!r} is not "
                           f"usable: {exc}", log.path) from None
    q = (2 * math.pi / (d.encoder_counts_per_rev * robot.gear_ratio)
         if d.encoder_counts_per_rev > 0 else 0.0)
    sa = math.sqrt(d.angle_rad ** 2 + q * q / 12.0)
    sc = d.current_a
    return (sa if sa > 0 else 1e-4), (sc if sc > 0 else 1e-2)


def _need_meta(log, cfg, key):
    if key not in cfg:
        raise LogError(f"{log.path or log.name}: metadata 'rig_config' has no '{key}', which a "
                       f"{log.meta.get('rig')} log needs (see docs/identification.md)", log.path)
    return cfg[key]


def prepare_log(log: ExperimentLog | str | Path, rig: str | None = None,
                robot: RobotParameters | None = None, use_current: bool | None = None) -> RigData:
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
            raise LogError(f"{where}: metadata key 'rig' missing: say which rig made the log "
                           f"(one of {', '.join(FITTABLE_RIGS)}) in the log or with --rig",
                           log.path)
    elif meta_rig is not None and meta_rig != rig:
        raise LogError(f"{where}: the log was made on the '{meta_rig}' rig, not '{rig}'",
                       log.path)
    if rig not in FITTABLE_RIGS:
        raise LogError(f"{where}: rig '{rig}' is not allowed for identification: must be one "
                       f"of {', '.join(FITTABLE_RIGS)}", log.path)
    cfg = log.meta.get("rig_config")
    if not isinstance(cfg, dict):
        raise LogError(f"{where}: metadata key 'rig_config' missing (the rig's configuration: "
                       "toe mass, release angles, motor circuit, clamp height; see "
                       "docs/identification.md)", log.path)
    t = log.t
    dt = float(np.median(np.diff(t)))
    duration = float(t[-1] - t[0])
    if duration <= 20 * dt:
        raise LogError(f"{where}: column 't': the log covers only {duration:.4g} s; a rig log "
                       "needs the whole response", log.path, "t")
    angle = np.column_stack([log.leg_angle(0), log.leg_angle(1)])
    sa, sc = _meta_noise(log, robot)
    td = None
    try:
        if rig == "free-swing":
            rcfg = FreeSwing(
                release_angle_back=float(_need_meta(log, cfg, "release_angle_back")),
                release_angle_front=float(_need_meta(log, cfg, "release_angle_front")),
                toe_mass=float(_need_meta(log, cfg, "toe_mass")),
                motor=str(cfg.get("motor", "open")),
                duration=duration, clamp_height=float(cfg.get("clamp_height", 1.0)))
            powered = rcfg.motor == "short"
        else:
            cols = ("touchdown_cmd_back_rad", "touchdown_cmd_front_rad")
            for c in cols:
                if not log.has(c):
                    raise LogError(f"{where}: column '{c}' missing: a flight-steps log needs "
                                   "the commanded touchdown angle of each leg per sample",
                                   log.path, c)
                bad = ~np.isfinite(log.columns[c])
                if bad.any():
                    k = int(np.argmax(bad))
                    raise LogError(f"{where}: column '{c}', row {k + 1}: not a finite number",
                                   log.path, c, k + 1)
            td = np.column_stack([log.columns[c] for c in cols])
            rcfg = FlightSteps(step_times=(0.0,), angles_back=(float(td[0, 0]),),
                               angles_front=(float(td[0, 1]),), duration=duration,
                               clamp_height=float(cfg.get("clamp_height", 1.0)),
                               initial_angle_back=cfg.get("initial_angle_back"),
                               initial_angle_front=cfg.get("initial_angle_front"))
            powered = True
    except ValueError as exc:
        if isinstance(exc, LogError):
            raise
        raise LogError(f"{where}: metadata 'rig_config' is not usable: {exc}", log.path) from None
    moving = []
    for leg, nm in enumerate(("back", "front")):
        span = float(np.ptp(angle[:, leg]))
        if span > max(MIN_MOTION_RAD, 20 * sa):
            moving.append(leg)
    if not moving:
        spans = ", ".join(f"{nm} {np.ptp(angle[:, i]):.3g} rad"
                          for i, nm in enumerate(("back", "front")))
        raise LogError(f"{where}: column 'phi_back_rad' / 'phi_front_rad': no leg moves (angle "
                       f"ranges {spans}, need more than {max(MIN_MOTION_RAD, 20 * sa):.3g} rad); "
                       "a leg that never moves carries no information on the hip unit",
                       log.path, "phi_back_rad")
    current = None
    has_current = log.has("current_back_a") and log.has("current_front_a")
    if use_current is None:
        use_current = powered and has_current
    if use_current:
        if not has_current:
            raise LogError(f"{where}: column 'current_back_a' missing: the fit was asked to "
                           "match the motor current", log.path, "current_back_a")
        current = np.column_stack([log.motor_current(0), log.motor_current(1)])
    return RigData(log=log, rig=rcfg, dt=dt, legs=tuple(moving), angle=angle, current=current,
                   sigma_angle=sa, sigma_current=sc, touchdown_commands=td)


def simulate_log(data: RigData, robot: RobotParameters, integrator=None):
    """(angle (n, 2), current (n, 2), result) of the rig replayed with ``robot``."""
    res = run_rig(data.rig, robot, integrator=integrator, dt=data.dt,
                  touchdown_commands=data.touchdown_commands)
    n = data.angle.shape[0]
    ang = np.column_stack([res.motor_angle(0), res.motor_angle(1)])
    cur = np.column_stack([res.motor_current(0), res.motor_current(1)])
    if ang.shape[0] < n:       # a run that failed early: hold its last value (large residual)
        pad = n - ang.shape[0]
        ang = np.vstack([ang, np.repeat(ang[-1:], pad, axis=0)])
        cur = np.vstack([cur, np.repeat(cur[-1:], pad, axis=0)])
    return ang[:n], cur[:n], res


# -----------------------------------------------------------------------------------------
# result
# -----------------------------------------------------------------------------------------
@dataclass
class FittedParameter:
    """One fitted parameter (SI)."""

    name: str
    unit: str
    value: float
    interval: tuple
    identifiable: bool
    reason: str
    log_sd: float
    start: float
    bounds: tuple
    true: float | None = None

    def to_dict(self) -> dict:
        def num(x):
            return None if (x is None or not math.isfinite(x)) else float(x)
        return {"value": float(self.value), "unit": self.unit,
                "interval": [num(self.interval[0]), num(self.interval[1])],
                "identifiable": bool(self.identifiable), "reason": self.reason,
                "log_sd": num(self.log_sd), "start": float(self.start),
                "search_box": [float(self.bounds[0]), float(self.bounds[1])],
                "true": num(self.true)}


@dataclass
class IdentificationResult:
    """What :func:`identify` found (see the module docstring)."""

    parameters: dict
    confidence: float
    robot: RobotParameters
    start_robot: RobotParameters
    correlation: np.ndarray
    singular_values: np.ndarray
    singular_vectors: np.ndarray
    cost: float
    residual_scale: float
    channel_rms: dict
    n_residuals: int
    data: list = field(repr=False, default_factory=list)
    starts: list = field(default_factory=list)
    curvature_ratios: list = field(default_factory=list)
    flat: list = field(default_factory=list)
    combinations: dict = field(default_factory=dict)
    nfev: int = 0
    message: str = ""

    @property
    def names(self) -> list:
        return list(self.parameters)

    def to_dict(self) -> dict:
        return {
            "format": "scoutsim.identified/1",
            "logs": [d.log.path or d.log.name for d in self.data],
            "rigs": [d.rig.name for d in self.data],
            "confidence": self.confidence,
            "parameters": {k: p.to_dict() for k, p in self.parameters.items()},
            "correlation": {"names": self.names,
                            "matrix": [[None if not math.isfinite(v) else round(float(v), 6)
                                        for v in row] for row in self.correlation]},
            "singular_values": [float(v) for v in self.singular_values],
            "singular_vectors": [[round(float(v), 6) for v in col]
                                 for col in self.singular_vectors.T],
            "curvature_ratios": [float(v) for v in self.curvature_ratios],
            "flat_directions": [bool(v) for v in self.flat],
            "combinations": self.combinations,
            "cost": self.cost, "residual_scale": self.residual_scale,
            "channel_rms_over_sigma": self.channel_rms, "n_residuals": self.n_residuals,
            "function_evaluations": self.nfev, "optimizer_message": self.message,
            "multistart": self.starts,
        }

    def report(self) -> str:
        """Plain-text table: fitted value, interval, identifiable flag (and truth if known)."""
        c = round(100 * self.confidence)
        has_true = any(p.true is not None for p in self.parameters.values())
        lines = [f"{'parameter':<30} {'unit':<10} " + (f"{'true':>11} " if has_true else "")
                 + f"{'fitted':>11}  {str(c) + ' % interval':<27} identifiable"]
        for p in self.parameters.values():
            lo, hi = p.interval
            iv = f"[{lo:.4g}, {hi:.4g}]" if math.isfinite(hi) else f"[{lo:.4g}, inf]"
            tr = (f"{p.true:>11.4g} " if p.true is not None else f"{'':>11} ") if has_true else ""
            lines.append(f"{p.name:<30} {p.unit:<10} {tr}{p.value:>11.4g}  {iv:<27} "
                         + ("yes" if p.identifiable else f"NO ({p.reason})"))
        lines.append(f"residual scale s = {self.residual_scale:.3f} (1 = residuals as large as "
                     f"the stated sensor noise); rms/sigma per channel: "
                     + ", ".join(f"{k} {v:.3f}" for k, v in self.channel_rms.items()))
        pairs = []
        n = len(self.names)
        for i in range(n):
            for j in range(i + 1, n):
                r = self.correlation[i, j]
                if math.isfinite(r) and abs(r) > 0.95:
                    pairs.append(f"{self.names[i]} / {self.names[j]}: {r:+.3f}")
        if pairs:
            lines.append("strongly correlated (|rho| > 0.95): " + "; ".join(pairs))
        if len(self.singular_values):
            sv = self.singular_values
            lines.append("singular values of the scaled Jacobian: "
                         + ", ".join(f"{x:.3g}" for x in sv) + "; cost rise over the "
                         "interval / linear prediction: "
                         + ", ".join(f"{x:.2f}" for x in self.curvature_ratios))
            for k in np.flatnonzero(self.flat):
                v = self.singular_vectors[:, k]
                idx = np.argsort(-np.abs(v))[:3]
                comb = " ".join(f"{v[i]:+.2f} ln {self.names[i]}" for i in idx
                                if abs(v[i]) > 0.05)
                lines.append(f"flat direction (not determined by these logs): {comb}")
        for name, c in self.combinations.items():
            lo, hi = c["interval"]
            tr = f" (true {c['true']:.5g})" if c.get("true") is not None else ""
            if hi is None:
                lines.append(f"combination {name} = {c['definition']}: {c['value']:.5g} "
                             f"{c['unit']}, not determined either{tr}")
            else:
                lines.append(f"determined combination {name} = {c['definition']}: "
                             f"{c['value']:.5g} {c['unit']}, interval [{lo:.5g}, {hi:.5g}]{tr}")
        return "\n".join(lines)

    def save(self, out_dir, figures: bool = True) -> Path:
        """Write ``identified.json`` (and fit figures ``fit_<n>.png``) into ``out_dir``."""
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        path = out / "identified.json"
        path.write_text(json.dumps(self.to_dict(), indent=2))
        if figures:
            self.plot(out)
        return path

    def plot(self, out_dir) -> list:
        """One figure per log, ``out_dir/fit_<n>.png``: logged vs fitted (and starting)
        encoder angle and current, residuals; a convenience for
        :func:`scoutsim.presentation.identification_plots.plot_fit` (needs Matplotlib).
        Returns the paths written."""
        from ..presentation.identification_plots import plot_fit
        files = []
        for i, d in enumerate(self.data):
            fit_a, fit_c, _ = simulate_log(d, self.robot)
            start_a, _, _ = simulate_log(d, self.start_robot)
            f = Path(out_dir) / f"fit_{i + 1}.png"
            plot_fit(d, fit_a, fit_c, start_a, f)
            files.append(f)
        return files


# -----------------------------------------------------------------------------------------
# the fit
# -----------------------------------------------------------------------------------------
def _robot_with(base: RobotParameters, names, x) -> RobotParameters:
    return base.replace(**{n: float(math.exp(v)) for n, v in zip(names, x)})


def identify(logs, params=None, *, rig: str | None = None, robot: RobotParameters | None = None,
             bounds: dict | None = None, n_starts: int = 16, n_local: int = 3, seed: int = 0,
             confidence: float = 0.95, start: dict | None = None,
             integrator: IntegratorSettings | None = None, use_current: bool | None = None,
             max_interval_ratio: float = 2.0, max_nfev: int = 60,
             diff_step: float = 1e-3, jac_step: float = 1e-2, flat_ratio: float = 0.25,
             progress=None) -> IdentificationResult:
    """Fit hip-unit parameters to one or more rig logs (see the module docstring).

    Parameters
    ----------
    logs : log paths, :class:`ExperimentLog` objects or prepared :class:`RigData`.
    params : names of the parameters to fit (keys of ``HIP_PARAMETERS``; default
        ``DEFAULT_PARAMS`` of the rig).
    rig : "free-swing" or "flight-steps" (default: from each log's metadata).
    robot : starting robot (default Scout II): the values of the parameters not fitted, and
        the centre of the default search boxes.
    bounds : {name: (lo, hi)} search boxes [SI] (default :func:`default_bounds`).
    n_starts : Sobol points of the global start (0: start from ``robot`` only).
    n_local : how many of the best starts are refined by least squares.
    seed : seed of the scrambled Sobol sequence.
    confidence : level of the intervals (default 0.95).
    start : {name: value} to add as a start point (e.g. a warm start).
    integrator : IntegratorSettings of the replayed rig runs (default: the reference).
    use_current : match the motor current too (default: where the rig drives current).
    max_interval_ratio : an identifiable parameter's interval spans at most this factor.
    max_nfev, diff_step : passed to ``scipy.optimize.least_squares`` (per local fit; the
        finite-difference step is in ln p).
    jac_step : central-difference step in ln p of the Jacobian at the optimum.
    flat_ratio : a singular direction along which the cost rises by less than this
        fraction, or more than its inverse, of the quadratic prediction over the interval
        counts as undetermined.
    progress : optional callable(str) for progress messages.
    """
    base = validate_robot(robot if robot is not None else RobotParameters())
    if not (0.0 < confidence < 1.0):
        raise ValueError(f"confidence = {confidence} is not allowed: must be in (0, 1)")
    if isinstance(logs, (str, Path, ExperimentLog, RigData)):
        logs = [logs]
    data = [d if isinstance(d, RigData) else prepare_log(d, rig, base, use_current)
            for d in logs]
    if not data:
        raise LogError("no logs given")
    if params is None:
        params = DEFAULT_PARAMS[data[0].rig.name]
    names = list(params)
    for n in names:
        if n not in HIP_PARAMETERS:
            raise ValueError(f"params: {n!r} is not allowed: must be among "
                             f"{', '.join(HIP_PARAMETERS)}")
    if len(set(names)) != len(names) or not names:
        raise ValueError(f"params = {names} is not allowed: need distinct names, at least one")
    bounds = dict(bounds or {})
    box = []
    for n in names:
        lo, hi = bounds.get(n) or default_bounds(n, float(getattr(base, n)))
        if not (0.0 < lo < hi and math.isfinite(hi)):
            raise ValueError(f"bounds[{n!r}] = ({lo}, {hi}) is not allowed: need 0 < lo < hi")
        if n == "gearbox_load_loss_coefficient" and hi >= 1.0:
            raise ValueError(f"bounds[{n!r}]: hi = {hi} is not allowed: must be < 1")
        box.append((math.log(lo), math.log(hi)))
    xlo = np.array([b[0] for b in box])
    xhi = np.array([b[1] for b in box])
    nres = sum(d.n_residuals for d in data)
    p = len(names)
    if nres <= p:
        raise LogError(f"{data[0].log.path or data[0].name}: only {nres} residuals for {p} "
                       "parameters", data[0].log.path)
    counter = {"nfev": 0}

    def residuals(x):
        counter["nfev"] += 1
        rb = _robot_with(base, names, x)
        out = []
        for d in data:
            a, c, _ = simulate_log(d, rb, integrator)
            for leg in d.legs:
                out.append((a[:, leg] - d.angle[:, leg]) / d.sigma_angle)
            if d.current is not None:
                for leg in d.legs:
                    out.append((c[:, leg] - d.current[:, leg]) / d.sigma_current)
        r = np.concatenate(out)
        r[~np.isfinite(r)] = 1e6
        return r

    # global start: Sobol points in the box, the starting robot's values, a warm start
    cands = []
    x_nom = np.clip([math.log(v) if v > 0 else 0.5 * (a + b)
                     for v, (a, b) in zip((float(getattr(base, n)) for n in names), box)],
                    xlo, xhi)
    cands.append(("start robot", np.array(x_nom, dtype=float)))
    if start:
        xs = np.array([math.log(float(start.get(n, math.exp(x)))) for n, x in zip(names, x_nom)])
        cands.append(("given start", np.clip(xs, xlo, xhi)))
    if n_starts > 0:
        m = int(math.ceil(math.log2(max(n_starts, 1))))
        pts = qmc.Sobol(d=p, scramble=True, seed=seed).random_base2(m)[:n_starts]
        for k, u in enumerate(pts):
            cands.append((f"sobol {k + 1}", xlo + u * (xhi - xlo)))
    scored = []
    for label, x in cands:
        r = residuals(x)
        scored.append((0.5 * float(r @ r), label, x))
        if progress:
            progress(f"start {label}: cost {scored[-1][0]:.4g}")
    scored.sort(key=lambda e: e[0])
    best = None
    starts_info = [{"label": lbl, "cost": c, "x": {n: float(math.exp(v)) for n, v in zip(names, x)}}
                   for c, lbl, x in scored]
    for c0, label, x0 in scored[:max(1, n_local)]:
        sol = optimize.least_squares(residuals, x0, bounds=(xlo, xhi), method="trf",
                                     x_scale=1.0, diff_step=diff_step, max_nfev=max_nfev)
        for si in starts_info:
            if si["label"] == label:
                si["refined_cost"] = float(sol.cost)
        if progress:
            progress(f"refined {label}: cost {c0:.4g} -> {sol.cost:.4g} ({sol.nfev} evaluations)")
        if best is None or sol.cost < best.cost:
            best = sol
    # polish: one more local fit from the best optimum with a fresh trust region (a
    # stick/slip kink can stall trf's trust region before the minimum)
    sol = optimize.least_squares(residuals, best.x, bounds=(xlo, xhi), method="trf",
                                 x_scale=1.0, diff_step=diff_step, max_nfev=max_nfev)
    if progress:
        progress(f"polished: cost {best.cost:.4g} -> {sol.cost:.4g}")
    if sol.cost < best.cost:
        best = sol
    x = best.x
    r = residuals(x)
    dof = max(nres - p, 1)
    s2 = float(r @ r) / dof
    c_opt = 0.5 * float(r @ r)
    zq = float(stats.t.ppf(0.5 + 0.5 * confidence, dof))
    # Jacobian at the optimum by central differences (step jac_step in ln p, kept inside
    # the box by shifting the stencil)
    cols = []
    for i in range(p):
        h = jac_step
        xp = x.copy()
        xm = x.copy()
        xp[i] = min(x[i] + h, xhi[i])
        xm[i] = max(xp[i] - 2 * h, xlo[i])
        cols.append((residuals(xp) - residuals(xm)) / (xp[i] - xm[i]))
    J = np.column_stack(cols)
    U, S, Vt = np.linalg.svd(J, full_matrices=False)
    tol = 1e-10 * (S[0] if S.size else 0.0)
    # curvature check of every direction: the linear model says that moving t along the
    # singular vector v_k raises the cost by (S_k t)^2 / 2; a direction along which the
    # cost rises far less over the interval is flat (the data do not determine it, however
    # large S_k looked) and gets infinite variance
    flat = np.zeros(S.size, dtype=bool)
    ratios = []
    for k in range(S.size):
        if S[k] <= tol:
            flat[k] = True
            ratios.append(0.0)
            continue
        w = zq * math.sqrt(s2) / S[k]
        acts, preds = [], []
        for sgn in (1.0, -1.0):
            xt = np.clip(x + sgn * w * Vt[k], xlo, xhi)
            t = float(np.dot(xt - x, Vt[k]))
            if abs(t) < 1e-12:
                continue
            rt = residuals(xt)
            acts.append(0.5 * float(rt @ rt) - c_opt)
            preds.append(0.5 * (S[k] * t) ** 2)
        rho = (sum(acts) / sum(preds)) if preds else 0.0
        ratios.append(rho)
        if rho < flat_ratio or rho > 1.0 / flat_ratio:
            flat[k] = True
    inv = np.where(flat, np.inf, 1.0 / np.where(flat, 1.0, S) ** 2)
    with np.errstate(invalid="ignore"):
        cov_det = np.einsum("ik,k,jk->ij", Vt.T, np.where(flat, 0.0, inv), Vt.T) * s2
        cov = cov_det.copy()
        # a flat direction makes every parameter it involves undetermined: followed
        # across the search box it moves parameter i by |v_ki| D_k; if that exceeds the
        # parameter's own half-width, the interval would only hold conditionally
        half_det = zq * np.sqrt(np.clip(np.diag(cov_det), 0.0, np.inf))
        spans = {}
        for k in np.flatnonzero(flat):
            v = Vt[k]
            with np.errstate(divide="ignore", invalid="ignore"):
                tmax = np.where(v > 0, (xhi - x) / v, np.where(v < 0, (xlo - x) / v, np.inf))
                tmin = np.where(v > 0, (xlo - x) / v, np.where(v < 0, (xhi - x) / v, -np.inf))
            D = float(np.min(tmax) - np.max(tmin))
            spans[int(k)] = D
            touched = (np.abs(v) > 0.05) | (np.abs(v) * D > half_det)
            cov[np.ix_(touched, touched)] = np.inf
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, np.inf))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(sd, sd)
    true = {}
    for d in data:
        tp = d.log.meta.get("true_parameters")
        if isinstance(tp, dict):
            true = tp
    fitted = {}
    for i, n in enumerate(names):
        half = zq * sd[i]
        lo = math.exp(x[i] - half) if math.isfinite(half) else 0.0
        hi = math.exp(x[i] + half) if math.isfinite(half) else math.inf
        at_edge = (x[i] - xlo[i] < 1e-3) or (xhi[i] - x[i] < 1e-3)
        ratio = hi / lo if lo > 0 else math.inf
        if not math.isfinite(ratio):
            ok, why = False, "not determined: flat or curved cost valley"
        elif at_edge and ratio > 1.0:
            ok, why = False, "fit ran to the search box's edge"
        elif ratio > max_interval_ratio:
            ok, why = False, f"interval spans a factor {ratio:.3g}"
        else:
            ok, why = True, ""
        fitted[n] = FittedParameter(
            name=n, unit=HIP_PARAMETERS[n], value=math.exp(x[i]), interval=(lo, hi),
            identifiable=ok, reason=why, log_sd=float(sd[i]),
            start=float(getattr(base, n)), bounds=(math.exp(xlo[i]), math.exp(xhi[i])),
            true=(float(true[n]) if n in true else None))
    # the combination the clamped rigs determine when both gear inertias are fitted:
    # the reflected gear-train inertia J_2 + N^2 J_1 (docs/specification.md section 5)
    combos = {}
    if "drive_gear_inertia" in names and "driven_gear_inertia" in names:
        i1, i2 = names.index("drive_gear_inertia"), names.index("driven_gear_inertia")
        n2 = base.gear_ratio ** 2
        j1, j2 = math.exp(x[i1]), math.exp(x[i2])
        jr = j2 + n2 * j1
        g = np.zeros(p)
        g[i1], g[i2] = n2 * j1 / jr, j2 / jr
        var = float(g @ cov_det @ g)
        half = zq * math.sqrt(max(var, 0.0))
        # undetermined if a flat direction, followed across the box, moves it beyond its
        # half-width (the same rule as for the parameters)
        # half-width (the same rule as for the parameters) - except the gear direction
        # itself, which the finite-difference stencil resolves only approximately
        for k in np.flatnonzero(flat):
            gv = abs(float(g @ Vt[k]))
            gear_dir = Vt[k, i1] ** 2 + Vt[k, i2] ** 2 > 0.5
            if gv > 0.2 * float(np.linalg.norm(g)) or (
                    not gear_dir and gv * spans.get(int(k), 0.0) > half):
                half = math.inf
        tr = None
        if "drive_gear_inertia" in true and "driven_gear_inertia" in true:
            tr = float(true["driven_gear_inertia"]) + n2 * float(true["drive_gear_inertia"])
        combos["reflected_gear_inertia"] = {
            "definition": "J_2 + N^2 J_1", "value": jr, "unit": "kg m^2",
            "interval": [jr * math.exp(-half), jr * math.exp(half) if math.isfinite(half)
                         else None],
            "true": tr}
    # channel rms in units of the stated noise
    rms = {}
    o = 0
    for j, d in enumerate(data):
        n = d.angle.shape[0] * len(d.legs)
        ra = r[o:o + n]
        o += n
        rms[f"log {j + 1} ({d.rig.name}) angle"] = float(np.sqrt(np.mean(ra * ra)))
        if d.current is not None:
            rc = r[o:o + n]
            o += n
            rms[f"log {j + 1} ({d.rig.name}) current"] = float(np.sqrt(np.mean(rc * rc)))
    return IdentificationResult(
        parameters=fitted, confidence=confidence, robot=_robot_with(base, names, x),
        start_robot=base, correlation=corr, singular_values=S, singular_vectors=Vt.T,
        cost=float(best.cost), residual_scale=math.sqrt(s2), channel_rms=rms,
        n_residuals=nres, data=data, starts=starts_info, nfev=counter["nfev"],
        message=str(best.message), curvature_ratios=[float(v) for v in ratios],
        flat=[bool(v) for v in flat], combinations=combos)


# -----------------------------------------------------------------------------------------
# the worked example (scoutsim identify --example)
# -----------------------------------------------------------------------------------------
#: Factors applied to the Table II values to make the example's "true" hip unit: the fit
#: starts from Table II and must find these.
EXAMPLE_FACTORS = {"drive_gear_inertia": 1.5, "driven_gear_inertia": 0.7,
                   "joint_stiction": 1.6, "joint_damping": 0.6, "belt_stiffness": 1.3,
                   "belt_damping": 0.8}


def example_robot(base: RobotParameters | None = None) -> RobotParameters:
    """The example's true robot: Table II hip values times :data:`EXAMPLE_FACTORS`."""
    base = base or RobotParameters()
    return base.replace(**{k: getattr(base, k) * f for k, f in EXAMPLE_FACTORS.items()})


def example_logs(rigs=("free-swing", "flight-steps"), seed: int = 0, noise: RigNoise | None = None,
                 out_dir=None) -> list:
    """Virtual rig logs made with :func:`example_robot` and sensor noise (seeded; one seed
    per log, ``seed + i``). Saved as ``<rig>.csv.gz`` in ``out_dir`` if given."""
    from .rigs import rig_log
    true = example_robot()
    noise = noise or RigNoise()
    logs = []
    for i, name in enumerate(rigs):
        if name == "free-swing":
            rig = FreeSwing()
        elif name == "flight-steps":
            rig = FlightSteps()
        else:
            raise ValueError(f"rig = {name!r} is not allowed: must be one of "
                             f"{', '.join(FITTABLE_RIGS)}")
        log = rig_log(run_rig(rig, true), noise=noise, seed=seed + i,
                      notes="scoutsim identify --example: true hip unit = Table II x "
                            + json.dumps(EXAMPLE_FACTORS))
        if out_dir is not None:
            out = Path(out_dir)
            out.mkdir(parents=True, exist_ok=True)
            path = log.save(out / f"{name}.csv.gz")
            log = load_log(path)
        logs.append(log)
    return logs
