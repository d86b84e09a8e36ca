"""Command-line interface: the ``scoutsim`` console script and its sub-commands, one module
each (``scoutsim COMMAND --help`` for the options):

    run       simulate one bounding run, print a summary, write its tables
    basin     basin map: which starts reach steady bounding, per model and floor
    assumptions  which modelling assumptions change a controller's bound
    compare   Fig. 12 errors of the models against experiment logs
    plot      figure of one saved run or one experiment log
    animate   stick-figure animation of a saved run (GIF or MP4)
    orbit     periodic bounding orbit and its Floquet multipliers (docs/orbits.md)
    continue  a family of periodic gaits along one parameter, its stability and bifurcations
    sweep     parameter sweep (grid or random sample) in parallel or on a Dask cluster
    uncertainty  global sensitivity of the gait to uncertain parameters (Sobol' indices)
    tune      optimise controller or robot parameters (CMA-ES) against an objective
    identify  fit Model II hip-unit parameters to bench-rig logs
    rig       run a virtual bench rig and write its log
    cache     where the compiled core is cached; --clean removes other versions

This module assembles the parser and dispatches; ``_common`` holds the argument types, the
options several sub-commands share and the input/output helpers.

Presentation layer: all computation is SI (angles in rad); degrees appear only in what is
printed and plotted, converted here with :func:`math.degrees` / :func:`math.radians`.

Exit codes: 0 success (also when the robot fell: the summary says so), 1 numerical failure
(``run``, a model in ``compare``), a crashed start (``basin``) or no periodic orbit found
(``orbit``, ``continue``), 2 bad usage, parameter file, initial state, input file or experiment log,
74 the outputs could not be written (``run``: a full disk, a directory where a file
goes; the run's data are saved to the temporary directory instead, the message says
where), 130 interrupted (Ctrl-C; the data computed so far is still written).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys

from . import (
    animate,
    assumptions,
    basin,
    cache,
    compare,
    continuation,
    identify,
    orbit,
    plot,
    rig,
    run,
    sweep,
    tune,
    uncertainty,
)
from ._common import MODELS, SCOUT_FLOOR_FRICTION, UsageError, join_list_values, simulation_options
from ._given import given_options
from .basin import format_basin
from .run import TIMESERIES_UNITS, column_unit, format_summary, write_timeseries_csv

__all__ = [
    "main",
    "build_parser",
    "TIMESERIES_UNITS",
    "column_unit",
    "write_timeseries_csv",
    "format_summary",
    "format_basin",
    "MODELS",
    "SCOUT_FLOOR_FRICTION",
]

#: the sub-command modules, in the order of ``scoutsim --help``
COMMANDS = (
    run,
    basin,
    assumptions,
    compare,
    plot,
    animate,
    orbit,
    continuation,
    sweep,
    uncertainty,
    tune,
    identify,
    rig,
    cache,
)
#: commands that simulate, so may have to compile the core first (a notice says so)
COMPILING_COMMANDS = {
    c.NAME
    for c in (
        run,
        basin,
        assumptions,
        compare,
        orbit,
        continuation,
        sweep,
        uncertainty,
        tune,
        identify,
        rig,
    )
}


def build_parser() -> argparse.ArgumentParser:
    """The ``scoutsim`` argument parser with all sub-commands (:data:`COMMANDS`)."""
    from .._version import __version__

    parser = argparse.ArgumentParser(
        prog="scoutsim",
        description="Simulate planar Scout II bounding (Poulakakis, Smith & Buehler, ICRA 2004).",
        epilog="examples:\n"
        "  scoutsim run                       # Model II, 10 s, tables in scoutsim_out/\n"
        "  scoutsim run --plots --steps       # also figures and every integrator step\n"
        "  scoutsim run --model I --duration 5 --robot my_robot.toml --out out_I\n"
        "  scoutsim run --json                # summary as JSON on stdout\n"
        "  scoutsim basin --model I,II --speeds 1.0,1.3 --pitch-rates -50,0 --workers 4\n"
        "  scoutsim tune --objective speed --target 1.3 --param "
        "controller.touchdown_angle_front_deg --out tuned\n"
        "  scoutsim run --controller tuned/best.toml\n"
        "  scoutsim assumptions --controller pitch-feedback --out assume\n"
        "  scoutsim uncertainty --param robot.leg_stiffness=3000:4000 "
        "--param controller.touchdown_angle_front_deg=19:23 --samples 64 --out unc\n"
        "  scoutsim compare run1.csv run2.csv --model I,II --out cmp\n"
        "  scoutsim compare --example             # on the shipped SYNTHETIC data set\n"
        "  scoutsim plot scoutsim_out --out run.pdf --t0 3 --t1 4\n"
        "  scoutsim animate scoutsim_out --out run.gif --t0 3 --t1 4",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"scoutsim {__version__}")
    sub = parser.add_subparsers(
        dest="command", metavar="{" + ",".join(c.NAME for c in COMMANDS) + "}"
    )
    common = simulation_options()
    for command in COMMANDS:
        command.register(sub, common)
    return parser


def main(argv=None) -> int:
    """Entry point of the ``scoutsim`` console script; returns the exit code."""
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser()
    try:
        args = parser.parse_args(join_list_values(argv))
        args.given = given_options(build_parser(), join_list_values(argv))
    except SystemExit as exc:  # --help, --version or a usage error (argparse printed it)
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
    if args.command is None:
        parser.print_help()
        return 0
    progress: contextlib.AbstractContextManager = contextlib.nullcontext()
    if args.command in COMPILING_COMMANDS and not getattr(args, "quiet", False):
        from .._numba.jit import FIRST_COMPILE_NOTICE, compile_progress, core_is_compiled

        if not core_is_compiled():
            print(
                f"scoutsim {args.command}: {FIRST_COMPILE_NOTICE} ...", file=sys.stderr, flush=True
            )
            progress = compile_progress(sys.stderr)
    try:
        with progress, _parameter_warnings_in_one_line(args.command):
            return args.func(args)
    except UsageError as exc:
        print(f"scoutsim {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"scoutsim {args.command}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # e.g. `scoutsim run --json | head`
        try:  # keep Python from complaining again when it flushes stdout at exit
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
        except (OSError, ValueError, AttributeError):
            pass
        return 1


@contextlib.contextmanager
def _parameter_warnings_in_one_line(command: str):
    """While a command runs, print a parameter warning (a value far from a robot of this kind: a likely unit slip,
    :class:`~scoutsim.parameters.ImplausibleParameterWarning`) as ``scoutsim COMMAND:
    warning: MESSAGE`` on stderr, as the command's errors are, instead of Python's form with
    the library's file and source line; other warnings are shown as Python shows them."""
    import warnings

    from ..parameters import ImplausibleParameterWarning

    python_shows = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, ImplausibleParameterWarning):
            print(f"scoutsim {command}: warning: {message}", file=file or sys.stderr)
        else:
            python_shows(message, category, filename, lineno, file, line)

    warnings.showwarning = show
    try:
        yield
    finally:
        warnings.showwarning = python_shows


#: commands that end their process at once when done (see :func:`console_main`)
FAST_EXIT_COMMANDS = {"run", "plot"}


def console_main() -> None:
    """The ``scoutsim`` console script and ``python -m scoutsim``: :func:`main`, then exit.

    After a command of :data:`FAST_EXIT_COMMANDS` (which start no worker processes and
    have closed every file they wrote) the process ends with ``os._exit`` once stdout and
    stderr are flushed: the interpreter's teardown of the loaded modules (Numba, LLVM,
    pyarrow) would add about 0.15-0.3 s to every such command and does nothing a user
    needs."""
    argv = sys.argv[1:]
    command = next((a for a in argv if not a.startswith("-")), None)
    try:
        code = main(argv)
    except KeyboardInterrupt:  # Ctrl-C while the command starts (imports, options)
        print(f"scoutsim {command or ''}: interrupted".replace("  ", " "), file=sys.stderr)
        code = 130
    if command in FAST_EXIT_COMMANDS:
        try:
            sys.stdout.flush()
            sys.stderr.flush()
        except (OSError, ValueError):
            pass
        os._exit(code if isinstance(code, int) else 1)
    sys.exit(code)
