"""Tests of scoutsim.presentation.style: one set of names and colours, one file writer."""

import pytest
from matplotlib.figure import Figure

from scoutsim._core.model import layout as L
from scoutsim.presentation import style
from scoutsim.presentation.animation import LEG_STATE_COLORS as ANIMATION_STATE_COLORS


def test_every_model_and_leg_state_has_a_name_and_colour():
    for name in L.MODEL_NAMES:
        assert style.model_label(name) == L.MODEL_LABELS[name]
        assert name in style.MODEL_STYLES
    assert len(style.LEG_STATE_LINE_COLORS) == len(style.LEG_STATE_COLORS) == len(L.LEG_STATE_NAMES)
    # the animation colours leg states as every other figure does
    assert ANIMATION_STATE_COLORS == style.LEG_STATE_LINE_COLORS


def test_unknown_sources_get_distinct_styles():
    styles = {style.model_style(f"run {i}", i) for i in range(4)}
    assert len(styles) == 4
    assert style.model_label("my run") == "my run"


def test_leg_index():
    assert [style.leg_index(x) for x in ("back", "front", 0, 1)] == [0, 1, 0, 1]
    for bad in ("left", 2, True, None):
        with pytest.raises(ValueError, match="leg"):
            style.leg_index(bad)


def test_save_figure_by_suffix(tmp_path):
    fig = Figure()
    fig.add_subplot().plot([0, 1], [0, 1])
    assert style.save_figure(fig, None) is None
    for suffix, magic in ((".png", b"\x89PNG"), (".pdf", b"%PDF"), (".svg", b"<?xml")):
        p = style.save_figure(fig, tmp_path / "sub" / f"f{suffix}")
        assert p.read_bytes().startswith(magic)
    with pytest.raises(ValueError, match="suffix"):
        style.save_figure(fig, tmp_path / "f.jpg")
    assert not (tmp_path / "f.jpg").exists()


def test_package_exports_load_lazily():
    import scoutsim.presentation as P

    assert P.plot_run.__module__ == "scoutsim.presentation.plots"
    assert P.fig12.__module__ == "scoutsim.presentation.error_figure"
    with pytest.raises(AttributeError):
        _ = P.no_such_figure
