"""Fixtures shared by the test modules."""

import importlib.util
import os
import time
from pathlib import Path

import pytest
import session_work

import scoutsim

_AS_IS_KEY = pytest.StashKey[session_work.AsIsRun]()


def _starts_workers(config) -> bool:
    """Whether this process runs the tests on workers (pytest-xdist) instead of itself."""
    return bool(getattr(config.option, "numprocesses", None)) and not hasattr(config, "workerinput")


def pytest_sessionstart(session):
    """Before the workers start (on several workers only): the second process of the
    compile-step test, then the core's compile, once for all (tests/session_work.py)."""
    config = session.config
    if not _starts_workers(config):
        return
    if session_work.as_is_test_selected(config) and not os.environ.get(
        session_work.AS_IS_DIRECTORY
    ):
        run = session_work.AsIsRun()
        config.stash[_AS_IS_KEY] = run
        os.environ[session_work.AS_IS_DIRECTORY] = str(run.dir)
    t0 = time.perf_counter()
    session_work.compile_the_core()
    reporter = config.pluginmanager.get_plugin("terminalreporter")
    if reporter is not None:
        reporter.write_line(
            f"compiled the core for the workers in {time.perf_counter() - t0:.0f} s "
            "(loaded from the cache if it was there)"
        )


def pytest_unconfigure(config):
    run = config.stash.get(_AS_IS_KEY, None)
    if run is not None:
        os.environ.pop(session_work.AS_IS_DIRECTORY, None)
        run.close()


@pytest.fixture
def force_outcome(monkeypatch):
    """``force_outcome("fell")``: every ``scoutsim.simulation.simulator.simulate`` call of the test
    runs as usual and then reports that outcome (to test what a command does with it)."""
    real = scoutsim.simulation.simulator.simulate

    def force(outcome: str) -> None:
        def simulate(*args, **kwargs):
            r = real(*args, **kwargs)
            r.outcome = outcome
            return r

        monkeypatch.setattr(scoutsim.simulation.simulator, "simulate", simulate)

    return force


@pytest.fixture
def interrupt_run(monkeypatch):
    """``interrupt_run(n)``: the n-th ``scoutsim.simulation.simulator.simulate`` call of the test
    returns as if Ctrl-C had reached it (outcome "interrupted", the data so far); the
    others run as usual."""
    real = scoutsim.simulation.simulator.simulate
    calls = []

    def interrupt(n: int) -> None:
        def simulate(*args, **kwargs):
            r = real(*args, **kwargs)
            calls.append(1)
            if len(calls) == n:
                r.outcome = "interrupted"
            return r

        monkeypatch.setattr(scoutsim.simulation.simulator, "simulate", simulate)

    return interrupt


@pytest.fixture
def dask_client_timeouts(monkeypatch):
    """The ``timeout`` given to every ``distributed.Client`` the test makes (each still the
    real Client); skips the test without dask.distributed."""
    distributed = pytest.importorskip("distributed")
    timeouts = []

    class Client(distributed.Client):
        def __init__(self, *args, **kwargs):
            timeouts.append(kwargs.get("timeout"))
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(distributed, "Client", Client)
    return timeouts


@pytest.fixture(scope="session")
def dask_cluster():
    """A local Dask cluster of two single-threaded worker processes, started once for the
    session (each start spawns a scheduler and two workers that import scoutsim: seconds)
    and shared by the tests that compare a study on Dask with the same study in local
    processes; a test that kills a worker, or needs an environment set before the workers
    start, starts its own. Skips the test without dask.distributed."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        yield cluster


@pytest.fixture
def dask_client(dask_cluster):
    """A ``distributed.Client`` of the session's cluster (:func:`dask_cluster`), closed
    after the test."""
    import distributed

    with distributed.Client(dask_cluster) as client:
        yield client


@pytest.fixture(scope="session")
def symbolic_model():
    """``tools/derive_eom.py``: the equations of motion derived with SymPy from the kinetic
    and potential energies, independently of ``scoutsim._core.model`` (``mass_matrix(q,
    params)``, ``params_from_robot(robot)``, energies, toe kinematics)."""
    path = Path(__file__).resolve().parents[1] / "tools" / "derive_eom.py"
    spec = importlib.util.spec_from_file_location("derive_eom_for_tests", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _png_draws_each_axes_data(path, fig, dpi=None):
    """Assert that the PNG at ``path``, written from ``fig``, shows the figure's data in
    every axes that has some: the figure is drawn again with its data artists (lines,
    collections, patches of the axes) hidden, and inside each such axes the two images
    differ in at least half as many pixels as the axes is wide (a curve across it), not
    only in a legend or a tick. The saved image is the size of the figure at its dpi."""
    import io

    import matplotlib.image as mpimg
    import numpy as np

    from scoutsim.presentation.style import PNG_DPI

    dpi = dpi or PNG_DPI
    shown = mpimg.imread(path)[..., :3]
    w_in, h_in = fig.get_size_inches()
    assert shown.shape[:2] == (round(h_in * dpi), round(w_in * dpi))
    data_axes = [
        ax
        for ax in fig.get_axes()
        if ax.get_visible() and (ax.lines or ax.collections or ax.patches)
    ]
    assert data_axes
    hidden = [
        a for ax in data_axes for a in (*ax.lines, *ax.collections, *ax.patches) if a.get_visible()
    ]
    for a in hidden:
        a.set_visible(False)
    try:
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=dpi)
    finally:
        for a in hidden:
            a.set_visible(True)
    buf.seek(0)
    bare = mpimg.imread(buf, format="png")[..., :3]
    assert bare.shape == shown.shape
    differs = np.max(np.abs(shown - bare), axis=2) > 0.1
    height, width = shown.shape[:2]
    for ax in data_axes:
        x0, y0, x1, y1 = ax.get_position().extents
        rows = slice(round((1 - y1) * height) + 2, round((1 - y0) * height) - 2)
        cols = slice(round(x0 * width) + 2, round(x1 * width) - 2)
        inside = int(np.count_nonzero(differs[rows, cols]))
        assert inside >= 0.5 * (cols.stop - cols.start), (
            f"{path}: the axes {ax.get_ylabel()!r} shows no data ({inside} pixels)"
        )


@pytest.fixture
def png_draws_each_axes_data():
    """``png_draws_each_axes_data(path, fig)``: see :func:`_png_draws_each_axes_data`."""
    return _png_draws_each_axes_data


@pytest.fixture(autouse=True)
def _parameter_warnings_start_afresh():
    """Each test starts with no memory of values already warned of with their file (the
    process-wide memory that keeps the library from warning twice of one value): a test
    that expects a warning must not depend on which tests ran before it in the process."""
    from scoutsim.parameters import plausibility

    plausibility._WARNED_FROM_A_FILE.clear()
    yield
