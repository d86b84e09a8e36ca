"""A tuning's gradient refinement (optional, after CMA-ES): a few steps from the best
candidate along the gradient of the objective of its periodic gait.

CMA-ES ranks candidates and learns the search distribution from the ranks alone, so it
closes in on an optimum slowly once the score is smooth around it. Near the end of a
tuning the gait is a periodic orbit whose metrics are smooth functions of the tuned
parameters within its sample-phase cell, and their derivatives cost a few strides
(:func:`scoutsim.analysis.orbit_sensitivity.orbit_sensitivities`: the implicit function
theorem on the fixed point, with the stride map's exact Jacobian), far less than one
evaluation's run. The refinement uses them:

1. At the best candidate so far (which must be feasible), the periodic orbit of each
   scenario that sets the score (``aggregate="worst"``: the worst one; ``"mean"``: all),
   found by :func:`~scoutsim.analysis.controlled_orbit.controlled_fixed_point` from a run
   of the tuning's duration (at least :data:`SETTLE_S`), or, after an accepted step, by
   Newton from the last gradient's orbit (kept if it is stable); and the derivatives of
   the objective's metric on it: the mean speed (objectives ``speed``, ``max-speed``),
   the cost of transport (``cot``) or the spectral radius per stride (``stability``),
   with the first of the relative steps :data:`SENSITIVITY_STEPS` that keeps every
   perturbed orbit in its sample-phase cell. The objective f and its gradient G in the
   unit cube of the parameters' bounds (u = (p - low) / (high - low)); for ``speed``,
   f = |v - target| and G = sign(v - target) dv/du; ``mean``: the scenarios' means.
2. A step within the trust radius r: along -G (the components that would leave the box at
   a bound dropped), of length r, or for ``speed`` the step to the zero of the linear model
   if shorter (Newton on v = target).
3. The candidate there is scored by the tuning's own evaluation (every scenario, every
   constraint): accepted if its score is lower than the best's (r doubles, at most
   :data:`MAX_RADIUS`; the gradient is taken again there), else rejected (r becomes a
   quarter of the step tried).

It ends after ``refine`` evaluations, when r falls below :data:`MIN_RADIUS`, when the
gradient is 0 in the box, or when there is no gradient (no feasible candidate; no periodic
orbit; a parameter step that leaves the orbit's sample-phase cell), saying which.

What can be refined: robot fields (``robot.<field>``, a leg's ``robot.<field>.<leg>``) with
the built-in laws or a CompiledController object, and the built-in laws' controller
fields (Table I's, pitch feedback's Table I fields): the parameters
:func:`~scoutsim.analysis.orbit_sensitivity.setting_with` can set on an orbit's setting.
Not a CompiledController's parameter array, a Python controller or a user's factory
(their parameters do not reach an orbit's setting); :func:`check_refinable` says so before
the tuning starts.

Determinism: the refinement is a function of the CMA-ES evaluations and the settings, so a
resumed tuning asks the same candidates (their rows are read back from the checkpoint).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from .controlled_orbit import controlled_fixed_point
from .orbit_sensitivity import orbit_sensitivities
from .poincare import MapError
from .tune_evaluation import PENALTY, candidate_controller
from .tune_parameters import apply_values

__all__ = ["REFINED_METRIC", "Refinement", "check_refinable", "objective_gradient", "refine"]

#: the orbit metric each objective is made of
REFINED_METRIC = {
    "speed": "mean_speed_m_s",
    "max-speed": "mean_speed_m_s",
    "cot": "cost_of_transport",
    "stability": "spectral_radius",
}
#: the trust radius's bounds, in the unit cube of the parameters' bounds
MIN_RADIUS = 1e-6
MAX_RADIUS = 0.5
#: the relative parameter steps of the orbit sensitivities, tried in turn. A cycle of many
#: strides has a small sample-phase cell (an 11-stride Table I cycle of Model II at front /
#: back 25.27 / 20.23 deg left it at 1e-6 of a touchdown angle, not at 1e-7), and there the
#: derivative within the cell does not describe the score's trend (measured there: d speed
#: / d front angle -1.6 per rad within the cell, +8 per rad across the tuning's runs), so
#: a smaller step is reported as no gradient rather than refined on
SENSITIVITY_STEPS = (1e-4, 1e-5)
#: the shortest run [s] the orbit's Newton search starts from (the orbit search's own
#: default): after a tuning's shorter runs (6 s) the default Table I gait of Model II,
#: whose multiplier is 0.92 per stride, is still so far from its orbit that Newton stalls
SETTLE_S = 12.0
#: controller kinds whose controller fields reach an orbit's setting
_LAWS = ("table-i", "pitch-feedback")


@dataclass
class Refinement:
    """What a tuning's refinement did.

    evaluations : candidates it scored; accepted : of them, those that became the best.
    start_score, end_score : the best score before and after it.
    stopped : why it ended.
    gradient : the objective's derivative at its last gradient point, per parameter
        (objective's unit per the unit of the parameter's name: per degree for a
        ``_deg`` name).
    """

    evaluations: int = 0
    accepted: int = 0
    start_score: float = math.nan
    end_score: float = math.nan
    stopped: str = ""
    gradient: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return asdict(self)


def check_refinable(params, kind: str) -> None:
    """ValueError naming the first tuned parameter the refinement cannot differentiate
    (module docstring), before the tuning runs."""
    if kind in ("python", "factory"):
        raise ValueError(
            f"refine is not allowed with a {kind} controller: the refinement's gradient is "
            "that of the periodic gait, whose parameters scoutsim sets on the built-in laws "
            "and on robot fields of a controller object (table-i, pitch-feedback, a "
            "CompiledController)"
        )
    for p in params:
        if p.key.startswith("params[") or (p.key.startswith("controller.") and kind not in _LAWS):
            raise ValueError(
                f"refine is not allowed with parameter {p.name!r}: the refinement's gradient "
                "(orbit sensitivities) is taken for robot fields and the built-in laws' "
                "controller fields only; tune without refine"
            )


def _scenario_objective(
    objective: str, target, orbit, sens, base: dict, names
) -> tuple[float, np.ndarray]:
    """(f, df/dp) of one scenario's orbit (its sensitivities ``sens``, its metrics
    ``base``): f the objective made of its metric."""
    metric = REFINED_METRIC[objective]
    k = orbit.strides
    rho = float(np.max(np.abs(orbit.multipliers)))
    if objective == "stability":
        # the per-stride radius rho^(1/k) of a k-stride cycle (the tuning's objective)
        value = rho ** (1.0 / k)
        chain = value / (k * rho) if rho > 0.0 else 0.0
        grad = np.array([chain * sens[n].derivative[metric] for n in names])
        return value, grad
    value = float(base[metric])
    grad = np.array([sens[n].derivative[metric] for n in names])
    if objective == "speed":
        sign = 1.0 if value >= target else -1.0
        return abs(value - target), sign * grad
    if objective == "max-speed":
        return -value, -grad
    return value, grad


def objective_gradient(
    values: dict, params, task_base: dict, scenario_indices, previous: dict | None = None
) -> tuple:
    """(f, df/dp per parameter, {scenario: why not}, {scenario: orbit}) of the tuning's
    objective at the candidate ``values`` ({key: SI}) from the periodic orbits of the
    scenarios ``scenario_indices`` (their mean). A scenario without an orbit or
    sensitivities is named in the third item (and the first two are None).
    ``previous``: {scenario: orbit} at a nearby candidate (the last gradient's): Newton
    starts from such an orbit with its number of strides, and the orbit found is kept if
    it is stable; otherwise (and without one) the orbit is searched from a run of the
    tuning's duration."""
    goal = task_base["goal"]
    spec = task_base["controller"]
    robot, cparams, arr = apply_values(
        values, task_base["robot"], task_base["cparams"], spec.get("params")
    )
    names = [p.key for p in params]
    fs, gs, why, orbits = [], [], {}, {}
    for i in scenario_indices:
        sc = task_base["scenarios"][i]
        setting = dict(
            model=sc["model"],
            friction_coefficient=sc["friction"],
            robot=robot,
            controller=candidate_controller(spec, robot, cparams, arr),
        )
        orbit = None
        near = (previous or {}).get(i)
        if near is not None:
            try:
                orbit = controlled_fixed_point(near.state, strides=near.strides, **setting)
            except (MapError, ValueError):
                orbit = None
            if orbit is not None and float(np.max(np.abs(orbit.multipliers))) >= 1.0:
                orbit = None  # an unstable orbit: not the gait the runs settle on
        if orbit is None:
            try:
                orbit = controlled_fixed_point(
                    sc["initial_state"],
                    settle_duration=max(task_base["duration"], SETTLE_S),
                    **setting,
                )
            except (MapError, ValueError) as exc:
                why[i] = f"no periodic orbit: {exc}"
                continue
        orbits[i] = orbit
        for step in SENSITIVITY_STEPS:
            sens, base = orbit_sensitivities(
                orbit,
                names,
                relative_step=step,
                spectral_radius=goal["objective"] == "stability",
            )
            bad = [s for s in sens.values() if s.status != "ok"]
            if not bad:
                break
        if bad:
            why[i] = f"{bad[0].name}: {bad[0].status}"
            continue
        f, g = _scenario_objective(goal["objective"], goal["target"], orbit, sens, base, names)
        fs.append(f)
        gs.append(g)
    if why:
        return None, None, why, orbits
    return float(np.mean(fs)), np.mean(gs, axis=0), why, orbits


def _step(f: float, g_u: np.ndarray, u: np.ndarray, radius: float, objective: str) -> np.ndarray:
    """The step in the unit cube from ``u`` (module docstring, 2.): along -g_u without the
    components that would leave the box, of length ``radius`` or, for ``speed``, to the
    linear model's zero if that is nearer; zero if no component is left."""
    d = -g_u.copy()
    d[(u <= 0.0) & (d < 0.0)] = 0.0
    d[(u >= 1.0) & (d > 0.0)] = 0.0
    norm = float(np.linalg.norm(d))  # the gradient's within the box
    if norm == 0.0:
        return d
    length = min(radius, f / norm) if objective == "speed" else radius
    return d / norm * length


def refine(
    n: int,
    best_row: dict,
    params,
    task_base: dict,
    radius: float,
    evaluate,
    say=None,
) -> Refinement:
    """Up to ``n`` refinement evaluations from ``best_row`` (the best CMA-ES row, with its
    ``values`` {key: SI} and ``score``), trust radius starting at ``radius`` (a fraction
    of each parameter's range). ``evaluate(values, j)`` scores the j-th candidate with the
    tuning's own evaluation and returns its row. Returns what it did (:class:`Refinement`)."""
    say = say or (lambda message: None)
    res = Refinement(start_score=float(best_row["score"]), end_score=float(best_row["score"]))
    lo = np.array([p.low for p in params])
    hi = np.array([p.high for p in params])
    if not best_row.get("feasible") or best_row["score"] >= PENALTY:
        res.stopped = "no feasible candidate to refine"
        return res
    objective = task_base["goal"]["objective"]
    best_values = dict(best_row["values"])
    best_score = float(best_row["score"])
    worst = best_row.get("scenario")
    stale = True  # no gradient yet at best_values
    orbits: dict = {}  # the orbits the gradient was taken on, by scenario
    f = g_u = None
    while res.evaluations < n:
        if stale:
            if task_base["goal"]["aggregate"] == "mean" or worst is None:
                indices = list(range(len(task_base["scenarios"])))
            else:
                indices = [int(worst)]
            f, g, why, orbits = objective_gradient(best_values, params, task_base, indices, orbits)
            if g is None:
                res.stopped = "no gradient: " + "; ".join(
                    f"scenario {i}: {w}" for i, w in why.items()
                )
                break
            stale = False
            res.gradient = {p.name: float(x) * p.scale for p, x in zip(params, g)}
            g_u = g * (hi - lo)
            say(
                f"refine: objective {f:.6g} on the orbit, |gradient| {np.linalg.norm(g_u):.3g} per range"
            )
        u = np.array([(best_values[p.key] - p.low) / (p.high - p.low) for p in params])
        assert f is not None and g_u is not None, "a gradient is taken before the first step"
        du = _step(f, g_u, u, radius, objective)
        if not np.any(du):
            res.stopped = "the gradient is 0 within the bounds"
            break
        u_new = np.clip(u + du, 0.0, 1.0)
        values = {p.key: float(p.low + (p.high - p.low) * x) for p, x in zip(params, u_new)}
        row = evaluate(values, res.evaluations)
        res.evaluations += 1
        if row["score"] < best_score:
            best_score, best_values = float(row["score"]), values
            worst = row.get("scenario")
            stale = True
            res.accepted += 1
            radius = min(MAX_RADIUS, 2.0 * radius)
            say(f"refine: accepted, score {best_score:.6g}")
        else:
            radius = float(np.linalg.norm(u_new - u)) / 4.0
            say(f"refine: rejected (score {row['score']:.6g}), trust radius {radius:.3g}")
            if radius < MIN_RADIUS:
                res.stopped = f"the trust radius fell below {MIN_RADIUS:g}"
                break
    else:
        res.stopped = f"{n} refinement evaluations"
    res.end_score = best_score
    return res
