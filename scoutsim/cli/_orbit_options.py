"""The options the commands that find periodic orbits share (``orbit`` and ``continue``):
the passive model's apex state and the controlled orbit's model, floor and settling time."""

from __future__ import annotations

from ._common import CONTROLLED_MODELS, SCOUT_FLOOR_FRICTION, add_friction_option, positive_float


def add_passive_apex_options(parser):
    """--speed and --apex-height: the passive model's level-torso apex state."""
    parser.add_argument(
        "--speed",
        type=positive_float,
        default=1.3,
        metavar="V",
        help="--passive: forward speed at the apex [m/s] (default: 1.3)",
    )
    parser.add_argument(
        "--apex-height",
        type=positive_float,
        default=0.35,
        metavar="H",
        help="--passive: torso COM height at the apex [m] (default: 0.35)",
    )


def add_controlled_orbit_options(parser, duration_help: str):
    """--model, --friction and --duration of the commands that find controlled orbits."""
    parser.add_argument(
        "--model", choices=CONTROLLED_MODELS, default="II", help="controlled model (default: II)"
    )
    add_friction_option(parser, f"controlled: toe friction (default: {SCOUT_FLOOR_FRICTION})")
    parser.add_argument(
        "--duration",
        type=positive_float,
        default=12.0,
        metavar="S",
        help=f"controlled: {duration_help} [s] (default: 12)",
    )


#: the options only the passive model's orbits take (argparse destinations)
PASSIVE_ONLY = ("speed", "apex_height", "pitch_rate")
#: the options only the controlled robot's orbits take
CONTROLLED_ONLY = ("model", "friction", "duration", "strides", "section", "points")
#: ... and those of a controlled orbit's sensitivities shared out to processes
PARALLEL = ("workers", "scheduler")
