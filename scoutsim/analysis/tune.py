"""Tuning: optimise controller (and robot) parameters against an objective a user states.

What is tuned: fields of :class:`~scoutsim.parameters.ControllerParameters` (Table I and
the torso-feedback gains of :class:`~scoutsim.control.PitchFeedbackController`), named
``controller.<field>``; fields of :class:`~scoutsim.parameters.RobotParameters` for design
studies, ``robot.<field>``; entries of a :class:`~scoutsim.CompiledController`'s parameter
array, ``controller.params[i]``. A ``_deg`` suffix on an angle field takes degrees at the
edge (converted here, once); everything inside is SI. Bounds are a range the user gives,
``NAME=LOW:HIGH``, or the field's default search range around its base value
(:data:`~scoutsim.analysis.tune_parameters.DEFAULT_SEARCH`: touchdown angles within 20 deg
of the base controller's), within the field's allowed range
(:func:`scoutsim.parameters.allowed_range`).

The controller may be the user's own: a CompiledController (its parameter array tuned), a
Python controller (robot fields tuned), or a factory ``"MODULE:FACTORY"`` /
:class:`~scoutsim.control.factory.ControllerSpec`, made in each worker with every
candidate's robot and controller parameters (:mod:`scoutsim.analysis.study_controller`;
checked before the first evaluation). An evaluation the tuning could not run is an error
of the tuning, not a score (:mod:`scoutsim.analysis.study_failures`, ``on_error``).

What is minimised (``objective``), over the steady strides of each run:

- ``"speed"``: ``|v - target|`` [m/s], v the mean forward speed of the steady strides;
- ``"max-speed"``: ``-v`` [m/s];
- ``"cot"``: the cost of transport [-] (electrical energy / (m g d), ``simulate(energy=True)``);
- ``"stability"``: the spectral radius [-] per stride of the stride map at the run's
  periodic orbit (Newton from the run's last strides,
  :func:`scoutsim.analysis.controlled_orbit.controlled_fixed_point`; for a cycle of k
  strides the k-th root of its map's spectral radius; < 1: stable), a few seconds per
  evaluation; any controller whose state scoutsim can read and set.

Constraints: the run must not fall (nor fail), must bound steadily
(:meth:`~scoutsim.analysis.gait.GaitMetrics.is_steady_bounding`: at least 7 steady strides
after the 2 s transient, stride periods within 5 %), and optionally keep the belt deflection
below ``max_belt_deflection`` [rad], the motor current below ``max_current`` [A] and the
steady speed above ``min_speed`` [m/s]. Robustness: each evaluation runs every scenario
(the product of ``models``, ``floors`` and ``starts``) and its score is the worst
(``aggregate="worst"``) or the mean of the scenarios' scores.

**Score** (what the optimiser sees, lower is better). CMA-ES ranks the candidates of a
generation and uses nothing but the ranks, so the penalties only have to order them:
every feasible candidate before every infeasible one, and among infeasible ones those
closer to feasible first, so the search is drawn towards the feasible region even when a
generation has no feasible member::

    feasible                        score = objective
    completed, k constraints broken score = P (1 + k + sum_j min(1, e_j)) + objective*
    fell / failed at t_end          score = 10 P (2 - t_end / duration)

with P = :data:`PENALTY` = 1000, e_j each broken constraint's relative excess (not steady:
the fraction of the 7 steady strides missing, 1 with them all but irregular) and
objective* the objective where it is defined (the whole-run average speed stands in for the
steady speed of a run with no steady strides; otherwise 0). A run that falls later ranks
before one that falls sooner.

**Optimiser**: CMA-ES (Hansen & Ostermeier, Evolutionary Computation 9(2), 2001), the
``cmaes`` library's implementation (the one Optuna's CMA-ES sampler uses), in the unit
cube of the parameters' bounds, started at the base parameters with step ``sigma`` (a
fraction of each range). Why CMA-ES: the scores are non-smooth (touchdown events, stride
counts, falls) and a few parameters are tuned at a time, where CMA-ES is the standard
derivative-free method; a generation is a batch of independent runs, which is what
:func:`scoutsim.analysis.parallel.map_tasks` runs on local cores or a Dask cluster. Why
``cmaes`` driven generation by generation rather than an Optuna study: its whole state,
random generator included, pickles, so the optimiser is saved after every generation and a
resumed run asks exactly the candidates the uninterrupted run asked (an Optuna sampler's
random state lives in the process, and its SQLite study would be a second copy of the
evaluations table).

**Refinement** (optional, ``refine`` evaluations after CMA-ES): steps from the best
candidate along the gradient of the objective of its periodic gait (the orbit
sensitivities), each scored by the tuning's own evaluation and kept if it lowers the
score (:mod:`~scoutsim.analysis.tune_refinement`); its rows follow CMA-ES's, with
``phase`` "refine".

**Resuming**: every finished evaluation is appended to ``out/evaluations.jsonl`` as it
arrives (Ctrl-C keeps them all), and the optimiser's state to ``out/optimizer.pkl``
(written atomically) after every generation. The same call again continues from them: the
generation that was cut re-asks the same candidates and runs only those not yet done, so
the table, the best parameters and everything after them equal an uninterrupted run's; a
call with a larger ``budget`` continues a finished one. Determinism: the same settings,
``seed`` and ``budget`` give the same evaluations, on one process, many, or a cluster.

Outputs in ``out``: ``tune.csv`` / ``tune.parquet`` (every evaluation), ``convergence.png``,
``best.toml`` (a controller file, :mod:`scoutsim.analysis.controller_file`, that
``scoutsim run --controller FILE`` reads), ``best.json`` and ``manifest.json``.

The parts have their own modules: :mod:`~scoutsim.analysis.tune_settings` (the settings
``tune()`` takes: :class:`TuneGoal`, :class:`TuneRuns`, :class:`TuneSearch`),
:mod:`~scoutsim.analysis.tune_controller` (the controller tuned and what it reads),
:mod:`~scoutsim.analysis.tune_parameters` (the tuned parameters: names, bounds, units),
:mod:`~scoutsim.analysis.tune_evaluation` (one evaluation: the scenarios' runs and the
score), :mod:`~scoutsim.analysis.tune_optimizer` (CMA-ES, its saved state and the
checkpoint's files), :mod:`~scoutsim.analysis.tune_refinement` (the gradient refinement)
and :mod:`~scoutsim.analysis.tune_result` (the result and the files
written). This module holds the run driver, :func:`tune`, and re-exports the public names.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import math
import os
import sys
from pathlib import Path

import numpy as np
from tqdm import tqdm

from ..io.run_directory import RunDirectory, json_default, json_safe
from ..parameters import RobotParameters
from .parallel import map_tasks, pool_is_broken, worker_pool
from .study_controller import (
    build_controller,
    check_controller_travels,
    check_factory_reads,
    describe_controller,
)
from .study_failures import StudyError, check_on_error, is_error
from .sweep_checkpoint import read_checkpoint
from .tune_controller import check_tuned_fields, controller_spec

# the parts of a tuning, re-exported here as its public API
from .tune_evaluation import (
    AGGREGATES,
    COLUMNS,
    MIN_STEADY_STRIDES,
    OBJECTIVES,
    PENALTY,
    EvaluationNotRunError,
    evaluation_error_row,
    tune_task,
)
from .tune_optimizer import (
    EVALUATIONS,
    OPTIMIZER_STATE,
    MissingDependencyError,
    checkpoint_key,
    cma_class,
    read_state,
    write_state,
)
from .tune_parameters import (
    TuneParameter,
    apply_values,
    base_value,
    has_tunable_array,
    parse_parameter,
    warn_of_box_ends,
)
from .tune_refinement import check_refinable, refine
from .tune_result import TuneResult, write_outputs
from .tune_settings import TuneGoal, TuneRuns, TuneSearch, bundles, check_settings

__all__ = [
    "tune",
    "TuneGoal",
    "TuneRuns",
    "TuneSearch",
    "TuneParameter",
    "TuneResult",
    "parse_parameter",
    "OBJECTIVES",
    "AGGREGATES",
    "PENALTY",
    "EVALUATIONS",
    "OPTIMIZER_STATE",
    "MIN_STEADY_STRIDES",
    "COLUMNS",
    "tune_task",
    "MissingDependencyError",
    "EvaluationNotRunError",
]


def tune(
    parameters,
    *,
    goal: TuneGoal | None = None,
    runs: TuneRuns | None = None,
    search: TuneSearch | None = None,
    out=None,
    workers: int | None = None,
    scheduler=None,
    progress: bool = False,
    resume: bool = True,
    command: str = "",
    on_error: str = "raise",
    **fields,
) -> TuneResult:
    """Optimise parameters against an objective with CMA-ES (module docstring).

    Parameters
    ----------
    parameters : names or :class:`TuneParameter` s (``"controller.touchdown_angle_front_deg"``,
        ``"robot.leg_stiffness=3000:4000"``, ``"controller.params[3]=0:1"``;
        :func:`parse_parameter`).
    goal : :class:`TuneGoal`, what is minimised and the constraints (default
        ``TuneGoal()``: the speed objective, which needs a ``target``).
    runs : :class:`TuneRuns`, the base robot and controller, the duration and the scenarios
        of every evaluation (default: Table I on Scout II, Model II, the default floor and
        start, 20 s).
    search : :class:`TuneSearch`, CMA-ES's budget, seed, initial step and population
        (default: 200 evaluations).
    out : output directory (module docstring); None: nothing written, nothing resumed.
    workers, scheduler : as :func:`scoutsim.analysis.parallel.map_tasks` (local processes,
        or a Dask address / Client / Executor).
    progress : a progress bar on stderr with the best score so far.
    resume : go on from ``out``'s evaluations and optimiser state (default); False starts
        afresh.
    command : the command line, recorded in the manifest.
    on_error : what an evaluation the tuning could not run does
        (:mod:`scoutsim.analysis.study_failures`): "raise" (default) ends the tuning after
        its generation with :class:`~scoutsim.analysis.study_failures.StudyError` (the
        finished evaluations are kept; a resumed tuning runs the failed ones again);
        "record" scores it as infeasible (``30 PENALTY``), records it with status "error"
        and goes on (``TuneResult.n_errors``; a RuntimeWarning).
    **fields : any field of the three bundles by its name, set on the bundle given or
        its default: ``objective``, ``target`` [m/s], ``aggregate``,
        ``max_belt_deflection`` [rad], ``max_current`` [A], ``min_speed`` [m/s];
        ``model``, ``models``, ``floors``, ``starts``, ``duration`` [s], ``robot``,
        ``controller``; ``budget``, ``seed``, ``sigma``, ``population``. So
        ``tune(names, target=1.3, budget=240)`` is ``tune(names,
        goal=TuneGoal(target=1.3), search=TuneSearch(budget=240))``.

    Raises
    ------
    TypeError : a keyword that is no field of the bundles.
    ValueError : a bad parameter name or range, objective or setting (named).
    MissingDependencyError : the ``cmaes`` library is not installed.
    KeyboardInterrupt : Ctrl-C; every finished evaluation is in ``out/evaluations.jsonl``.
    NotSendableError : the controller cannot be sent to the workers (before any run).
    StudyError : an evaluation could not be run (``on_error="raise"``): the controller
        raised or could not be made, or (EvaluationNotRunError) its worker died twice or a
        Dask worker could not load the task; the finished ones are kept likewise.
    """
    goal, runs, search = bundles(goal, runs, search, fields)
    objective, target, aggregate = goal.objective, goal.target, goal.aggregate
    max_belt_deflection, max_current, min_speed = (
        goal.max_belt_deflection,
        goal.max_current,
        goal.min_speed,
    )
    duration, robot, controller = runs.duration, runs.robot, runs.controller
    budget, seed, sigma, population = search.budget, search.seed, search.sigma, search.population
    CMA = cma_class()
    check_settings(goal, search)
    check_on_error(on_error)
    robot = robot or RobotParameters()
    kind, cparams, spec = controller_spec(controller, robot)
    probe = spec.get("controller")
    if kind == "factory" and any("params[" in str(p) for p in parameters):
        # a factory's parameter array: the controller it makes for the base robot
        probe = build_controller(probe, robot, cparams)
        if has_tunable_array(probe):
            spec["params"] = [float(x) for x in probe.params]
    params = [
        p
        if isinstance(p, TuneParameter)
        else parse_parameter(
            p, probe if kind in ("compiled", "factory") else controller, robot, cparams
        )
        for p in parameters
    ]
    if not params:
        raise ValueError("no parameter to tune: give at least one")
    check_tuned_fields(kind, params)
    if kind == "factory":
        ranges = {
            p.name: (p.low / p.scale, p.high / p.scale)
            for p in params
            if p.key.startswith("controller.")
        }
        check_factory_reads(spec.get("controller"), robot, cparams, ranges)
    if search.refine:
        check_refinable(params, kind)
    check_controller_travels(spec.get("controller"), workers, scheduler, 2)
    seen = set()
    for p in params:
        if p.key in seen:
            raise ValueError(f"parameter {p.name!r} is given twice")
        seen.add(p.key)
    scenarios = runs.scenarios()
    dim = len(params)
    pop = int(population) if population else 4 + int(3 * math.log(dim))
    if pop < 4:  # (CMA-ES's weights need at least two selected candidates)
        raise ValueError(f"population = {population!r} is not allowed: must be >= 4")
    if budget < pop:
        raise ValueError(
            f"budget = {budget} is not allowed: it must hold at least one "
            f"generation of {pop} evaluations"
        )
    n_gen = budget // pop
    lo = np.array([p.low for p in params])
    hi = np.array([p.high for p in params])
    base = np.array([base_value(p, robot, cparams, spec) for p in params])
    mean0 = np.clip((base - lo) / (hi - lo), 0.0, 1.0)
    goal_settings = {
        "objective": objective,
        "target": target,
        "aggregate": aggregate,
        "max_belt_deflection": max_belt_deflection,
        "max_current": max_current,
        "min_speed": min_speed,
    }
    settings = {
        "parameters": [dataclasses.asdict(p) for p in params],
        "goal": goal_settings,
        "controller": kind,
        # (a user's controller described by names and numbers, not addresses)
        "controller_spec": {
            k: (describe_controller(v) if k == "controller" else v) for k, v in spec.items()
        },
        "scenarios": [
            {
                "model": s["model"],
                "friction": None if math.isinf(s["friction"]) else s["friction"],
                "initial_state": None
                if s["initial_state"] is None
                else dataclasses.asdict(s["initial_state"]),
            }
            for s in scenarios
        ],
        "duration_s": duration,
        "robot": dataclasses.asdict(robot),
        "controller_parameters": dataclasses.asdict(cparams),
        "seed": seed,
        "sigma": sigma,
        "population": pop,
    }
    skey = checkpoint_key(settings)
    task_base = {
        "goal": goal_settings,
        "duration": duration,
        "robot": robot,
        "cparams": cparams,
        "controller": spec,
        "scenarios": scenarios,
    }
    warn_of_box_ends(params, robot, cparams)

    done: dict = {}
    rd = ck = state_path = None
    cma = None
    gen = 0
    if out is not None:
        out = Path(out)
        rd = RunDirectory(
            out,
            command=command,
            info={
                "kind": "tune",
                "checkpoint": EVALUATIONS,
                "optimizer_state": OPTIMIZER_STATE,
                "budget": budget,
            },
        ).open()
        ck, state_path = out / EVALUATIONS, out / OPTIMIZER_STATE
        saved = read_state(state_path) if resume else None
        if saved is not None and saved["key"] == skey:
            cma, gen = saved["cma"], saved["generation"]
            done = read_checkpoint(ck)
        else:
            for p in (ck, state_path):
                if p.exists():
                    p.unlink()
    if cma is None:
        cma = CMA(
            mean=mean0,
            sigma=sigma,
            bounds=np.array([[0.0, 1.0]] * dim),
            seed=seed,
            population_size=pop,
        )
        gen = 0
        cma = write_state(state_path, skey, 0, cma)
    n_resumed = len(done)

    bar = tqdm(
        total=n_gen * pop + search.refine,
        unit="run",
        desc="tune",
        file=sys.stderr,
        disable=not progress,
        leave=False,
    )
    rows_by_key: dict = {}
    stopped = "budget"
    refine_keys: list = []  # the refinement's evaluations, in order
    refinement = None
    fh = open(ck, "a") if ck is not None else None
    best = math.inf

    def record(key, row):
        nonlocal best
        rows_by_key[key] = row
        best = min(best, row["score"])
        bar.set_postfix_str(f"best {best:.4g}")
        bar.update(1)

    def kept(key, values) -> bool:
        """Record the checkpoint's row of ``key`` if it is of ``values`` (and not an error
        to run again); False if there is none."""
        row = done.get(key)
        if row is None or row.get("values") != values:
            return False
        if on_error == "raise" and is_error(row):
            return False
        record(key, row)
        return True

    def keep(key, row):
        """Append a finished evaluation to the checkpoint and record it."""
        if fh is not None:
            fh.write(json.dumps({"key": key, "row": row}, default=json_default) + "\n")
            fh.flush()
        record(key, row)

    n_workers = workers or os.cpu_count() or 1
    own_pool = scheduler is None and n_workers > 1
    pools = contextlib.ExitStack()
    try:
        # the generations already told: their rows come from the checkpoint
        for g in range(min(gen, n_gen)):
            for i in range(pop):
                k = checkpoint_key([skey, g, i])
                if k not in done:
                    raise ValueError(
                        f"{out}/{EVALUATIONS} lacks evaluation {g * pop + i} of "
                        f"generation {g}, which {out}/{OPTIMIZER_STATE} has "
                        "told the optimiser: start afresh (resume off, "
                        "--no-resume)"
                    )
                record(k, done[k])
        while gen < n_gen:
            if cma.should_stop():
                stopped = "converged"
                break
            xs = [cma.ask() for _ in range(pop)]
            keys = [checkpoint_key([skey, gen, i]) for i in range(pop)]
            tasks, todo = [], []
            for i, (x, k) in enumerate(zip(xs, keys)):
                values = {p.key: float(p.low + (p.high - p.low) * u) for p, u in zip(params, x)}
                if kept(k, values):
                    continue
                tasks.append(
                    task_base | {"values": values, "evaluation": gen * pop + i, "generation": gen}
                )
                todo.append(k)

            failed: list = []  # this generation's evaluations that could not be run

            def on_result(j, row, todo=todo, failed=failed):
                if on_error == "raise" and is_error(row):
                    failed.append(row)  # never recorded: a resumed tuning runs it again
                    return
                keep(todo[j], row)

            if tasks:
                if own_pool and (scheduler is None or pool_is_broken(scheduler)):
                    # one pool for every generation (a broken one is replaced)
                    pools.close()
                    scheduler = pools.enter_context(worker_pool(min(n_workers, pop)))
                map_tasks(
                    tune_task,
                    tasks,
                    workers=workers,
                    scheduler=scheduler,
                    progress=False,
                    on_result=on_result,
                    error_row=evaluation_error_row,
                )
                if failed:
                    failed.sort(key=lambda r: r["evaluation"])
                    r = failed[0]
                    shown = {p.name: p.shown(r["values"][p.key]) for p in params}
                    error = (
                        EvaluationNotRunError
                        if any(f.get("not_run") for f in failed)
                        else StudyError
                    )
                    raise error(
                        f"{len(failed)} evaluation(s) of generation {gen} could not be run "
                        f"(an error of the tuning, not a score); evaluation "
                        f"{r['evaluation']} at {shown}: {r['error']}"
                        + (
                            f"; the finished evaluations are kept in {ck}: the same call "
                            "again goes on from them"
                            if ck is not None
                            else ""
                        )
                        + "; or pass on_error='record' to score such evaluations as "
                        "infeasible and go on",
                        failed,
                    )
            cma.tell([(x, rows_by_key[k]["score"]) for x, k in zip(xs, keys)])
            gen += 1
            cma = write_state(state_path, skey, gen, cma)
        cma_keys = [
            checkpoint_key([skey, g, i])
            for g in range(gen if stopped == "converged" else n_gen)
            for i in range(pop)
        ]
        if search.refine > 0:

            def evaluate(values, j):
                k = checkpoint_key([skey, "refine", j])
                refine_keys.append(k)
                if kept(k, values):
                    return done[k]
                task = task_base | {
                    "values": values,
                    "evaluation": len(cma_keys) + j,
                    "generation": len(cma_keys) // pop,
                    "phase": "refine",
                }
                row = tune_task(task)
                if is_error(row) and on_error == "raise":
                    shown = {p.name: p.shown(values[p.key]) for p in params}
                    raise StudyError(
                        f"refinement evaluation {j} at {shown} could not be run: {row['error']}",
                        [row],
                    )
                keep(k, row)
                return row

            first = min(range(len(cma_keys)), key=lambda j: (rows_by_key[cma_keys[j]]["score"], j))
            refinement = refine(
                search.refine,
                rows_by_key[cma_keys[first]],
                params,
                task_base,
                sigma,
                evaluate,
                say=(lambda message: bar.write(message)) if progress else None,
            )
    except BaseException as exc:
        pools.__exit__(type(exc), exc, exc.__traceback__)  # kills the workers at once
        if rd is not None and isinstance(exc, (KeyboardInterrupt, StudyError)):
            rd.finish(
                outcome="interrupted"
                if isinstance(exc, KeyboardInterrupt)
                else "evaluation not run",
                partial=True,
            )
        raise
    else:
        pools.close()
    finally:
        bar.close()
        if fh is not None:
            fh.close()

    raw = [rows_by_key[k] for k in cma_keys + refine_keys]
    rows = []
    for r in raw:
        row = {p.name: p.shown(r["values"][p.key]) for p in params}
        row.update({k: r.get(k) for k in COLUMNS})
        rows.append(row)
    b = min(range(len(rows)), key=lambda j: (rows[j]["score"], j))
    best_row = rows[b]
    best_values = {p.key: raw[b]["values"][p.key] for p in params}
    b_robot, b_cparams, b_params = apply_values(best_values, robot, cparams, spec.get("params"))
    n_errors = sum(r.get("status") == "error" for r in rows)
    res = TuneResult(
        rows=rows,
        parameters=params,
        best=best_row,
        best_values=best_values,
        robot=b_robot,
        controller_parameters=b_cparams,
        params=b_params,
        settings=json_safe(settings)
        | {"budget": budget, "refine": search.refine, "n_resumed": n_resumed},
        stopped=stopped,
        n_errors=n_errors,
        refinement=None if refinement is None else refinement.to_dict(),
    )
    if n_errors:
        import warnings

        warnings.warn(
            f"the tuning: {n_errors} of its {len(rows)} evaluations could not be "
            "run and are recorded with status 'error', scored as infeasible",
            RuntimeWarning,
            stacklevel=2,
        )
    if rd is not None:
        write_outputs(res, rd, command)
    return res
