"""``scoutsim plot``: a figure of one saved run (the output directory of ``scoutsim run``, its
timeseries table or a result.npz: pitch, height, leg angles with leg states, hip torques;
an overview and the last strides for runs over 4 s) or of one experiment log (measured
pitch and height, leg angles, leg states, torques from current).

    scoutsim plot RUN_DIR|RESULT.npz|LOG [--out FILE] [--t0 S] [--t1 S]
"""

from __future__ import annotations

from pathlib import Path

from ._common import (
    UsageError,
    add_repair_spikes_option,
    add_time_window_options,
    check_time_window,
    input_file,
    is_saved_run,
    load_result,
    report_repairs,
    usage_errors,
)

NAME = "plot"


def register(sub, common) -> None:
    plot = sub.add_parser(
        NAME,
        help="figure of one saved run or one experiment log",
        description="Plot one run: the output directory of `scoutsim run` (or its "
        "timeseries table, or a result.npz): pitch, height, leg angles with leg "
        "states, hip torques (runs over 4 s: an overview and the last strides); "
        "or an experiment log (.csv, .csv.gz, .parquet: measured pitch and "
        "height, leg angles, leg states, torques from current).",
    )
    plot.add_argument(
        "input",
        metavar="RUN|LOG",
        help="saved run (directory, timeseries table, result.npz) or experiment log",
    )
    plot.add_argument(
        "--out",
        metavar="FILE",
        default=None,
        help="output figure, .png, .pdf or .svg (default: INPUT's name with "
        ".png, in the current directory)",
    )
    add_time_window_options(
        plot,
        "start of the time window [s] (default: the start; a run streamed to "
        "disk: the start of its kept end, --keep of scoutsim run). Only the "
        "window of a saved run's tables is read",
        "end of the time window [s] (default: the end)",
    )
    add_repair_spikes_option(plot)
    plot.set_defaults(func=execute)


def _run_extent(p: Path):
    """(first sample time, last sample time [s], kept seconds if the run was streamed to disk
    else None, the run if it had to be loaded whole for this) of a saved run, from its
    metadata where it has some (the tables of a long streamed run are not read whole)."""
    from ..io.run_directory import IncompleteRunError
    from ..io.tables import TableError
    from ..result.simulation_result import SimulationResult

    if not p.name.lower().endswith(".npz"):
        try:
            meta = SimulationResult.load_metadata(p)
        except (IncompleteRunError, TableError, OSError, ValueError, KeyError) as exc:
            raise UsageError(f"cannot read result '{p}': {exc}") from None
        stream = (meta.get("provenance") or {}).get("stream")
        # (t_end: where the run got to; a run starts at t = 0)
        return (0.0, float(meta["t_end"]), None if stream is None else stream["keep_seconds"], None)
    r = load_result(p)
    return (float(r.t[0]), float(r.t[-1]), None, r) if len(r.t) else (0.0, 0.0, None, r)


def _saved_behaviour(p: Path):
    """What a saved run did, from the summary.json next to its tables (None without one, or
    for a streamed run, whose summary covers only its kept end: manifest.json says)."""
    import json

    d = p if p.is_dir() else p.parent
    try:
        summary = json.loads((d / "summary.json").read_text())
        manifest = json.loads((d / "manifest.json").read_text())
    except (OSError, ValueError):
        return None
    if (
        not (isinstance(summary, dict) and isinstance(manifest, dict))
        or manifest.get("streamed") is not False
    ):
        return None
    what = summary.get("behaviour")
    return what if isinstance(what, str) else None


def execute(args) -> int:
    from ..validation.log_format import LOG_SUFFIXES, LogError
    from ..validation.log_reading import load_log

    p = input_file(args.input, directory_ok=True)
    check_time_window(args)
    name = p.name.lower()
    is_run = is_saved_run(p)
    is_log = not is_run and any(name.endswith(s) for s in LOG_SUFFIXES)
    if not is_log and not is_run:
        raise UsageError(
            f"input '{p}' is neither a saved run (the output directory of "
            "`scoutsim run`, its timeseries table, a .npz) nor an experiment log "
            f"({', '.join(LOG_SUFFIXES)})"
        )
    if args.out is None:
        stem = p.name
        for s in (".npz",) + LOG_SUFFIXES:
            if stem.lower().endswith(s):
                stem = stem[: -len(s)]
                break
        out = Path(f"{stem}.png")
    else:
        out = Path(args.out)
    if out.suffix.lower() not in (".png", ".pdf", ".svg"):
        raise UsageError(f"--out '{out}' is not allowed: the suffix must be .png, .pdf or .svg")
    if is_log:
        with usage_errors(LogError):
            obj = load_log(p, repair_spikes=args.repair_spikes)
        report_repairs([obj], NAME)
        t_start, t_stop = (float(obj.t[0]), float(obj.t[-1])) if len(obj.t) else (0.0, 0.0)
    else:
        t_start, t_stop, streamed, obj = _run_extent(p)
        if args.t0 is None and args.t1 is None and streamed is not None:
            # a run streamed to disk may not fit in memory: its kept end by default
            args.t0 = max(t_start, t_stop - streamed)
            print(
                f"streamed run: plotting its last {t_stop - args.t0:g} s (t = {args.t0:g} - "
                f"{t_stop:g} s; --t0 / --t1 choose another window)"
            )
    t0 = t_start if args.t0 is None else args.t0
    t1 = t_stop if args.t1 is None else args.t1
    t_range = None if (args.t0 is None and args.t1 is None) else (t0, t1)
    if t_range is not None and t_stop > t_start and not (t0 < t_stop and t1 > t_start):
        raise UsageError(
            f"--t0 {t0:g} --t1 {t1:g} is not allowed: the window must overlap "
            f"the {'log' if is_log else 'run'} ({t_start:g} .. {t_stop:g} s)"
        )
    if not is_log and obj is None:  # (a saved run's tables: only the window is read)
        obj = load_result(p, t_range)
    with usage_errors():
        if is_log:
            from ..presentation.log_figure import plot_log

            plot_log(obj, out, t_range=t_range)
        else:
            from ..presentation.plots import plot_run

            plot_run(
                obj,
                out,
                t_range=t_range,
                overview="auto",
                behaviour=_saved_behaviour(p) if t_range is not None else None,
            )
    print(f"wrote {out}")
    return 0
