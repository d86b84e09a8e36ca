"""``scoutsim identify``: fit Model II hip-unit parameters (nonlinear least squares with a
multi-start global search) to free-swing or flight-step bench-rig logs, print the report
and write identified.json and the fit figures (docs/identification.md). --example fits
virtual logs made with known parameters and compares true and fitted values.

    scoutsim identify (LOG... | --example) [--rig {free-swing,flight-steps}] [--params LIST]
                      [--robot FILE] [--out DIR] [--starts N] [--local N] [--seed SEED]
                      [--confidence C] [--no-plots] [--json]
"""

from __future__ import annotations

import time

from ._common import (
    UsageError,
    add_no_progress_option,
    add_out_option,
    add_plots_option,
    check_logs_or_example,
    load_robot,
    out_dir,
    positive_int,
    progress_messages,
    usage_errors,
)

NAME = "identify"


def register(sub, common) -> None:
    from ..identification.rigs import DEFAULT_PARAMS, HIP_PARAMETERS

    idf = sub.add_parser(
        NAME,
        help="fit Model II hip-unit parameters to bench-rig logs",
        description="Fit hip-unit parameters (nonlinear least squares with a multi-start "
        "global search) to free-swing or flight-step rig logs; write DIR/"
        "identified.json (value, unit, interval, identifiable flag per parameter) "
        "and fit figures DIR/fit_<n>.png. --example makes virtual logs with known "
        "parameters and sensor noise, fits them and prints true against fitted "
        "values. See docs/identification.md.",
    )
    idf.add_argument("logs", nargs="*", metavar="LOG", help="rig log files (CSV/Parquet)")
    idf.add_argument(
        "--example",
        action="store_true",
        help="generate virtual logs with known parameters, fit, compare",
    )
    idf.add_argument(
        "--rig",
        choices=("free-swing", "flight-steps"),
        default=None,
        help="the rig that made the logs (default: the logs' metadata 'rig'; "
        "with --example: both rigs, fitted together)",
    )
    idf.add_argument(
        "--params",
        default=None,
        metavar="LIST",
        help="comma-separated parameters to fit, from: "
        + ", ".join(HIP_PARAMETERS)
        + " (default: "
        + ", ".join(DEFAULT_PARAMS["free-swing"])
        + ")",
    )
    idf.add_argument(
        "--robot",
        metavar="FILE",
        help="TOML robot file: the starting values and the fixed parameters",
    )
    add_out_option(idf, "scoutsim_identify", note="")
    idf.add_argument(
        "--starts",
        type=positive_int,
        default=16,
        metavar="N",
        help="Sobol start points of the global search (default: 16)",
    )
    idf.add_argument(
        "--local",
        type=positive_int,
        default=2,
        metavar="N",
        help="best starts refined by least squares (default: 2)",
    )
    idf.add_argument("--seed", type=int, default=0, help="Sobol / noise seed (default: 0)")
    idf.add_argument(
        "--confidence",
        type=float,
        default=0.95,
        metavar="C",
        help="interval confidence level (default: 0.95)",
    )
    idf.add_argument(
        "--jacobian",
        choices=("fd", "exact"),
        default="exact",
        help="the local fits' Jacobian: exact, the replays' derivatives carried with them "
        "(differences where a replay is not differentiable); fd, forward differences of "
        "the residuals, the check (the same optimum: docs/identification.md) (default: exact)",
    )
    add_plots_option(idf, True, "the fit figures")
    idf.add_argument("--json", action="store_true", help="print identified.json to stdout")
    add_no_progress_option(idf)
    idf.set_defaults(func=execute)


def execute(args) -> int:
    from ..identification.example import EXAMPLE_FACTORS, example_logs
    from ..identification.fit import identify

    check_logs_or_example(args, "give at least one rig log (or --example)")
    if not 0.0 < args.confidence < 1.0:
        raise UsageError(f"--confidence {args.confidence:g} is not allowed: must be in (0, 1)")
    params = None
    if args.params:
        params = [p.strip() for p in args.params.split(",") if p.strip()]
    robot = load_robot(args.robot)
    out = out_dir(args.out)
    wall0 = time.perf_counter()
    with usage_errors():  # also the logs' LogError
        if args.example:
            rigs = (args.rig,) if args.rig else ("free-swing", "flight-steps")
            print(
                "scoutsim identify --example: virtual logs of the "
                + " and ".join(rigs)
                + " rig(s), made with a hip unit = Table II x "
                + ", ".join(f"{k} {v:g}" for k, v in EXAMPLE_FACTORS.items())
                + "; the fit starts from Table II"
            )
            logs = example_logs(rigs, seed=args.seed, out_dir=out)
            rig = None
        else:
            logs = args.logs
            rig = args.rig
        res = identify(
            logs,
            params,
            rig=rig,
            robot=robot,
            n_starts=args.starts,
            n_local=args.local,
            seed=args.seed,
            confidence=args.confidence,
            jacobian=args.jacobian,
            progress=progress_messages(args, NAME),
        )
    wall = time.perf_counter() - wall0
    path = res.save(out, figures=args.plots)
    if args.json:
        print(path.read_text())
    else:
        print(res.report())
        print(
            f"wall time {wall:.1f} s ({res.nfev} rig simulations"
            + (f", {res.jacobian_evaluations} exact Jacobians" if res.jacobian == "exact" else "")
            + f"); wrote {path}"
            + (" and fit figures" if args.plots else "")
            + f" to {out}/"
        )
    return 0
