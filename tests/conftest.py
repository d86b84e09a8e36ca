"""Fixtures shared by the test modules."""

import importlib.util
from pathlib import Path

import pytest

import scoutsim


@pytest.fixture
def force_outcome(monkeypatch):
    """``force_outcome("fell")``: every ``scoutsim.simulation.simulate`` call of the test
    runs as usual and then reports that outcome (to test what a command does with it)."""
    real = scoutsim.simulation.simulate

    def force(outcome: str) -> None:
        def simulate(*args, **kwargs):
            r = real(*args, **kwargs)
            r.outcome = outcome
            return r
        monkeypatch.setattr(scoutsim.simulation, "simulate", simulate)
    return force


@pytest.fixture
def interrupt_run(monkeypatch):
    """``interrupt_run(n)``: the n-th ``scoutsim.simulation.simulate`` call of the test
    returns as if Ctrl-C had reached it (outcome "interrupted", the data so far); the
    others run as usual."""
    real = scoutsim.simulation.simulate
    calls = []

    def interrupt(n: int) -> None:
        def simulate(*args, **kwargs):
            r = real(*args, **kwargs)
            calls.append(1)
            if len(calls) == n:
                r.outcome = "interrupted"
            return r
        monkeypatch.setattr(scoutsim.simulation, "simulate", simulate)
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
def symbolic_model():
    """``tools/derive_eom.py``: the equations of motion derived with SymPy from the kinetic
    and potential energies, independently of ``scoutsim.model`` (``mass_matrix(q,
    params)``, ``params_from_robot(robot)``, energies, toe kinematics)."""
    path = Path(__file__).resolve().parents[1] / "tools" / "derive_eom.py"
    spec = importlib.util.spec_from_file_location("derive_eom_for_tests", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
