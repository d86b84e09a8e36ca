"""The power over one stride of a run by destination (docs/model.md "Work-energy
balance"; needs ``simulate(energy=True)``): the battery's output and where it goes
(copper and transmission losses, hip work), and where the hip work goes (friction and
dampers, the change of mechanical energy, the touchdown impacts). Power in W, energy in J,
time in s.

    fig = plot_stride_power(result, "power.png")
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from ..names import Leg, LegState
from .run_parts import behaviour_text, run_model_label, state_bands
from .style import LEG_STATE_COLORS, save_figure

__all__ = ["plot_stride_power", "STRIDE_POWER_SOURCES", "STRIDE_POWER_SINKS"]


#: destinations of :func:`plot_stride_power`: (name for ``result.power``, label, colour)
STRIDE_POWER_SOURCES = (
    ("battery", "battery output", "k"),
    ("copper", "copper losses R_A i^2", "tab:orange"),
    ("transmission", "transmission losses (signed)", "tab:purple"),
    ("hip_work", "hip work (mechanical)", "tab:green"),
)
STRIDE_POWER_SINKS = (
    ("hip_work", "hip work", "tab:green"),
    ("friction", "friction and dampers", "tab:brown"),
)


def plot_stride_power(result, path=None, stride=None) -> Figure:
    """Power over one stride by destination (needs ``simulate(energy=True)``; ``scoutsim
    run --plots`` draws it as stride_power.png).

    Two panels share the time axis [s], the power [W] of both virtual legs together, each
    the mean over a control period (``result.power``: exact, from the energy integrated on
    every integrator step):

    1. the battery's output and where it goes: motor copper losses, transmission losses
       (the paper's constant efficiency, signed: negative while a leg back-drives its
       motor) and the hip work, which add up to the electrical power into the motors
       (docs/model.md "Work-energy balance"); the ideal actuator has the hip work only;
    2. where the hip work goes: every friction and damper of the mechanism, and the rate of
       change of the mechanical energy (kinetic, gravity, springs); touchdowns are marked,
       with their impact losses [J] (none where the toes land sliding).

    The legends, right of the panels, give each destination's energy over the stride [J]
    and the colours of the background: each leg's controller state (paper Sec. II, Table I:
    flight, stance-retraction, stance-brake), the back leg in the lower half of each panel,
    the front leg in the upper half. The title says whether the stride is steady and, if
    the run did not bound steadily, what it did instead.

    Parameters
    ----------
    result : SimulationResult
        A run made with the energy accounting.
    path : str or path-like, optional
        Save the figure there (.png, .pdf, .svg).
    stride : int, optional
        Index into ``result.strides`` (default: the last steady stride, or the last stride
        if none is steady).

    Returns
    -------
    matplotlib.figure.Figure
    """
    if result.energy_series is None:
        raise ValueError("plot_stride_power needs a run made with simulate(..., energy=True)")
    model = (result.provenance or {}).get("model")
    if model == "passive":
        raise ValueError("plot_stride_power: the passive model has no actuators (no power input)")
    strides = result.strides
    if not strides:
        raise ValueError("plot_stride_power: the run has no complete stride")
    if stride is None:
        steady = [s for s in strides if s.steady]
        st = steady[-1] if steady else strides[-1]
    else:
        if not (isinstance(stride, (int, np.integer)) and -len(strides) <= stride < len(strides)):
            raise ValueError(
                f"stride = {stride!r} is not allowed: must be an index into the "
                f"run's {len(strides)} strides"
            )
        st = strides[stride]
    if st.energy_t_start is None:
        raise ValueError("plot_stride_power: the stride has no energy (too short a run?)")
    t = np.asarray(result.t, dtype=float)
    i, j = (int(np.searchsorted(t, v)) for v in (st.energy_t_start, st.energy_t_end))
    k = np.arange(i, j + 1)  # the periods i .. j-1, drawn as steps to t[j]
    tk = t[k]

    def steps(p):
        return np.append(p[i:j], p[j - 1])

    fig = Figure(figsize=(12.5, 7.5), layout="constrained")
    ax_in, ax_out = fig.subplots(2, 1, sharex=True)
    electrical = model in ("I", "II")
    sources = STRIDE_POWER_SOURCES if electrical else STRIDE_POWER_SOURCES[-1:]
    for name, label, color in sources:
        e = float(result.cumulative_energy(name)[j] - result.cumulative_energy(name)[i])
        ax_in.step(
            tk,
            steps(result.power(name)),
            where="post",
            color=color,
            lw=2.0 if name == "battery" else 1.2,
            label=f"{label}: {e:.1f} J",
        )
    mech = np.full(len(t), np.nan)
    mech[:-1] = np.diff(np.asarray(result.energy, dtype=float)) / np.diff(t)
    for name, label, color in STRIDE_POWER_SINKS:
        e = float(result.cumulative_energy(name)[j] - result.cumulative_energy(name)[i])
        ax_out.step(
            tk,
            steps(result.power(name)),
            where="post",
            color=color,
            lw=1.2,
            label=f"{label}: {e:.1f} J",
        )
    ax_out.step(
        tk,
        steps(mech),
        where="post",
        color="tab:gray",
        lw=1.2,
        label=f"rate of change of mechanical energy: {st.mechanical_energy_change_j:+.1f} J",
    )
    imp = result.impact_log(t[i], t[j])
    for n, (t_imp, lost) in enumerate(zip(imp["t"], imp["energy_lost"])):
        ax_out.axvline(
            t_imp,
            color="tab:red",
            ls=":",
            lw=1.0,
            label=(
                f"touchdowns (impact losses {imp['energy_lost'].sum():.2f} J)" if n == 0 else None
            ),
        )
        if lost >= 0.005:
            ax_out.annotate(
                f"{lost:.2f} J",
                (t_imp, 0.95),
                xycoords=("data", "axes fraction"),
                fontsize=8,
                color="tab:red",
                ha="left",
                va="top",
            )
    for ax in (ax_in, ax_out):
        ax.axhline(0.0, color="k", lw=0.5)
        for leg, (y0, y1) in zip(Leg, ((0.0, 0.5), (0.5, 1.0))):
            state_bands(ax, t[i : j + 1], result.leg_state(leg)[i : j + 1], y0, y1)
            ax.text(
                1.005,
                0.5 * (leg + 0.5),
                f"{leg.label}\nleg",
                transform=ax.transAxes,
                fontsize=7,
                va="center",
                ha="left",
                color="0.35",
            )
        handles, labels = ax.get_legend_handles_labels()
        if ax is ax_in:
            # the background's colours: each leg's controller state
            handles.append(Patch(visible=False))
            labels.append(
                "background: controller leg state\n(back leg: lower half of a "
                "panel;\nfront leg: upper half)"
            )
            handles += [
                Patch(facecolor=LEG_STATE_COLORS[state], edgecolor="0.5", lw=0.5)
                for state in LegState
            ]
            labels += [state.label for state in LegState]
        ax.legend(
            handles,
            labels,
            loc="upper left",
            bbox_to_anchor=(1.055, 1.0),
            fontsize=8,
            framealpha=0.9,
            borderaxespad=0.0,
        )
        ax.grid(alpha=0.3)
    ax_in.set_ylabel("power from the battery [W]")
    ax_out.set_ylabel("power of the hip work [W]")
    ax_out.set_xlabel("time [s]")
    ax_out.set_xlim(tk[0], tk[-1])
    cot = "" if st.cost_of_transport is None else f", cost of transport {st.cost_of_transport:.2f}"
    title = (
        f"Power over stride {st.index} ({tk[0]:.3f} - {tk[-1]:.3f} s"
        f"{'' if st.steady else ', not a steady stride'}), {run_model_label(result)}{cot}"
    )
    try:
        what = result.behaviour()
    except Exception:  # a run too broken for the stride analysis
        what = None
    if what is None or not what.bounding:
        import textwrap

        title += "\n" + "\n".join(textwrap.wrap(f"the run: {behaviour_text(result)}", 120))
    fig.suptitle(title, fontsize=10)
    save_figure(fig, path)
    return fig
