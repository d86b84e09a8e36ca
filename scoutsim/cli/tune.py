"""``scoutsim tune``: optimise controller (or robot) parameters against an objective with
CMA-ES (:mod:`scoutsim.analysis.tune`), in local processes or on a Dask cluster, and write
tune.csv / tune.parquet (every evaluation), convergence.png, best.toml (a controller file:
``scoutsim run --controller DIR/best.toml``), best.json and the checkpoints
evaluations.jsonl and optimizer.pkl (Ctrl-C exits with status 130 and keeps every finished
evaluation; the same command again goes on from them).

    scoutsim tune --param NAME[=LOW:HIGH] ... [--objective {speed,max-speed,cot,stability}]
                  [--target M_S] [--budget N] [--model LIST] [--floors LIST]
                  [--speeds LIST] [--pitch-rates LIST] [--aggregate {worst,mean}]
                  [--controller {table-i,pitch-feedback,FILE}] [--max-belt-deflection DEG]
                  [--max-current A] [--min-speed M_S] [--seed N] [--sigma F]
                  [--population N] [--refine N] [--workers N] [--scheduler ADDRESS]
                  [--no-resume]
                  [--duration S] [--robot FILE] [--out DIR] [--friction MU]
"""

from __future__ import annotations

import math
import os
import sys
import time

from ..analysis.tune import TuneRuns
from ._common import (
    CONTROLLED_MODELS,
    UsageError,
    add_controller_option,
    add_duration_option,
    add_parallel_options,
    check_expected_time,
    controller_choice,
    float_list,
    friction_list,
    load_parameters,
    make_controller,
    model_list,
    out_dir,
    positive_float,
    positive_int,
    show_progress,
    usage_errors,
)
from ._given import refuse_given

NAME = "tune"
#: default simulated time of every evaluation [s]: TuneRuns' default
DEFAULT_DURATION_S = TuneRuns.duration


def register(sub, common) -> None:
    tu = sub.add_parser(
        NAME,
        parents=[common],
        help="optimise controller or robot parameters (CMA-ES) against an objective",
        description="Optimise parameters named controller.<field>, robot.<field> (SI units "
        "as in ControllerParameters / RobotParameters; a _deg suffix on an angle "
        "field takes degrees), each within its allowed range or NAME=LOW:HIGH, "
        "with CMA-ES against an objective, on local cores or a Dask cluster. "
        f"Every evaluation runs --duration ({DEFAULT_DURATION_S:g} s by default) and must "
        "complete without falling and bound steadily. Writes "
        "tune.csv, tune.parquet, convergence.png, best.toml (scoutsim run "
        "--controller DIR/best.toml) and best.json; an interrupted tuning "
        "resumes from evaluations.jsonl and optimizer.pkl. Example: scoutsim "
        "tune --objective speed --target 1.30 --param "
        "controller.touchdown_angle_front_deg --param "
        "controller.touchdown_angle_back_deg --model II --budget 200 --out DIR",
    )
    add_duration_option(tu, DEFAULT_DURATION_S, "simulated time of every evaluation's runs")
    tu.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="NAME[=LOW:HIGH]",
        help="a tuned parameter (repeatable); LOW:HIGH in the name's unit, "
        "default its allowed range",
    )
    tu.add_argument(
        "--objective",
        choices=("speed", "max-speed", "cot", "stability"),
        default="speed",
        help="speed: |steady speed - --target|; max-speed: the fastest steady "
        "bound; cot: the lowest cost of transport; stability: the smallest "
        "spectral radius of the stride map (a few s per evaluation) "
        "(default: speed)",
    )
    tu.add_argument(
        "--target",
        type=positive_float,
        default=None,
        metavar="M_S",
        help="target steady speed [m/s] of --objective speed",
    )
    tu.add_argument(
        "--budget",
        type=positive_int,
        default=200,
        metavar="N",
        help="the most evaluations (whole CMA-ES generations) (default: 200)",
    )
    tu.add_argument(
        "--model",
        type=model_list,
        default=["II"],
        metavar="LIST",
        help="model(s) of every evaluation: one, or a comma-separated list "
        "(robustness over models) (default: II)",
    )
    tu.add_argument(
        "--floors",
        type=friction_list,
        default=None,
        metavar="LIST",
        help="toe friction coefficients (robustness over floors; default: --friction)",
    )
    tu.add_argument(
        "--speeds",
        type=float_list(positive=True),
        default=None,
        metavar="LIST",
        help="forward speeds of the start [m/s] (robustness over starts)",
    )
    tu.add_argument(
        "--pitch-rates",
        type=float_list(),
        default=None,
        metavar="LIST",
        help="pitch rates of the start [deg/s] (robustness over starts)",
    )
    tu.add_argument(
        "--aggregate",
        choices=("worst", "mean"),
        default="worst",
        help="score of an evaluation over its scenarios (default: worst)",
    )
    add_controller_option(tu)
    tu.add_argument(
        "--max-belt-deflection",
        type=positive_float,
        default=None,
        metavar="DEG",
        help="constraint: largest belt deflection [deg] (Model II)",
    )
    tu.add_argument(
        "--max-current",
        type=positive_float,
        default=None,
        metavar="A",
        help="constraint: largest motor current [A]",
    )
    tu.add_argument(
        "--min-speed",
        type=positive_float,
        default=None,
        metavar="M_S",
        help="constraint: slowest steady speed [m/s]",
    )
    tu.add_argument("--seed", type=int, default=0, help="optimiser seed (default: 0)")
    tu.add_argument(
        "--sigma",
        type=positive_float,
        default=0.1,
        metavar="F",
        help="initial CMA-ES step as a fraction of each range (default: 0.1)",
    )
    tu.add_argument(
        "--population",
        type=positive_int,
        default=None,
        metavar="N",
        help="candidates per generation (default: 4 + 3 ln n)",
    )
    tu.add_argument(
        "--refine",
        type=int,
        default=0,
        metavar="N",
        help="after CMA-ES, up to N evaluations of a gradient refinement along the "
        "periodic gait's exact derivatives (robot fields and the built-in laws' fields; "
        "default: 0, none)",
    )
    add_parallel_options(tu, "start afresh even if DIR holds an earlier tuning's checkpoints")
    tu.set_defaults(func=execute)


def _starts(args, robot, model):
    """The starts of the scenarios: the model's default start with --speeds x
    --pitch-rates (None: the default start alone)."""
    if args.speeds is None and args.pitch_rates is None:
        return None
    from ..simulation.initial_conditions import default_initial_state

    base = default_initial_state(model, robot)
    out = []
    for v in args.speeds or [None]:
        for w in args.pitch_rates or [None]:
            ch = {}
            if v is not None:
                ch["dx"] = v
            if w is not None:
                ch["dtheta"] = math.radians(w)
            out.append(base.replace(**ch))
    return out


def _where_in_a_robot_file(parameters) -> str:
    """Where each tuned value goes in a robot file: its field's section, and for one leg of
    a per-leg field, that leg's entry of the (back, front) pair."""
    from ..parameters.robot_fields import field_of
    from ..parameters.schema import field_schema

    places = []
    for p in parameters:
        section, _, name = p.key.partition(".")
        if section != "robot":
            places.append(f"{p.name}: [controller]")
            continue
        field, leg = field_of(name)
        where = f"[{field_schema()[field].section}] {field}"
        if leg is not None:
            where += f", the {name.rpartition('.')[2]} entry of [back, front]"
        places.append(f"{p.name}: {where}")
    return "; ".join(places)


def execute(args) -> int:
    from ..analysis.parallel import NotSendableError, SchedulerUnreachableError
    from ..analysis.study_failures import StudyError
    from ..analysis.sweep import read_checkpoint
    from ..analysis.tune import TuneGoal, TuneRuns, TuneSearch, tune
    from ..analysis.tune_optimizer import EVALUATIONS, MissingDependencyError
    from ..analysis.tune_parameters import parse_parameter
    from ..simulation.simulator import warm_up

    if not args.param:
        raise UsageError("give at least one --param NAME[=LOW:HIGH] to tune")
    if args.objective == "speed" and args.target is None:
        raise UsageError("--objective speed needs --target M_S (the steady speed to reach)")
    if args.objective != "speed" and args.target is not None:
        raise UsageError(f"--target is only allowed with --objective speed, not {args.objective}")
    bad = [m for m in args.model if m not in CONTROLLED_MODELS]
    if bad:
        raise UsageError(
            f"--model {','.join(bad)} is not allowed: tuning needs a controlled "
            f"model ({', '.join(CONTROLLED_MODELS)})"
        )
    robot, cparams = load_parameters(args.robot)
    law, cparams = controller_choice(args.controller, cparams)
    controller = make_controller(law, cparams, robot, on_workers=True)
    with usage_errors():
        # a range left out is centred on the robot file's (or controller file's) value
        params = [parse_parameter(p, controller, robot, cparams) for p in args.param]
    if args.floors is not None:
        refuse_given(args, ("friction",), "with --floors (give the floor in the list)")
    floors = args.floors or [args.friction]
    starts = _starts(args, robot, args.model[0])
    n_scen = len(args.model) * len(floors) * len(starts or [None])
    try:
        from cmaes import CMA  # noqa: F401 - only to say what to install, before anything runs
    except ImportError:
        raise UsageError(
            "scoutsim tune needs the CMA-ES library 'cmaes': pip install cmaes "
            "(or pip install 'scoutsim[tune]')"
        ) from None
    check_expected_time(
        args,
        {m: args.budget * args.duration * len(floors) * len(starts or [None]) for m in args.model},
        runs=args.budget * n_scen,
        per_run_s=5.0 if args.objective == "stability" else 0.0,
        workers=1 if args.scheduler else (args.workers or os.cpu_count() or 1),
        what=f"the tuning of {args.budget} evaluations",
    )
    out = out_dir(args.out)
    if args.scheduler is None:
        warm_up()  # compiled (or loaded) once here; the workers then load the cache
    wall0 = time.perf_counter()
    try:
        with usage_errors(
            ValueError, SchedulerUnreachableError, MissingDependencyError, NotSendableError
        ):
            goal = TuneGoal(
                objective=args.objective,
                target=args.target,
                aggregate=args.aggregate,
                max_belt_deflection=(
                    None
                    if args.max_belt_deflection is None
                    else math.radians(args.max_belt_deflection)
                ),
                max_current=args.max_current,
                min_speed=args.min_speed,
            )
            runs = TuneRuns(
                models=args.model,
                floors=floors,
                starts=starts,
                duration=args.duration,
                robot=robot,
                controller=controller,
            )
            search = TuneSearch(
                budget=args.budget,
                seed=args.seed,
                sigma=args.sigma,
                population=args.population,
                refine=args.refine,
            )
            res = tune(
                params,
                goal=goal,
                runs=runs,
                search=search,
                out=out,
                workers=args.workers,
                scheduler=args.scheduler,
                progress=show_progress(args),
                resume=not args.no_resume,
                command=" ".join(["scoutsim"] + sys.argv[1:]),
            )
    except StudyError as exc:  # evaluations the tuning could not run (not the robot's)
        print(f"scoutsim tune: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        n_done = len(read_checkpoint(out / EVALUATIONS))
        print(
            f"scoutsim tune: interrupted; {n_done} evaluations are done and kept in "
            f"{out}/{EVALUATIONS} (no table written): run the same command again to go on",
            file=sys.stderr,
        )
        return 130
    wall = time.perf_counter() - wall0
    b = res.best
    n_feasible = sum(bool(r["feasible"]) for r in res.rows)
    print(
        f"scoutsim tune: {len(res.rows)} evaluations ({res.settings['n_resumed']} resumed "
        f"from {out}/{EVALUATIONS}), {n_feasible} feasible; stopped: {res.stopped}"
    )
    if res.refinement is not None:
        r = res.refinement
        print(
            f"  refinement: {r['evaluations']} evaluations, {r['accepted']} accepted, "
            f"best score {r['start_score']:.6g} -> {r['end_score']:.6g}; stopped: {r['stopped']}"
        )
    print(
        f"  objective {args.objective}"
        + (f", target {args.target:g} m/s" if args.target is not None else "")
        + f"; best score {b['score']:.6g} at evaluation {b['evaluation']}"
        + ("" if b["feasible"] else f" (INFEASIBLE: {b['violations']})")
    )
    for p in res.parameters:
        print(f"  {p.name} = {b[p.name]:.6g}")
    speed = b["mean_speed_m_s"]
    print(
        f"  best run: {b['outcome']}, mean steady speed "
        + (f"{speed:.4f} m/s" if speed is not None else "n/a")
        + f", {b['n_steady_strides']} steady strides, steady bounding "
        + ("yes" if b["steady_bounding"] else "no")
    )
    tuned_robot = any(p.key.startswith("robot.") for p in res.parameters)
    written = [
        name
        for name in ("tune.csv", "tune.parquet", "convergence.png", "best.toml", "best.json")
        if (out / name).is_file()
    ]
    print(f"  wall time {wall:.1f} s; wrote {', '.join(written)} to {out}/")
    tail = (
        f" --model {args.model[0]}" if args.model[0] != "II" else ""
    ) + f" --duration {args.duration:g}"
    if "best.toml" in written:
        print(
            f"  run it: scoutsim run --controller {out}/best.toml"
            + (
                f" --robot {out}/best.toml"
                if tuned_robot
                else (f" --robot {args.robot}" if args.robot else "")
            )
            + tail
        )
    else:
        # a user's controller (MODULE:FACTORY): the tuned values are the parameters its
        # factory was called with, which a controller file of the Table I law cannot carry
        print(
            f"  run it: put the tuned values of {out}/best.json in a robot file "
            f"({_where_in_a_robot_file(res.parameters)}) and run scoutsim run --controller "
            f"{args.controller} --robot FILE" + tail
        )
    return 0
