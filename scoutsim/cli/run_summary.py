"""The printed summary of ``scoutsim run``: the table of what the robot did and the gait
means (:func:`format_summary`), and the short energy block (:func:`format_energy`).
"""

from __future__ import annotations

import math


def _fmt(v, spec: str, unit: str = "") -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "n/a"
    return f"{v:{spec}}{(' ' + unit) if unit else ''}"


def _pair(a, b, spec: str, unit: str) -> str:
    if a is None and b is None:
        return "n/a"
    return f"{_fmt(a, spec)} / {_fmt(b, spec)}{(' ' + unit) if unit else ''}"


def format_summary(
    summary: dict,
    *,
    duration: float,
    wall_s: float,
    t_end: float,
    friction: float | None = None,
    load_s: float | None = None,
    command_wall_s: float | None = None,
) -> str:
    """The human-readable summary table of a run: what the robot did (``behaviour``:
    steady bounding, or what instead, :mod:`scoutsim.analysis.behaviour`), the gait means
    over the steady strides, ``wall_s`` the simulation's wall time [s] (its real-time factor
    is t_end / wall_s), ``load_s`` the time the compiled core took to get ready before it,
    ``command_wall_s`` the whole command's."""
    import textwrap

    outcome = summary.get("outcome")
    if outcome != "completed" and t_end is not None:
        outcome = f"{outcome} at t = {t_end:.3f} s"
    rtf = (t_end / wall_s) if wall_s > 0 and t_end else None
    steady = bool(summary.get("n_steady_strides"))
    speed = _fmt(summary.get("mean_speed_m_s"), ".3f", "m/s")
    if not steady:
        # no steady stride: the run's average instead, said to be one
        average = ((summary.get("behaviour_detail") or {}).get("counts") or {}).get(
            "average_speed_m_s"
        )
        speed = "n/a (no steady stride)" + (
            f"; {average:.3f} m/s averaged over the run" if average is not None else ""
        )
    rows = [
        ("outcome", outcome),
        ("what the robot did", summary.get("behaviour") or "n/a"),
    ]
    n_steady = summary.get("n_steady_strides") or 0
    if steady and summary.get("steady_bounding") is False:
        # a few strides passed the steadiness test, but the run is no steady bound: the
        # means below describe those strides alone, and say so
        rows.append(
            (
                "gait means below",
                f"over {n_steady} steady stride"
                f"{'s' if n_steady != 1 else ''} only (not a steady bound)",
            )
        )
    rows += [
        ("mean forward speed", speed),
        ("stride frequency", _fmt(summary.get("stride_frequency_hz"), ".3f", "Hz")),
        (
            "duty factor back / front",
            _pair(summary.get("duty_factor_back"), summary.get("duty_factor_front"), ".3f", ""),
        ),
        (
            "pitch max / min",
            _pair(summary.get("pitch_max_deg"), summary.get("pitch_min_deg"), ".2f", "deg"),
        ),
        (
            "COM height max / min",
            _pair(summary.get("height_max_m"), summary.get("height_min_m"), ".4f", "m"),
        ),
        ("largest friction ratio |F_t|/F_n", _fmt(summary.get("max_friction_ratio"), ".3f")),
        (
            "steady strides",
            _fmt(summary.get("n_steady_strides"), "d")
            + (f" (of {summary['n_strides']})" if summary.get("n_strides") is not None else ""),
        ),
        (
            "steady bounding",
            {True: "yes", False: "no", None: "n/a"}.get(summary.get("steady_bounding"), "n/a"),
        ),
    ]
    if "startup_duration_s" in summary:
        rows.append(
            (
                "start-up (standing to bounding)",
                _fmt(summary["startup_duration_s"], ".3f", "s") + " (t = 0 to the "
                "hand-over to the bounding controller)",
            )
        )
    rows += [
        (
            "simulation",
            (
                f"{wall_s:.3f} s wall, real-time factor {rtf:.0f}x"
                if rtf
                else _fmt(wall_s, ".3f", "s")
            ),
        ),
    ]
    if load_s is not None:
        rows.append(
            (
                "compiled core",
                f"ready in {load_s:.2f} s (loaded from the cache, or compiled on a first run)",
            )
        )
    if command_wall_s is not None:
        rows.append(
            ("command wall time", f"{command_wall_s:.2f} s (start-up, simulation, outputs)")
        )
    width = max(len(k) for k, _ in rows)
    model = summary.get("model")
    floor = (
        ""
        if friction is None
        else ", floor: no slip"
        if math.isinf(friction)
        else f", floor: Coulomb mu = {friction:g}"
    )
    lines = [f"scoutsim run: model {model}, {duration:g} s requested{floor}"]
    for k, v in rows:
        line = f"  {k:<{width}}  {v}"
        if k == "what the robot did":  # a sentence: wrapped under its column
            lines += textwrap.wrap(
                line, 100, subsequent_indent=" " * (width + 4), break_on_hyphens=False
            )
        else:
            lines.append(line)
    return "\n".join(lines)


def format_energy(summary: dict) -> str:
    """The short energy block of a run's summary (:data:`SUMMARY_ENERGY_KEYS
    <scoutsim.analysis.gait.SUMMARY_ENERGY_KEYS>`): where the electrical energy went over
    the run, and the steady strides' mean power and cost of transport."""
    e = summary.get("electrical_energy_j")
    head = "  energy, whole run      " + (
        f"electrical {e:.1f} J = copper {summary['copper_loss_j']:.1f} + transmission "
        f"{summary['transmission_loss_j']:.1f} + hip work {summary['hip_work_j']:.1f} J"
        if e is not None
        else f"hip work {_fmt(summary.get('hip_work_j'), '.1f', 'J')}"
    )
    rows = [
        head,
        f"  hip work went to       friction and dampers "
        f"{_fmt(summary.get('friction_loss_j'), '.1f', 'J')}, impacts "
        f"{_fmt(summary.get('impact_loss_j'), '.1f', 'J')}, mechanical energy "
        f"{_fmt(summary.get('mechanical_energy_change_j'), '+.1f', 'J')} (residual "
        f"{_fmt(summary.get('energy_residual_j'), '.2g', 'J')})",
        f"  steady strides         mean electrical power "
        f"{_fmt(summary.get('mean_electrical_power_w'), '.1f', 'W')}, cost of transport "
        f"{_fmt(summary.get('cost_of_transport'), '.3f')}",
    ]
    return "\n".join(rows)
