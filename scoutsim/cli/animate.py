"""``scoutsim animate``: a stick-figure animation (GIF or MP4) of a run saved by ``scoutsim
run`` (its output directory or a result.npz): torso, legs coloured by the controller's leg
state, toes marked by the simulated contact (on the ground, sliding, in the air), ground
forces, time stamp, and the title saying what the run did.

    scoutsim animate RUN_DIR|RESULT.npz --out FILE.gif|.mp4 [--fps N] [--t0 S] [--t1 S]
                     [--dpi N]
"""

from __future__ import annotations

from pathlib import Path

from ._common import (
    UsageError,
    add_time_window_options,
    check_time_window,
    input_file,
    load_result,
    positive_float,
    positive_int,
    usage_errors,
)

NAME = "animate"


def register(sub, common) -> None:
    anim = sub.add_parser(
        NAME,
        help="stick-figure animation of a saved run (GIF or MP4)",
        description="Animate a run saved by `scoutsim run` (its output directory, "
        "timeseries table or result.npz): torso box, legs "
        "coloured by the controller's leg state, toes marked by the simulated "
        "contact (filled: on the ground, diamond: sliding, open: in the air), "
        "ground-force arrows, ground line, time stamp. Frames at t0 + k/fps, k = 0 .. floor((t1 - t0) fps). GIF "
        "via Pillow; MP4 needs ffmpeg on the PATH.",
    )
    anim.add_argument(
        "input",
        metavar="RUN",
        help="saved run (the directory of scoutsim "
        "run --out, its timeseries table, or a result.npz)",
    )
    anim.add_argument("--out", metavar="FILE", required=True, help="output .gif or .mp4")
    anim.add_argument(
        "--fps",
        type=positive_float,
        default=25.0,
        metavar="N",
        help="frames per simulated second, played back in real time (default: 25)",
    )
    add_time_window_options(
        anim,
        "start of the animated window [s] (default: start of the run)",
        "end of the animated window [s] (default: end of the run)",
    )
    anim.add_argument(
        "--dpi",
        type=positive_int,
        default=80,
        metavar="N",
        help="resolution; frames are 8 x 4 inches (default: 80 -> 640 x 320)",
    )
    anim.set_defaults(func=execute)


def execute(args) -> int:
    from ..presentation.animation import ANIMATION_SUFFIXES, save_animation

    p = input_file(args.input, directory_ok=True)
    check_time_window(args)
    out = Path(args.out)
    if out.suffix.lower() not in ANIMATION_SUFFIXES:
        raise UsageError(f"--out '{out}' is not allowed: the suffix must be .gif or .mp4")
    result = load_result(p)
    with usage_errors(ValueError, RuntimeError):
        save_animation(result, out, fps=args.fps, t0=args.t0, t1=args.t1, dpi=args.dpi)
    print(f"wrote {out}")
    return 0
