"""``scoutsim plot``: a figure of one saved run (the output directory of ``scoutsim run``, its
timeseries table or a result.npz: pitch, height, leg angles with leg states, hip torques;
an overview and the last strides for runs over 4 s) or of one experiment log (measured
pitch and height, leg angles, leg states, torques from current).

    scoutsim plot RUN_DIR|RESULT.npz|LOG [--out FILE] [--t0 S] [--t1 S]
"""

from __future__ import annotations

from pathlib import Path

from ._common import (UsageError, add_time_window_options, check_time_window, input_file,
                      is_saved_run, load_result, usage_errors)

NAME = "plot"


def register(sub, common) -> None:
    plot = sub.add_parser(
        NAME, help="figure of one saved run or one experiment log",
        description="Plot one run: the output directory of `scoutsim run` (or its "
                    "timeseries table, or a result.npz): pitch, height, leg angles with leg "
                    "states, hip torques (runs over 4 s: an overview and the last strides); "
                    "or an experiment log (.csv, .csv.gz, .parquet: measured pitch and "
                    "height, leg angles, leg states, torques from current).")
    plot.add_argument("input", metavar="RUN|LOG",
                      help="saved run (directory, timeseries table, result.npz) or "
                           "experiment log")
    plot.add_argument("--out", metavar="FILE", default=None,
                      help="output figure, .png, .pdf or .svg (default: INPUT's name with "
                           ".png, in the current directory)")
    add_time_window_options(plot, "start of the time window [s]", "end of the time window [s]")
    plot.set_defaults(func=execute)


def execute(args) -> int:
    from ..validation.logs import LOG_SUFFIXES, LogError, load_log
    p = input_file(args.input, directory_ok=True)
    check_time_window(args)
    name = p.name.lower()
    is_run = is_saved_run(p)
    is_log = not is_run and any(name.endswith(s) for s in LOG_SUFFIXES)
    if not is_log and not is_run:
        raise UsageError(f"input '{p}' is neither a saved run (the output directory of "
                         "`scoutsim run`, its timeseries table, a .npz) nor an experiment log "
                         f"({', '.join(LOG_SUFFIXES)})")
    if args.out is None:
        stem = p.name
        for s in (".npz",) + LOG_SUFFIXES:
            if stem.lower().endswith(s):
                stem = stem[:-len(s)]
                break
        out = Path(f"{stem}.png")
    else:
        out = Path(args.out)
    if out.suffix.lower() not in (".png", ".pdf", ".svg"):
        raise UsageError(f"--out '{out}' is not allowed: the suffix must be .png, .pdf or "
                         ".svg")
    if is_log:
        with usage_errors(LogError):
            obj = load_log(p)
    else:
        obj = load_result(p)
    t = obj.t
    t0 = float(t[0]) if args.t0 is None else args.t0
    t1 = float(t[-1]) if args.t1 is None else args.t1
    t_range = None if (args.t0 is None and args.t1 is None) else (t0, t1)
    if t_range is not None and len(t) and not (t0 < float(t[-1]) and t1 > float(t[0])):
        raise UsageError(f"--t0 {t0:g} --t1 {t1:g} is not allowed: the window must overlap "
                         f"the {'log' if is_log else 'run'} ({float(t[0]):g} .. "
                         f"{float(t[-1]):g} s)")
    with usage_errors():
        if is_log:
            from ..presentation.paper_figures import plot_log
            plot_log(obj, out, t_range=t_range)
        else:
            from ..presentation.plots import plot_run
            plot_run(obj, out, t_range=t_range, overview="auto")
    print(f"wrote {out}")
    return 0
