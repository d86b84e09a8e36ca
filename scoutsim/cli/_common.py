"""What the ``scoutsim`` sub-commands share: the usage error, argument types, the options
that several sub-commands define alike, and the helpers that load their inputs and write
their outputs.

Every user-facing problem is raised as :class:`UsageError`; ``scoutsim.cli.main`` prints it
as ``scoutsim COMMAND: error: MESSAGE`` and exits with code 2.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from contextlib import contextmanager
from pathlib import Path

from ..io.run_directory import json_safe
from ..parameters import DEFAULT_FRICTION_COEFFICIENT

_IMPORTED_AT = time.perf_counter()

#: the models that run the bounding controller
CONTROLLED_MODELS = ("ideal", "I", "II")
#: every model ``scoutsim run`` accepts
MODELS = CONTROLLED_MODELS + ("passive",)

#: Toe friction of the CLI's jobs: the package's one default floor
SCOUT_FLOOR_FRICTION = DEFAULT_FRICTION_COEFFICIENT

#: options whose value is a comma-separated list that may start with a minus sign
_LIST_OPTIONS = (
    "--speeds",
    "--pitch-rates",
    "--heights",
    "--model",
    "--models",
    "--floors",
    "--pitch-rate",
)


class UsageError(Exception):
    """A problem with the user's input: message on stderr, exit code 2."""


@contextmanager
def usage_errors(*types: type[BaseException]):
    """Turn the given exceptions (default: ``ValueError``) raised inside the block into a
    :class:`UsageError` with the same message."""
    caught = types or (ValueError,)
    try:
        yield
    except caught as exc:
        raise UsageError(str(exc)) from None


# -----------------------------------------------------------------------------------------
# argument types
# -----------------------------------------------------------------------------------------
def _number(text: str, ok, allowed: str) -> float:
    """``text`` as a float for argparse, which must satisfy ``ok`` (``allowed`` says how)."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not ok(v):
        raise argparse.ArgumentTypeError(f"{text!r} is not allowed: must be {allowed}")
    return v


def positive_float(text: str) -> float:
    return _number(text, lambda v: math.isfinite(v) and v > 0, "a finite number > 0")


def finite_float(text: str) -> float:
    return _number(text, math.isfinite, "finite")


def friction(text: str) -> float:
    return _number(text, lambda v: v >= 0, ">= 0 ('inf' = no slip)")


def friction_list(text: str) -> list:
    vals = [friction(x.strip()) for x in text.split(",") if x.strip()]
    if not vals:
        raise argparse.ArgumentTypeError(f"{text!r} is not allowed: give at least one value")
    if len(set(vals)) != len(vals):
        raise argparse.ArgumentTypeError(f"{text!r} is not allowed: a floor is repeated")
    return vals


def positive_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"{text!r} is not allowed: must be >= 1")
    return v


def float_list(positive: bool = False):
    def parse(text: str) -> list[float]:
        items = [s.strip() for s in text.split(",")]
        if not items or any(s == "" for s in items):
            raise argparse.ArgumentTypeError(f"{text!r} is not a comma-separated list of numbers")
        return [(positive_float if positive else finite_float)(s) for s in items]

    return parse


def model_list(text: str) -> list[str]:
    items = [s.strip() for s in text.split(",") if s.strip()]
    if not items:
        raise argparse.ArgumentTypeError("give at least one model")
    bad = [m for m in items if m not in MODELS]
    if bad:
        raise argparse.ArgumentTypeError(f"unknown model(s) {bad}; choose from {', '.join(MODELS)}")
    return list(dict.fromkeys(items))


def join_list_values(argv: list[str]) -> list[str]:
    """Let ``--pitch-rates -100,-50`` work: argparse would take "-100,-50" for an option."""
    out, i = [], 0
    while i < len(argv):
        tok = argv[i]
        if (
            tok in _LIST_OPTIONS
            and i + 1 < len(argv)
            and len(argv[i + 1]) > 1
            and argv[i + 1][0] == "-"
            and (argv[i + 1][1].isdigit() or argv[i + 1][1] == ".")
        ):
            out.append(f"{tok}={argv[i + 1]}")
            i += 2
            continue
        out.append(tok)
        i += 1
    return out


# -----------------------------------------------------------------------------------------
# options defined alike by several sub-commands
# -----------------------------------------------------------------------------------------
def add_out_option(parser, default: str = "scoutsim_out", *, note: str = ", created if needed"):
    parser.add_argument(
        "--out", default=default, metavar="DIR", help=f"output directory{note} (default: {default})"
    )


def add_friction_option(parser, help: str):
    parser.add_argument(
        "--friction", type=friction, default=SCOUT_FLOOR_FRICTION, metavar="MU", help=help
    )


def add_no_progress_option(parser):
    parser.add_argument(
        "--no-progress",
        action="store_true",
        help="no progress bar (it is also off when stderr is not a terminal)",
    )
    parser.add_argument(
        "--quiet",
        action="store_true",
        help="nothing on stderr but errors and warnings: no progress bar, no notice of "
        "the first run's compilation",
    )


#: --controller choices: the paper's Table I law, and Table I with torso feedback at
#: touchdown (scoutsim.control.PitchFeedbackController)
CONTROLLERS = ("table-i", "pitch-feedback")
#: how outputs name them
CONTROLLER_LABELS = {"table-i": "Table I", "pitch-feedback": "pitch feedback"}


def add_controller_option(parser):
    """--controller: which controller runs: a built-in law with the robot file's
    [controller] section, a controller file (as ``scoutsim tune`` writes its best
    parameters), a learned policy's file (``.npz``) or a ``MODULE:FACTORY`` controller."""
    parser.add_argument(
        "--controller",
        default="table-i",
        metavar="{" + ",".join(CONTROLLERS) + ",FILE,FILE.npz,MODULE:FACTORY}",
        help="table-i: the paper's Table I controller (no torso feedback); "
        "pitch-feedback: Table I with the touchdown angles corrected "
        "by torso pitch and pitch rate (PitchFeedbackController, gains "
        "pitch_gain_* / pitch_rate_gain_* of the robot file's "
        "[controller]); FILE: a controller file, its law and every "
        "controller parameter (as scoutsim tune writes best.toml; it "
        "replaces the robot file's [controller]); FILE.npz: a learned policy's "
        "file (PolicyController; its Table I parameters replace the robot file's "
        "[controller]); MODULE:FACTORY: your "
        "own controller, FACTORY(robot, params) in the importable "
        "module MODULE (on PYTHONPATH) returning any controller "
        "scoutsim.simulate accepts (default: table-i)",
    )


def controller_choice(value: str, params):
    """``(law, ControllerParameters)`` of ``--controller value``: a law's name with the
    robot file's ``params``, a controller file's law and parameters, a policy file
    (``.npz``: its path is the law) with the Table I parameters it runs on, or a
    ``MODULE:FACTORY`` string (the law) with ``params``. UsageError naming the file and the
    problem otherwise."""
    from ..control.factory import is_factory_spec

    if value in CONTROLLERS:
        return value, params
    p = Path(value)
    if value.lower().endswith(".npz"):  # a learned policy's file
        from ..control.policy import PolicyController, PolicyError

        with usage_errors(PolicyError):
            return value, PolicyController.load(value).controller_parameters
    if p.is_file():
        from ..analysis.controller_file import read_controller_file

        with usage_errors():
            cf = read_controller_file(p)
        return cf.law, cf.controller
    if p.exists():
        raise UsageError(f"--controller {value!r}: not a file")
    if is_factory_spec(value):
        return value.strip(), params
    raise UsageError(
        f"--controller {value!r} is not allowed: not one of "
        f"{', '.join(CONTROLLERS)}, no controller file of that name, and not "
        "of the form MODULE:FACTORY"
    )


def controller_label(law: str) -> str:
    """How outputs name the law of :func:`controller_choice` (a user's: its string)."""
    return CONTROLLER_LABELS.get(law, law)


def make_controller(name: str, params, robot=None, *, on_workers: bool = False):
    """The controller the law ``name`` (of :func:`controller_choice`) runs with the
    ControllerParameters ``params``: the parameters themselves (Table I), a
    PitchFeedbackController, or a user's ``MODULE:FACTORY`` controller made for ``robot``
    (``on_workers``: a :class:`~scoutsim.control.factory.ControllerSpec` that each worker
    of a study makes itself, after the factory was tried here once), or a policy file's."""
    if name == "pitch-feedback":
        from ..control.pitch_feedback import PitchFeedbackController

        return PitchFeedbackController(params)
    if name in CONTROLLERS:
        return params
    if name.lower().endswith(".npz"):  # (read by controller_choice: a good file)
        from ..control.policy import PolicyController

        return PolicyController.load(name)
    from ..control.factory import ControllerSpec, FactoryError, controller_from_spec

    try:
        controller = controller_from_spec(name, robot, params)  # fails here, not on workers
        return ControllerSpec(name, robot, params) if on_workers else controller
    except FactoryError as exc:
        raise UsageError(str(exc)) from None


def add_models_option(parser):
    """--model LIST (alias --models): a comma-separated list of models, by default the
    controlled ones (every command that takes a model calls the option --model; the
    commands that run one model take one)."""
    parser.add_argument(
        "--model",
        "--models",
        dest="model",
        type=model_list,
        default=list(CONTROLLED_MODELS),
        metavar="LIST",
        help="comma-separated models (default: " + ",".join(CONTROLLED_MODELS) + ")",
    )


def add_plots_option(parser, default: bool, what: str):
    """--plots / --no-plots, the same pair in every command that draws figures; ``what``
    says which figures, ``default`` whether the command draws them unasked."""
    parser.add_argument(
        "--plots",
        action=argparse.BooleanOptionalAction,
        default=default,
        help=f"{'' if default else 'also '}draw {what} (default: "
        f"{'--plots' if default else '--no-plots'})",
    )


def add_time_window_options(parser, t0_help: str, t1_help: str):
    parser.add_argument("--t0", type=finite_float, default=None, metavar="S", help=t0_help)
    parser.add_argument("--t1", type=finite_float, default=None, metavar="S", help=t1_help)


def add_parallel_options(parser, resume_help: str | None = None) -> None:
    """A study's --workers N (local processes) and --scheduler ADDRESS (a Dask cluster),
    as :func:`scoutsim.analysis.parallel.map_tasks` takes them; and --no-resume, with
    ``resume_help``, for a study that keeps a checkpoint."""
    parser.add_argument(
        "--workers",
        type=positive_int,
        default=None,
        metavar="N",
        help="local processes (default: all cores; 1 runs in this process)",
    )
    parser.add_argument(
        "--scheduler",
        default=None,
        metavar="ADDRESS",
        help="Dask distributed scheduler address (e.g. tcp://host:8786)",
    )
    if resume_help is not None:
        parser.add_argument("--no-resume", action="store_true", help=resume_help)


def add_duration_option(parser, default: float, what: str = "simulated time per run"):
    """--duration S with the command's own ``default`` [s] (each command has its own, from
    the function it calls: argparse would share one default between the commands whose
    parsers have the option from a common parent)."""
    parser.add_argument(
        "--duration",
        type=positive_float,
        default=float(default),
        metavar="S",
        help=f"{what} [s] (default: {default:g})",
    )


def simulation_options() -> argparse.ArgumentParser:
    """The parent parser of the sub-commands that simulate runs (run, basin, sweep, tune);
    each adds its own --duration (:func:`add_duration_option`)."""
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument(
        "--robot",
        metavar="FILE",
        help="TOML robot/controller file with the layout of "
        "scoutsim/data/scout2.toml; unset entries keep the Scout II "
        "defaults",
    )
    add_out_option(common)
    common.add_argument(
        "--rtol",
        type=positive_float,
        default=None,
        metavar="X",
        help="integrator relative tolerance (default: 1e-5 for Model II "
        "(ARK3), 1e-8 otherwise (DOPRI5))",
    )
    common.add_argument(
        "--atol",
        type=positive_float,
        default=None,
        metavar="X",
        help="integrator absolute tolerance (default: 1e-6 for Model II "
        "(ARK3), 1e-9 otherwise (DOPRI5))",
    )
    add_friction_option(
        common,
        "Coulomb friction coefficient of the toes (default: "
        f"{SCOUT_FLOOR_FRICTION}, rubber toes on carpet, where the "
        "paper's experiments ran; 'inf' = no slip; see docs/model.md)",
    )
    add_no_progress_option(common)
    common.add_argument(
        "--max-hours",
        type=positive_float,
        default=DEFAULT_MAX_HOURS,
        metavar="H",
        help="refuse a job expected to take longer than H hours of wall time "
        f"before starting (default: {DEFAULT_MAX_HOURS:g}; an estimate "
        "from the simulator's speed on a slow machine)",
    )
    return common


#: the longest job (wall time [h]) the commands start without --max-hours
DEFAULT_MAX_HOURS = 24.0


def check_expected_time(
    args,
    simulated_s: dict,
    *,
    workers: int = 1,
    per_run_s: float = 0.0,
    runs: int = 1,
    what: str = "the run",
) -> None:
    """UsageError if a job of ``simulated_s`` ({model: simulated seconds}; plus
    ``per_run_s`` for each of ``runs`` runs), spread over ``workers`` processes, is expected
    to take longer than ``args.max_hours``."""
    from ..simulation.budgets import expected_wall_time

    wall = sum(expected_wall_time(sim_s, model) for model, sim_s in simulated_s.items())
    hours = (wall + per_run_s * runs) / max(1, workers) / 3600.0
    if hours > args.max_hours:
        raise UsageError(
            f"{what} would take about {hours:.3g} h of wall time (estimated from "
            f"the simulator's speed on a slow machine), more than --max-hours "
            f"{args.max_hours:g}; raise --max-hours to run it anyway"
        )


# -----------------------------------------------------------------------------------------
# checks and inputs
# -----------------------------------------------------------------------------------------
def add_repair_spikes_option(parser) -> None:
    parser.add_argument(
        "--repair-spikes",
        action="store_true",
        help="replace each isolated spike of a log (one to three samples far "
        "from their neighbours, which the log check refuses) by the "
        "median of its neighbours, and report each on stderr",
    )


def report_repairs(logs, command: str) -> None:
    """Say on stderr which spikes were replaced when the logs were loaded."""
    for log in logs:
        for column, row, value, median in log.repairs:
            print(
                f"scoutsim {command}: {log.path}: column '{column}', row {row}: spike "
                f"{value:.6g} replaced by its neighbours' median {median:.6g}",
                file=sys.stderr,
            )


def check_logs_or_example(args, missing: str):
    """Exactly one of LOG arguments and --example; ``missing`` is the message for neither."""
    if args.example and args.logs:
        raise UsageError("give log files or --example, not both")
    if not args.example and not args.logs:
        raise UsageError(missing)


def check_time_window(args):
    if args.t0 is not None and args.t1 is not None and not args.t1 > args.t0:
        raise UsageError(f"--t0 {args.t0:g} --t1 {args.t1:g} is not allowed: need t1 > t0")


def command_wall_time() -> float:
    """Wall time [s] since this process started (Linux: from /proc, so the interpreter's
    start-up and every import count; elsewhere: since :mod:`scoutsim.cli` was imported)."""
    try:
        with open("/proc/self/stat") as f:
            start_ticks = int(f.read().rsplit(")", 1)[1].split()[19])
        with open("/proc/uptime") as f:
            uptime = float(f.read().split()[0])
        return max(uptime - start_ticks / os.sysconf("SC_CLK_TCK"), 0.0)
    except (OSError, ValueError, IndexError, AttributeError):
        return time.perf_counter() - _IMPORTED_AT


def progress_messages(args, command: str):
    """A callable(str) that prints a progress message on stderr (``scoutsim COMMAND
    [elapsed s]: message``) when :func:`show_progress` allows, else None."""
    if not show_progress(args):
        return None
    t0 = time.perf_counter()

    def say(message: str) -> None:
        print(
            f"scoutsim {command} [{time.perf_counter() - t0:6.1f} s]: {message}",
            file=sys.stderr,
            flush=True,
        )

    return say


def show_progress(args) -> bool:
    """Progress bar unless --no-progress, --quiet or stderr is not a terminal."""
    return not (args.no_progress or getattr(args, "quiet", False)) and sys.stderr.isatty()


def load_parameters(path):
    """(robot, controller) from the user's TOML file (or the defaults); UsageError if bad."""
    from ..parameters import load_parameters

    if path is not None:
        p = Path(path)
        if not p.exists():
            raise UsageError(f"robot file '{path}' not found")
        if not p.is_file():
            raise UsageError(f"robot file '{path}' is not a file")
    try:
        return load_parameters(path)
    except OSError as exc:
        raise UsageError(f"cannot read robot file '{path}': {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise UsageError(f"robot file '{path}' is not UTF-8 text: {exc}") from None
    except ValueError as exc:  # ParameterError (names the field) and other bad values
        raise UsageError(str(exc)) from None


def load_sensors(path, robot):
    """The sensors of the user's TOML file's ``[sensors]`` (ideal without one); UsageError
    if bad."""
    from ..control.sensors import load_sensors as load

    try:
        return load(path, robot)
    except ValueError as exc:  # ParameterError names the field
        raise UsageError(str(exc)) from None


def load_robot(path):
    """The robot of the user's TOML file, or None (the callee's default) without one."""
    if not path:
        return None
    robot, _ = load_parameters(path)
    return robot


def integrator(args):
    """IntegratorSettings from --rtol / --atol (unset: the defaults)."""
    from ..simulation.integrator import IntegratorSettings

    kw = {}
    if args.rtol is not None:
        kw["rtol"] = args.rtol
    if args.atol is not None:
        kw["atol"] = args.atol
    with usage_errors():
        return IntegratorSettings(**kw)


def input_file(path: str, *, directory_ok: bool = False) -> Path:
    """``path`` as a Path; UsageError if it does not exist or is not a file (or, with
    ``directory_ok``, a directory)."""
    p = Path(path)
    if not p.exists():
        raise UsageError(f"input '{path}' not found")
    if not (p.is_file() or (directory_ok and p.is_dir())):
        raise UsageError(f"input '{path}' is not a file")
    return p


def is_saved_run(p: Path) -> bool:
    """True if ``p`` is a run saved by ``scoutsim run``: its output directory, its
    timeseries table or a result.npz (an experiment log is not)."""
    from ..io.tables import TableError, read_metadata
    from ..result.run_files import TABLES_FORMAT

    if p.is_dir() or p.name.lower().endswith(".npz"):
        return True
    try:
        return read_metadata(p)["metadata"].get("format") == TABLES_FORMAT
    except (TableError, ImportError, OSError, ValueError, KeyError):
        return False


def load_result(p: Path, t_range: tuple[float, float] | None = None):
    """A run saved by ``scoutsim run``: its output directory (or timeseries table) or a
    result.npz (``t_range``: only that window [s], SimulationResult.load)."""
    from ..io.tables import TableError
    from ..result.simulation_result import SimulationResult

    if not is_saved_run(p):
        raise UsageError(
            f"input '{p}' is not a saved run: expected the output directory of "
            "`scoutsim run`, its timeseries table or a result.npz"
        )
    try:
        return SimulationResult.load(p, t_range=t_range)
    except (OSError, ValueError, KeyError, TableError) as exc:
        raise UsageError(f"cannot read result '{p}': {exc}") from None


# -----------------------------------------------------------------------------------------
# outputs
# -----------------------------------------------------------------------------------------
def out_dir(path) -> Path:
    """The output directory, created if needed."""
    out = Path(path)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UsageError(f"cannot create output directory '{out}': {exc.strerror or exc}") from None
    return out


def dumps(obj) -> str:
    """Strict, indented JSON (non-finite floats as null)."""
    return json.dumps(json_safe(obj), indent=2, allow_nan=False)


def write_json(path: Path, obj) -> Path:
    """Write :func:`dumps` of ``obj`` and a newline to ``path``."""
    path.write_text(dumps(obj) + "\n")
    return path
