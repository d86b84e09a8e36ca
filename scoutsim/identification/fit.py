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


The steps, one module each (``scoutsim.identification.``)
-------------------------------------------------------
rig_data           a rig log prepared for the fit, and the rig replayed with trial parameters
parameter_vector   x = ln p, the search box, the robot of a trial x
residuals          the weighted residual vector r(x) and the rms of each channel
multistart         the global start, the local least-squares fits, the polish
uncertainty        the Jacobian at the optimum, its flat directions, the covariance of x
identifiability    values, intervals, identifiable or why not; the determined combination
fit_result         :class:`IdentificationResult`, :class:`FittedParameter`
example            the worked example (``scoutsim identify --example``)

:func:`identify` runs them in that order. This module also re-exports their public names.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from ..parameters import RobotParameters, validate_robot
from ..simulation.integrator import IntegratorSettings
from .example import EXAMPLE_FACTORS, example_logs, example_robot
from .fit_result import FittedParameter, IdentificationResult
from .identifiability import fitted_parameters, reflected_gear_inertia, true_parameters
from .multistart import refine, score_starts, start_points, starts_table
from .parameter_vector import default_bounds, fitted_names, robot_with, search_box
from .residuals import Residuals, channel_rms, residual_count
from .rig_data import (
    FITTABLE_RIGS,
    MIN_MOTION_RAD,
    RigData,
    prepare_log,
    prepare_logs,
    simulate_log,
)
from .rigs import DEFAULT_PARAMS, HIP_PARAMETERS
from .uncertainty import optimum, spread

__all__ = [
    "identify",
    "FitSettings",
    "IdentificationResult",
    "FittedParameter",
    "RigData",
    "prepare_log",
    "simulate_log",
    "DEFAULT_PARAMS",
    "default_bounds",
    "MIN_MOTION_RAD",
    "FITTABLE_RIGS",
    "EXAMPLE_FACTORS",
    "example_robot",
    "example_logs",
]


@dataclass(frozen=True)
class FitSettings:
    """How :func:`identify` searches and judges the fit.

    n_starts : Sobol points of the global start (0: start from ``robot`` only).
    n_local : how many of the best starts are refined by least squares.
    seed : seed of the scrambled Sobol sequence.
    confidence : level of the intervals (default 0.95).
    max_interval_ratio : an identifiable parameter's interval spans at most this factor.
    max_nfev, diff_step : passed to ``scipy.optimize.least_squares`` (per local fit; the
        finite-difference step is in ln p).
    jacobian : the local fits' Jacobian: "exact" (default), the replays' derivatives
        carried with them (:meth:`~scoutsim.identification.residuals.Residuals.jacobian`;
        differences where a replay is not differentiable); "fd", forward differences of
        the residuals with ``diff_step``. docs/identification.md compares the two.
    jac_step : central-difference step in ln p of the Jacobian at the optimum.
    flat_ratio : a singular direction along which the cost rises by less than this
        fraction, or more than its inverse, of the quadratic prediction over the interval
        counts as undetermined.
    """

    n_starts: int = 16
    n_local: int = 3
    seed: int = 0
    confidence: float = 0.95
    max_interval_ratio: float = 2.0
    max_nfev: int = 60
    diff_step: float = 1e-3
    jacobian: str = "exact"
    jac_step: float = 1e-2
    flat_ratio: float = 0.25


def _settings(settings: FitSettings | None, options: dict) -> FitSettings:
    """``settings`` (default :class:`FitSettings`) with the fields named in ``options``
    replaced; TypeError for a name that is not a field, as for any unknown keyword."""
    known = {f.name for f in dataclasses.fields(FitSettings)}
    for name in options:
        if name not in known:
            raise TypeError(f"identify() got an unexpected keyword argument {name!r}")
    return dataclasses.replace(settings or FitSettings(), **options)


def identify(
    logs,
    params=None,
    *,
    rig: str | None = None,
    robot: RobotParameters | None = None,
    bounds: dict | None = None,
    start: dict | None = None,
    integrator: IntegratorSettings | None = None,
    use_current: bool | None = None,
    progress=None,
    settings: FitSettings | None = None,
    **options,
) -> IdentificationResult:
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
    start : {name: value} to add as a start point (e.g. a warm start).
    integrator : IntegratorSettings of the replayed rig runs (default: the reference).
    use_current : match the motor current too (default: where the rig drives current).
    progress : optional callable(str) for progress messages.
    settings : :class:`FitSettings` (default: its defaults).
    **options : any field of :class:`FitSettings` by name (``n_starts``, ``n_local``,
        ``seed``, ``confidence``, ``max_interval_ratio``, ``max_nfev``, ``diff_step``,
        ``jac_step``, ``flat_ratio``), replacing that of ``settings``.
    """
    s = _settings(settings, options)
    base = validate_robot(robot if robot is not None else RobotParameters())
    differ = [
        n
        for n in (*HIP_PARAMETERS, "planetary_ratio", "sprocket_ratio")
        if isinstance(getattr(base, n), tuple)
    ]
    if differ:
        raise ValueError(
            f"robot: the hip units differ between the legs in "
            f"{', '.join(differ)}; the fit identifies one hip unit for both "
            "legs: give those fields one value (in Python, robot.leg('back') "
            "or robot.leg('front') is one leg's robot)"
        )
    if s.jacobian not in ("fd", "exact"):
        raise ValueError(f"jacobian = {s.jacobian!r} is not allowed: must be fd or exact")
    if not (0.0 < s.confidence < 1.0):
        raise ValueError(f"confidence = {s.confidence} is not allowed: must be in (0, 1)")
    data = prepare_logs(logs, rig, base, use_current)
    names = fitted_names(params, data)
    sb = search_box(names, base, bounds)
    p = len(names)
    nres = residual_count(data, p)
    residuals = Residuals(data, base, names, integrator, s.diff_step)
    scored = score_starts(residuals, start_points(base, sb, start, s.n_starts, s.seed), progress)
    starts_info = starts_table(scored, names)
    best = refine(residuals, scored, starts_info, sb, s, progress)
    opt = optimum(residuals, best.x, nres, p, s.confidence)
    spr = spread(residuals, opt, sb, s.jac_step, s.flat_ratio)
    true = true_parameters(data)
    fitted = fitted_parameters(sb, opt, spr.sd, base, true, s.max_interval_ratio)
    combos = reflected_gear_inertia(sb, opt, spr, base, true)
    rms = channel_rms(opt.r, data)
    return IdentificationResult(
        parameters=fitted,
        confidence=s.confidence,
        robot=robot_with(base, names, opt.x),
        start_robot=base,
        correlation=spr.corr,
        singular_values=spr.S,
        singular_vectors=spr.Vt.T,
        cost=float(best.cost),
        residual_scale=math.sqrt(opt.s2),
        channel_rms=rms,
        n_residuals=nres,
        data=data,
        starts=starts_info,
        nfev=residuals.nfev,
        message=str(best.message),
        jacobian=s.jacobian,
        jacobian_evaluations=residuals.njev,
        jacobian_fallbacks=residuals.nfd,
        curvature_ratios=[float(v) for v in spr.ratios],
        flat=[bool(v) for v in spr.flat],
        combinations=combos,
    )
