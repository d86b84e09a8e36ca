"""Tests of scoutsim.presentation.plots: figures render headless, carry units, and draw the motor
limits of docs/specification.md section 4 where they belong."""

import sys

import numpy as np
import pytest
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure

import scoutsim
from scoutsim.presentation.plots import motor_limits, plot_run, plot_torque_speed
from scoutsim.presentation.style import LEG_STATE_COLORS

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def result_II():
    return scoutsim.simulate(duration=1.0, model="II")


@pytest.fixture(scope="module")
def result_I():
    return scoutsim.simulate(duration=1.0, model="I")


def _pyplot_fignums():
    plt = sys.modules.get("matplotlib.pyplot")
    return None if plt is None else list(plt.get_fignums())


def test_plot_run_has_four_labelled_panels_with_units(result_II):
    fig = plot_run(result_II)
    assert isinstance(fig, Figure)
    axes = fig.get_axes()
    assert len(axes) == 4
    ylabels = [ax.get_ylabel() for ax in axes]
    assert "[deg]" in ylabels[0] and "pitch" in ylabels[0]
    assert "[m]" in ylabels[1] and "height" in ylabels[1]
    assert "[deg]" in ylabels[2] and "phi" in ylabels[2]
    assert "[N m]" in ylabels[3] and "torque" in ylabels[3]
    assert axes[3].get_xlabel() == "time [s]"
    for ax in axes:
        assert ax.get_lines(), "every panel has data"
        assert ax.get_legend() is not None
    # panels share the time axis
    assert axes[0].get_shared_x_axes().joined(axes[0], axes[3])
    title = " ".join(fig._suptitle.get_text().split())  # (wrapped over lines)
    assert "Model II" in title and result_II.behaviour().text in title


def test_plot_run_values_are_in_degrees(result_II):
    fig = plot_run(result_II)
    pitch_line = fig.get_axes()[0].get_lines()[0]
    np.testing.assert_allclose(pitch_line.get_ydata(), np.degrees(result_II.pitch))
    leg_lines = [ln for ln in fig.get_axes()[2].get_lines() if ln.get_label().startswith("phi")]
    np.testing.assert_allclose(leg_lines[0].get_ydata(), np.degrees(result_II.leg_angle("back")))
    np.testing.assert_allclose(leg_lines[1].get_ydata(), np.degrees(result_II.leg_angle("front")))


def test_plot_run_shows_torques_commanded_dashed_and_applied_solid(result_II):
    ax = plot_run(result_II).get_axes()[3]
    by_label = {ln.get_label(): ln for ln in ax.get_lines()}
    for leg in ("back", "front"):
        cmd, app = by_label[f"{leg} commanded"], by_label[f"{leg} applied"]
        assert cmd.get_linestyle() == "--" and app.get_linestyle() == "-"
        np.testing.assert_allclose(cmd.get_ydata(), result_II.hip_torque_commanded(leg))
        np.testing.assert_allclose(app.get_ydata(), result_II.hip_torque_applied(leg))


def test_plot_run_leg_state_bands_cover_the_states_the_controller_visited(result_II):
    ax = plot_run(result_II).get_axes()[2]
    bands = [c for c in ax.collections if isinstance(c, PolyCollection)]
    colors = {tuple(np.round(c.get_facecolor()[0][:3], 3)) for c in bands}
    from matplotlib.colors import to_rgb

    visited = set(np.unique(result_II.leg_state(0))) | set(np.unique(result_II.leg_state(1)))
    assert visited == {0, 1, 2}, "a 1 s run passes through all three leg states"
    expected = {tuple(np.round(to_rgb(LEG_STATE_COLORS[k]), 3)) for k in visited}
    assert colors == expected
    # the bands of one leg tile its time span without gaps (zero-order hold)
    back = [c for c in bands if c.get_paths()[0].vertices[0, 1] == 0.0]
    total = sum(float(np.ptp(p.vertices[:, 0])) for c in back for p in c.get_paths())
    assert total == pytest.approx(result_II.t[-1] - result_II.t[0], rel=1e-9)
    legend_texts = {t.get_text() for t in ax.get_legend().get_texts()}
    assert {"flight", "stance-retraction", "stance-brake"} <= legend_texts


def test_plot_run_saves_png_pdf_svg_headless(result_II, tmp_path, png_draws_each_axes_data):
    before = _pyplot_fignums()
    for suffix, magic in ((".png", PNG_MAGIC), (".pdf", b"%PDF"), (".svg", b"<?xml")):
        path = tmp_path / "sub" / f"run{suffix}"
        fig = plot_run(result_II, path)
        data = path.read_bytes()
        assert data.startswith(magic)
        if suffix == ".png":
            png_draws_each_axes_data(path, fig)
        else:  # the file is whole
            assert data.rstrip().endswith(b"%%EOF" if suffix == ".pdf" else b"</svg>")
    assert _pyplot_fignums() == before, "no figures registered with pyplot"


def test_plot_run_rejects_unknown_suffix_and_bad_time_range(result_II, tmp_path):
    with pytest.raises(ValueError, match="suffix"):
        plot_run(result_II, tmp_path / "run.jpeg")
    with pytest.raises(ValueError, match="t_range"):
        plot_run(result_II, t_range=(0.5, 0.2))


def test_plot_run_time_range_limits_axis_and_data(result_II):
    fig = plot_run(result_II, t_range=(0.2, 0.6))
    ax = fig.get_axes()[0]
    assert ax.get_xlim() == pytest.approx((0.2, 0.6))
    x = ax.get_lines()[0].get_xdata()
    assert x[0] >= 0.2 - 1.5e-3 and x[-1] <= 0.6 + 1.5e-3


def test_motor_limits_match_spec_numbers():
    lim = motor_limits(scoutsim.simulate(duration=0.01, model="I").provenance["robot"])
    assert lim["N"] == pytest.approx(102.19, abs=0.01)  # 72.38 x 48/34
    assert lim["eta"] == pytest.approx(0.6528)
    assert lim["tau_current"] == pytest.approx(lim["N"] * 0.6528 * 0.0389 * 12.0)
    assert lim["w_no_load"] == pytest.approx(36.0 / (0.0389 * lim["N"]))


def test_torque_speed_draws_current_limit_and_torque_speed_lines(result_I, tmp_path):
    path = tmp_path / "ts.png"
    fig = plot_torque_speed(result_I, "both", path)
    assert path.read_bytes().startswith(PNG_MAGIC)
    axes = fig.get_axes()
    assert len(axes) == 2
    lim = motor_limits(result_I.provenance["robot"])
    for ax, leg in zip(axes, ("back", "front")):
        assert "[N m]" in ax.get_xlabel() and "[rad/s]" in ax.get_ylabel()
        assert leg in ax.get_title()
        lines = ax.get_lines()
        verticals = sorted(
            float(ln.get_xdata()[0])
            for ln in lines
            if ln.get_linestyle() == "--" and len(set(ln.get_xdata())) == 1
        )
        assert verticals == pytest.approx([-lim["tau_current"], lim["tau_current"]])
        ts_lines = [ln for ln in lines if ln.get_linestyle() == "-."]
        assert len(ts_lines) == 2
        for ln, sign in zip(ts_lines, (1.0, -1.0)):
            tau, w = np.asarray(ln.get_xdata()), np.asarray(ln.get_ydata())
            # tau = N eta K_T (+-V - K_w N w) / R_A
            expect = lim["N"] * lim["eta"] * 0.0389 * (sign * 36.0 - 0.0389 * lim["N"] * w) / 1.2
            np.testing.assert_allclose(tau, expect, rtol=1e-12)
        # the samples lie inside the limits (Model I enforces them)
        pts = [ln for ln in lines if ln.get_linestyle() in ("None", "none", "")]
        tau = np.concatenate([ln.get_xdata() for ln in pts])
        w = np.concatenate([ln.get_ydata() for ln in pts])
        assert tau.size == result_I.t.size
        assert np.all(np.abs(tau) <= lim["tau_current"] * (1 + 1e-9))
        assert np.all(tau <= lim["tau_stall"] - lim["slope"] * w + 1e-6)
        assert np.all(tau >= -lim["tau_stall"] - lim["slope"] * w - 1e-6)


def test_torque_speed_single_leg_and_bad_leg(result_II):
    fig = plot_torque_speed(result_II, "front")
    assert len(fig.get_axes()) == 1 and "front" in fig.get_axes()[0].get_title()
    with pytest.raises(ValueError, match="leg"):
        plot_torque_speed(result_II, "middle")


def test_plot_run_overview_shows_the_whole_run_and_the_last_strides(result_II):
    from scoutsim.presentation.plots import DETAIL_STRIDES

    fig = plot_run(result_II, overview=True)
    axes = fig.get_axes()
    assert len(axes) == 7
    overview, detail = axes[:3], axes[3:]
    t = result_II.t
    assert overview[0].get_xlim() == pytest.approx((t[0], t[-1]))
    t0, t1 = detail[-1].get_xlim()
    assert t1 == pytest.approx(t[-1])
    strides = result_II.strides
    assert t0 == pytest.approx(strides[-DETAIL_STRIDES]["t_start"])
    # "auto": only runs longer than LONG_RUN_S get the overview
    assert len(plot_run(result_II, overview="auto").get_axes()) == (7 if t[-1] - t[0] > 4.0 else 4)
    with pytest.raises(ValueError, match="overview"):
        plot_run(result_II, overview="yes")


def test_plot_stride_power_shows_each_destination_with_its_energy(tmp_path):
    """Two panels in W over one stride: the battery's output with copper, transmission and
    hip work (their stride energies in the legend, adding up to the battery's), then the
    hip work with friction and dampers and the mechanical energy's rate of change."""
    from scoutsim.presentation.plots import plot_stride_power

    r = scoutsim.simulate(duration=1.0, model="II", energy=True)
    fig = plot_stride_power(r, tmp_path / "p.png", stride=1)
    assert (tmp_path / "p.png").read_bytes()[:8] == PNG_MAGIC
    ax_in, ax_out = fig.get_axes()
    assert "[W]" in ax_in.get_ylabel() and "[W]" in ax_out.get_ylabel()
    labels = [t.get_text() for t in ax_in.get_legend().get_texts()]
    energy = {
        lab.split(":")[0]: float(lab.split(":")[1].split()[0])
        for lab in labels
        if lab.endswith(" J")
    }
    assert energy["battery output"] == pytest.approx(
        energy["copper losses R_A i^2"]
        + energy["transmission losses (signed)"]
        + energy["hip work (mechanical)"],
        abs=0.15,
    )  # legend rounds to 0.1 J
    assert any("friction" in t.get_text() for t in ax_out.get_legend().get_texts())
    with pytest.raises(ValueError, match="energy=True"):
        plot_stride_power(scoutsim.simulate(duration=1.0, model="II"))


def _drawn(fig):
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig).draw()
    return fig


def test_plot_run_legends_sit_above_their_panels_off_the_traces(result_II):
    """Every legend of the four panels lies above its axes (in display coordinates), so it
    covers no trace; the title says what the run did."""
    fig = _drawn(plot_run(result_II))
    for ax in fig.get_axes():
        legend = ax.get_legend().get_window_extent()
        assert legend.y0 >= ax.get_window_extent().y1 - 0.5, ax.get_ylabel()


def test_plot_run_overview_draws_the_range_over_one_stride_and_every_stride():
    """A 5 s run: the overview's pitch band holds every sample between its edges, its upper
    edge reaching the run's largest pitch; one marker per stride, the steady ones filled."""
    r = scoutsim.simulate(duration=5.0, model="II")
    fig = plot_run(r, overview="auto")
    ax_p, ax_h, ax_s = fig.get_axes()[:3]
    pitch = np.degrees(r.pitch)
    hi, lo = (ln.get_ydata() for ln in ax_p.get_lines()[:2])
    assert np.all(lo <= pitch) and np.all(pitch <= hi)
    assert hi.max() == pitch.max() and lo.min() == pitch.min()
    # the band is a stride wide: in the steady bound it is the stride's pitch range
    steady = r.gait().steady_strides
    k = np.searchsorted(r.t, 0.5 * (steady[-1].t_start + steady[-1].t_end))
    assert hi[k] == pytest.approx(steady[-1].pitch_max_deg, abs=0.05)
    assert lo[k] == pytest.approx(steady[-1].pitch_min_deg, abs=0.05)
    open_marks, filled = ax_s.get_lines()
    assert len(filled.get_xdata()) == r.gait().n_steady_strides
    assert len(open_marks.get_xdata()) + len(filled.get_xdata()) == r.gait().n_strides
    np.testing.assert_array_equal(filled.get_ydata(), [s.period_s for s in steady])


def test_plot_run_title_of_a_fall_says_so():
    """A robot that fell is not "bounding ... completed": the title says when and how."""
    import math

    r = scoutsim.simulate(
        initial_state=scoutsim.InitialState(theta=math.radians(40.0), y=0.5), duration=1.0
    )
    title = " ".join(plot_run(r)._suptitle.get_text().split())
    assert "fell at t = " in title and "pitch passed 60 deg" in title
    assert "bounding" not in title and "completed" not in title


def test_plot_stride_power_has_a_legend_for_the_leg_state_colours():
    """The background bands' colours are named in a legend: flight, stance-retraction,
    stance-brake, each patch the colour of the bands of that state."""
    from matplotlib.colors import to_rgba
    from matplotlib.patches import Patch

    from scoutsim.names import LegState
    from scoutsim.presentation.plots import plot_stride_power

    r = scoutsim.simulate(duration=1.0, model="II", energy=True)
    fig = plot_stride_power(r)
    ax_in, ax_out = fig.get_axes()
    legend = ax_in.get_legend()
    patches = {
        t.get_text(): h
        for t, h in zip(legend.get_texts(), legend.legend_handles)
        if isinstance(h, Patch) and h.get_visible()
    }
    for state in LegState:
        assert to_rgba(patches[state.label].get_facecolor()) == to_rgba(LEG_STATE_COLORS[state])
    band_colours = {
        to_rgba(tuple(c))
        for coll in ax_out.collections
        if isinstance(coll, PolyCollection)
        for c in coll.get_facecolors()
    }
    assert band_colours <= {to_rgba(c) for c in LEG_STATE_COLORS}
    _drawn(fig)
    for ax in (ax_in, ax_out):  # the legends right of the panels, off the traces
        assert ax.get_legend().get_window_extent().x0 >= ax.get_window_extent().x1


def test_a_window_of_a_run_is_titled_by_its_run_not_by_its_own_strides(result_II):
    """A window holds too few strides to judge the gait: the title gives the run's outcome
    and the window shown, or what the whole run did when told (a saved run's summary)."""
    part = result_II.window(0.2, 0.6)
    title = " ".join(plot_run(part)._suptitle.get_text().split())
    assert "t = 0.20 - 0.60 s shown of the run's 0 - 1.00 s" in title
    assert "stride" not in title
    whole = result_II.behaviour().text
    title = " ".join(plot_run(part, behaviour=whole)._suptitle.get_text().split())
    assert title.startswith(f"Scout II, Model II: {whole} (t = 0.20 - 0.60 s shown")


def test_scoutsim_plot_of_a_window_titles_it_by_the_saved_summary(tmp_path, monkeypatch):
    import json

    import scoutsim.presentation.plots as plots
    from scoutsim.cli import main

    out = tmp_path / "run"
    assert main(["run", "--duration", "0.5", "--out", str(out), "--no-progress", "--quiet"]) == 0
    seen = {}
    real = plots.plot_run

    def spy(result, path=None, **kwargs):
        seen.update(kwargs)
        return real(result, path, **kwargs)

    monkeypatch.setattr(plots, "plot_run", spy)
    assert (
        main(["plot", str(out), "--t0", "0.1", "--t1", "0.3", "--out", str(tmp_path / "w.png")])
        == 0
    )
    assert seen["behaviour"] == json.loads((out / "summary.json").read_text())["behaviour"]
