"""The compiled integrator against SciPy's solve_ivp (RK45) driving the same model functions
(benchmarks/scipy_baseline.py): two independent integrators and event locators agree."""

import importlib.util
from pathlib import Path

import numpy as np

import scoutsim
import scoutsim.parameters

ROOT = Path(__file__).resolve().parents[3]


def _baseline():
    spec = importlib.util.spec_from_file_location(
        "scipy_baseline", ROOT / "benchmarks" / "scipy_baseline.py"
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_model_ii_state_agrees_with_scipy_solve_ivp():
    mu = scoutsim.parameters.DEFAULT_FRICTION_COEFFICIENT
    t, nev, s = _baseline().run(0.21, "II", rtol=1e-10, atol=1e-10, friction_coefficient=mu)
    r = scoutsim.simulate(
        duration=0.21,
        model="II",
        friction_coefficient=mu,
        integrator=scoutsim.IntegratorSettings(rtol=1e-10, atol=1e-10),
    )
    assert t == r.t[-1]
    assert len(r.event_times("touchdown")) >= 2  # both touchdowns inside the window
    assert np.max(np.abs(s[:3] - r.state[-1, :3])) < 1e-7
    assert np.max(np.abs(s[7:10] - r.state[-1, 7:10])) < 1e-5
