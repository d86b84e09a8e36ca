"""``scoutsim uncertainty``: what uncertain robot, controller and floor parameters do to the
gait. Sample the parameters (``--param``, repeatable, and the robot file's
``[uncertainty]`` section) by the Saltelli design, run the ``N (d + 2)`` simulations in
local processes or on a Dask cluster, and write samples.parquet, indices.csv (first-order
and total Sobol' indices with confidence intervals), summary.json, the checkpoint
points.jsonl (an interrupted study resumes: Ctrl-C exits with status 130 and keeps every
finished run) and figures (:mod:`scoutsim.analysis.uncertainty`).

    scoutsim uncertainty --param NAME=LOW:HIGH|NAME=normal:MEAN:SD ... [--samples N]
                         [--seed N] [--energy] [--model {ideal,I,II}] [--workers N]
                         [--scheduler ADDRESS] [--no-resume] [--duration S]
                         [--robot FILE] [--out DIR] [--friction MU] [--plots/--no-plots]
"""

from __future__ import annotations

import os
import sys
import time
import warnings

from ..analysis.sweep import SweepBase
from ._common import (
    CONTROLLED_MODELS,
    UsageError,
    add_controller_option,
    add_duration_option,
    add_parallel_options,
    add_plots_option,
    check_expected_time,
    controller_choice,
    load_parameters,
    make_controller,
    out_dir,
    positive_int,
    show_progress,
    usage_errors,
)

#: simulated time per run [s]: SweepBase's default
DEFAULT_DURATION_S = SweepBase.duration
#: base sample size: a power of two (the Sobol' points stay balanced)
DEFAULT_SAMPLES = 64

NAME = "uncertainty"


def register(sub, common) -> None:
    p = sub.add_parser(
        NAME,
        parents=[common],
        help="global sensitivity of the gait to uncertain parameters (Sobol' indices)",
        description="Sample uncertain parameters, named robot.<field>, controller.<field> "
        "(SI units; a _deg suffix on an angle field takes degrees) or "
        "friction_coefficient, uniform (NAME=LOW:HIGH) or normal truncated at the "
        "field's allowed range (NAME=normal:MEAN:SD), also from the robot file's "
        "[uncertainty] section; run N (d + 2) simulations and write samples.parquet, "
        "indices.csv (first-order and total Sobol' indices, 95% confidence "
        "intervals), summary.json, the checkpoint points.jsonl and figures. Example: "
        "scoutsim uncertainty --param controller.touchdown_angle_front_deg=20:22 "
        "--param robot.leg_stiffness=3000:3800 --samples 16 --duration 6",
    )
    add_duration_option(p, DEFAULT_DURATION_S, "simulated time per run")
    add_controller_option(p)
    add_plots_option(p, True, "indices.png and distributions.png")
    p.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="NAME=LOW:HIGH|NAME=normal:MEAN:SD",
        help="uncertain parameter (repeatable): uniform on [LOW, HIGH) or normal (truncated "
        "at the field's allowed range), in the unit of NAME",
    )
    p.add_argument(
        "--samples",
        type=positive_int,
        default=DEFAULT_SAMPLES,
        metavar="N",
        help=f"base sample size N, a power of two; N (d + 2) runs (default: {DEFAULT_SAMPLES})",
    )
    p.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    p.add_argument(
        "--energy",
        action="store_true",
        help="also account for every run's energy and add the cost of transport to the "
        "metrics (the same runs, each about 1.1 times as long to compute)",
    )
    p.add_argument("--model", choices=CONTROLLED_MODELS, default="II", help="model (default: II)")
    add_parallel_options(p, "recompute every run even if DIR/points.jsonl has it")
    p.set_defaults(func=execute)


def _parameters(args) -> list:
    """The uncertain parameters: the robot file's [uncertainty] section, then --param
    (a name given in both: --param's)."""
    from ..analysis.uncertainty import parse_parameter, read_uncertainty

    with usage_errors():
        given = [parse_parameter(t) for t in args.param]
        names = [p.name for p in given]
        if len(set(names)) != len(names):
            raise UsageError(f"--param: a parameter is given twice: {names}")
        from_file = read_uncertainty(args.robot) if args.robot else []
        fields = {p.field for p in given}
        params = [p for p in from_file if p.field not in fields] + given
    if not params:
        raise UsageError(
            "give uncertain parameters: --param NAME=LOW:HIGH (or NAME=normal:MEAN:SD), or "
            "an [uncertainty] section in the --robot file"
        )
    if args.samples < 2 or args.samples & (args.samples - 1):
        raise UsageError(f"--samples {args.samples} is not allowed: a power of two >= 2")
    return params


def execute(args) -> int:
    from ..analysis.parallel import NotSendableError, SchedulerUnreachableError
    from ..analysis.study_failures import StudyError
    from ..analysis.sweep import CHECKPOINT, read_checkpoint
    from ..analysis.uncertainty import check_parameters, uncertainty_study
    from ..control.factory import FactoryError

    params = _parameters(args)
    n_runs = args.samples * (len(params) + 2)
    check_expected_time(
        args,
        {args.model: n_runs * args.duration},
        runs=n_runs,
        workers=1 if args.scheduler else (args.workers or os.cpu_count() or 1),
        what=f"the study of {n_runs} runs",
    )
    robot, cparams = load_parameters(args.robot)
    with usage_errors():
        check_parameters(params, robot)
    law, cparams = controller_choice(args.controller, cparams)
    controller = make_controller(law, cparams, robot, on_workers=True)
    out = out_dir(args.out)
    wall0 = time.perf_counter()
    try:
        with (
            usage_errors(SchedulerUnreachableError, NotSendableError, FactoryError),
            warnings.catch_warnings(),
        ):
            warnings.simplefilter("ignore", RuntimeWarning)
            res = uncertainty_study(
                params,
                n=args.samples,
                seed=args.seed,
                model=args.model,
                duration=args.duration,
                robot=robot,
                controller=controller,
                friction_coefficient=args.friction,
                out=out,
                workers=args.workers,
                scheduler=args.scheduler,
                progress=show_progress(args),
                resume=not args.no_resume,
                command=" ".join(["scoutsim"] + sys.argv[1:]),
                energy=args.energy,
            )
    except KeyboardInterrupt:
        n_done = len(read_checkpoint(out / CHECKPOINT))
        print(
            f"scoutsim uncertainty: interrupted; {n_done} of {n_runs} runs are done and kept "
            f"in {out}/{CHECKPOINT} (no table written): run the same command again to "
            "finish the rest",
            file=sys.stderr,
        )
        return 130
    except StudyError as exc:
        print(f"scoutsim uncertainty: {exc}", file=sys.stderr)
        return 1
    wall = time.perf_counter() - wall0
    s = res.summary()
    print(
        f"scoutsim uncertainty: {len(params)} parameters, N = {args.samples}: {n_runs} runs of "
        f"model {args.model}, {args.duration:g} s each"
    )
    print("  outcomes: " + ", ".join(f"{k} {v}" for k, v in s["outcomes"].items()))
    print(f"  share of samples that do not bound: {s['share_not_bounding']:.3f}")
    reasons: dict[str, list[str]] = {}
    for metric, reason in res.not_computed.items():
        reasons.setdefault(reason, []).append(metric)
    for reason, metrics in reasons.items():
        print(f"  indices not computed for {', '.join(metrics)}: {reason}")
    print(f"  wall time {wall:.1f} s; wrote samples.parquet, indices.csv, summary.json to {out}/")
    if args.plots:
        from ..io.run_directory import add_to_manifest
        from ..presentation.uncertainty_plots import plot_uncertainty

        written = plot_uncertainty(res, out)
        add_to_manifest(out, [p.name for p in written])
        print(f"  figures: {', '.join(p.name for p in written)}")
    return 0
