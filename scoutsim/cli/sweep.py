"""``scoutsim sweep``: a parameter sweep. Run a grid or a random sample of robot/controller
parameters (``robot.<field>`` / ``controller.<field>``, SI units; a ``_deg`` suffix takes
degrees) in local processes or on a Dask cluster, and write sweep.parquet, sweep.csv, the
checkpoint points.jsonl (an interrupted sweep resumes: Ctrl-C exits with status 130 and
keeps every finished point) and, for a two-parameter grid, maps; manifest.json lists the
files of a complete sweep.

    scoutsim sweep (--grid NAME=START:STOP:NUM ... | --random NAME=LOW:HIGH ... [--samples N])
                   [--seed N] [--model {ideal,I,II}] [--workers N] [--scheduler ADDRESS]
                   [--no-resume] [--orbit] [--duration S] [--robot FILE] [--out DIR]
                   [--rtol X] [--atol X] [--friction MU] [--no-progress]
"""

from __future__ import annotations

import math
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

#: simulated time per point [s]: SweepBase's default
DEFAULT_DURATION_S = SweepBase.duration

#: wall seconds of --orbit per point (Newton on the stride map; "a few seconds")
ORBIT_SECONDS_PER_POINT = 5.0

NAME = "sweep"


def register(sub, common) -> None:
    sw = sub.add_parser(
        NAME,
        parents=[common],
        help="parameter sweep (grid or random sample) in parallel or on a Dask cluster",
        description="Run a grid or random sample of robot/controller parameters, named "
        "robot.<field> or controller.<field> (SI units as in RobotParameters / "
        "ControllerParameters; a _deg suffix on an angle field takes degrees), "
        "and write sweep.parquet, sweep.csv, the checkpoint points.jsonl (an "
        "interrupted sweep resumes) and, for a two-parameter grid, map.png. "
        "Example: scoutsim sweep --grid controller.touchdown_angle_front_deg="
        "15:27:20 --grid controller.touchdown_angle_back_deg=13:25:20 "
        "--duration 2",
    )
    add_duration_option(sw, DEFAULT_DURATION_S, "simulated time per point")
    add_controller_option(sw)
    add_plots_option(sw, True, "map.png (and with --orbit stability.png) of a two-parameter grid")
    sw.add_argument(
        "--grid",
        action="append",
        default=[],
        metavar="NAME=START:STOP:NUM",
        help="grid axis (repeatable): NUM values from START to STOP",
    )
    sw.add_argument(
        "--random",
        action="append",
        default=[],
        metavar="NAME=LOW:HIGH",
        help="uniformly sampled parameter (repeatable), with --samples",
    )
    sw.add_argument(
        "--samples",
        type=positive_int,
        default=100,
        metavar="N",
        help="number of random points (default: 100)",
    )
    sw.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    sw.add_argument(
        "--max-points",
        type=positive_int,
        default=100_000,
        metavar="N",
        help="refuse sweeps of more points than this before starting (default: 100000)",
    )
    sw.add_argument("--model", choices=CONTROLLED_MODELS, default="II", help="model (default: II)")
    add_parallel_options(sw, "recompute every point even if DIR/points.jsonl has it")
    sw.add_argument(
        "--orbit",
        action="store_true",
        help="also find each bounding point's periodic orbit (Newton) and record "
        "its period and Floquet stability (a few s per point)",
    )
    sw.set_defaults(func=execute)


def _sweep_axis(text: str, n_parts: int):
    """'name=a:b[:n]' -> (name, floats): a _deg name keeps its degrees, which the sweep
    converts to the field's radians for each run and keeps in the table's _deg column."""
    name, sep, rng = text.partition("=")
    parts = rng.split(":")
    if not sep or len(parts) != n_parts:
        form = "NAME=START:STOP:NUM" if n_parts == 3 else "NAME=LOW:HIGH"
        raise UsageError(f"{text!r} is not allowed: must be {form}")
    try:
        vals = [float(v) for v in parts]
    except ValueError:
        raise UsageError(f"{text!r}: the range must be numbers") from None
    if not all(math.isfinite(v) for v in vals):
        raise UsageError(f"{text!r}: the range must be finite numbers")
    if name.endswith("_deg"):
        from ..parameters import field_dimension

        base = name[:-4]
        if field_dimension(base.partition(".")[2]) != "angle":
            raise UsageError(
                f"{text!r} is not allowed: the _deg suffix takes degrees for "
                f"an angle; {base!r} is not an angle (give it in SI units, "
                "without the suffix)"
            )
    return name, vals


def _unique(name: str, seen: set, text: str) -> None:
    if name in seen:
        raise UsageError(f"{text!r}: {name} is given twice (one axis per parameter)")
    seen.add(name)


def _points(args):
    """The sweep's points from --grid axes or --random bounds."""
    import numpy as np

    from ..analysis.sweep import grid_points, random_points

    with usage_errors():
        seen = set()
        if args.grid:
            sizes = {}
            for g in args.grid:
                name, (a, b, n) = _sweep_axis(g, 3)
                _unique(name, seen, g)
                if n < 1 or n != int(n):
                    raise UsageError(f"{g!r}: NUM must be a whole number >= 1")
                sizes[name] = (a, b, int(n))
            total = math.prod(n for _, _, n in sizes.values())
            if total > args.max_points:
                raise UsageError(
                    f"the grid has {total:.4g} points, more than --max-points "
                    f"{args.max_points} (at about 0.1 s per point of 10 s); "
                    "raise --max-points to run it anyway"
                )
            return grid_points({k: np.linspace(a, b, n) for k, (a, b, n) in sizes.items()})
        bounds = {}
        for g in args.random:
            name, (a, b) = _sweep_axis(g, 2)
            _unique(name, seen, g)
            if not a < b:
                raise UsageError(f"{g!r} is not allowed: LOW must be below HIGH")
            bounds[name] = (a, b)
        if args.samples > args.max_points:
            raise UsageError(
                f"--samples {args.samples} is more than --max-points "
                f"{args.max_points}; raise --max-points to run it anyway"
            )
        return random_points(bounds, args.samples, args.seed)


def execute(args) -> int:
    from ..analysis.parallel import NotSendableError, SchedulerUnreachableError
    from ..analysis.sweep import CHECKPOINT, read_checkpoint, sweep
    from ..io.run_directory import add_to_manifest, atomic_write

    if bool(args.grid) == bool(args.random):
        raise UsageError("give either --grid axes or --random parameters")
    points = _points(args)
    check_expected_time(
        args,
        {args.model: len(points) * args.duration},
        runs=len(points),
        per_run_s=ORBIT_SECONDS_PER_POINT if args.orbit else 0.0,
        workers=1 if args.scheduler else (args.workers or os.cpu_count() or 1),
        what=f"the sweep of {len(points)} points",
    )
    robot, cparams = load_parameters(args.robot)
    law, cparams = controller_choice(args.controller, cparams)
    controller = make_controller(law, cparams, robot, on_workers=True)
    if args.orbit:
        _check_orbit_controller(args, law, cparams, robot)
    out = out_dir(args.out)
    progress = show_progress(args)
    wall0 = time.perf_counter()
    try:
        # (a ValueError here is the sweep refusing its settings: a usage error, exit 2)
        with (
            usage_errors(SchedulerUnreachableError, NotSendableError, ValueError),
            warnings.catch_warnings(),
        ):
            # the points the sweep could not run are reported below, by point
            warnings.simplefilter("ignore", RuntimeWarning)
            res = sweep(
                points,
                model=args.model,
                duration=args.duration,
                robot=robot,
                controller=controller,
                friction_coefficient=args.friction,
                out=out,
                workers=args.workers,
                scheduler=args.scheduler,
                progress=progress,
                resume=not args.no_resume,
                orbit=args.orbit,
                on_error="record",
                command=" ".join(["scoutsim"] + sys.argv[1:]),
            )
    except KeyboardInterrupt:
        n_done = len(read_checkpoint(out / CHECKPOINT))
        print(
            f"scoutsim sweep: interrupted; {n_done} of {len(points)} points are done and "
            f"kept in {out}/{CHECKPOINT} (no table written): run the same command again "
            "to finish the rest",
            file=sys.stderr,
        )
        return 130
    wall = time.perf_counter() - wall0
    outcomes: dict[str, int] = {}
    for r in res.rows:
        outcomes[r["outcome"]] = outcomes.get(r["outcome"], 0) + 1
    steady = sum(bool(r.get("steady_bounding")) for r in res.rows)
    print(
        f"scoutsim sweep: {len(points)} points of model {args.model}, {args.duration:g} s "
        f"each ({res.settings['n_resumed']} resumed from {out}/points.jsonl)"
    )
    print("  outcomes: " + ", ".join(f"{k} {v}" for k, v in sorted(outcomes.items())))
    print(f"  steady bounding: {steady}")
    print(f"  wall time {wall:.1f} s; wrote sweep.parquet, sweep.csv to {out}/")
    if args.grid and len(res.parameters) == 2 and args.plots:
        atomic_write(
            out / "map.png",
            lambda p: res.plot_map(
                res.parameters[0], res.parameters[1], "average_speed_m_s", path=p
            ),
        )
        add_to_manifest(out, ["map.png"])
        print(f"  map of the average speed: {out}/map.png")
        if args.orbit:
            atomic_write(
                out / "stability.png",
                lambda p: res.plot_map(
                    res.parameters[0],
                    res.parameters[1],
                    "orbit_spectral_radius_per_stride",
                    path=p,
                ),
            )
            add_to_manifest(out, ["stability.png"])
            print(
                "  map of the orbit's spectral radius per stride (< 1: stable): "
                f"{out}/stability.png"
            )
    if args.orbit:
        stable = sum(bool(r.get("orbit_stable")) for r in res.rows)
        print(f"  periodic orbits found and stable: {stable} of {steady} bounding points")
    errors = res.errors()
    for r in errors[:3]:
        print(
            f"scoutsim sweep: point { ({k: r[k] for k in res.parameters}) } could not run (an "
            f"error of the sweep, not of the robot): {r['error']}",
            file=sys.stderr,
        )
    if errors:
        print(
            f"scoutsim sweep: {len(errors)} of {len(points)} points could not run (status "
            f"'error' in the table); the same command again runs them afresh",
            file=sys.stderr,
        )
    return 1 if errors else 0


def _check_orbit_controller(args, law, cparams, robot) -> None:
    """UsageError before any point runs if ``--orbit`` cannot restart the controller's
    strides from section states (a Python controller without get_state / set_state):
    every point would report it instead of an orbit."""
    from ..control.dispatch import ControllerStateError, check_state_access, plan_controller

    try:
        check_state_access(plan_controller(make_controller(law, cparams, robot), args.model, robot))
    except ControllerStateError as exc:
        raise UsageError(
            f"--orbit with --controller {args.controller}: {exc}; the orbit search restarts "
            "strides from section states, which include the controller's own state"
        ) from exc
