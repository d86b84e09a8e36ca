"""What a run records besides its samples: the exact state at every event (before and after
its transition) and, on request, every integrator step.

Laws checked:
* recording changes nothing: a run with step recording is bit-identical to one without;
* at a touchdown the toe is on the ground in the state before, the configuration is the
  same after (an impact changes velocities only) and the energies of both states, computed
  by the independent symbolic model, are the logged transition energies;
* controller records carry the state at their sample (no transition: before = after);
* the integrator steps tile the run: increasing times, every control sample among them, the
  state at a sample step equal to the recorded sample, as many rows as a run cut into
  one-sample chunks records (the buffer grows without losing a row).
"""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

import scoutsim
import scoutsim.simulation.engine
from scoutsim._core.model import layout as L
from scoutsim._core.model.packing import robot_array

_TOOL = Path(__file__).resolve().parents[3] / "tools" / "derive_eom.py"


def _sym():
    spec = importlib.util.spec_from_file_location("derive_eom_for_recording", _TOOL)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def run_ii():
    return scoutsim.simulate(duration=3.0, model="II", record_steps=True)


def test_recording_steps_changes_nothing(run_ii):
    plain = scoutsim.simulate(duration=3.0, model="II")
    for name in ("t", "state", "aux", "modes", "events", "event_states"):
        np.testing.assert_array_equal(getattr(run_ii, name), getattr(plain, name), err_msg=name)
    assert plain.steps is None


def test_every_event_has_its_states(run_ii):
    es = run_ii.event_states
    assert es.shape == (len(run_ii.events), 2, L.NS)
    assert np.isfinite(es).all()
    kinds = run_ii.events[:, L.EVR_KIND]
    ctrl = np.isin(kinds, [L.EK_CTRL_TOUCHDOWN, L.EK_CTRL_LIFTOFF, L.EK_CTRL_SWEEP])
    assert ctrl.any()
    np.testing.assert_array_equal(es[ctrl, L.EVS_BEFORE], es[ctrl, L.EVS_AFTER])
    # a controller record at sample k carries that sample's state before settling
    k = np.rint(run_ii.events[ctrl, L.EVR_T] / 1e-3).astype(int)
    assert np.array_equal(run_ii.t[k], run_ii.events[ctrl, L.EVR_T])


def test_touchdown_states_toe_on_ground_configuration_kept_energies_logged(run_ii):
    sym = _sym()
    robot = scoutsim.RobotParameters()
    prm = sym.params_from_robot(robot, gears=True)
    P = robot_array(robot, "II")
    ev, es = run_ii.events, run_ii.event_states
    td = np.flatnonzero(ev[:, L.EVR_KIND] == L.EK_TOUCHDOWN)
    assert len(td) >= 10
    for j in td:
        before, after = es[j, L.EVS_BEFORE], es[j, L.EVS_AFTER]
        leg = int(ev[j, L.EVR_LEG])
        sL = (2 * leg - 1) * P[L.P_L]

        def toe_height(s, leg=leg, sL=sL):
            th, phi, ll = s[L.ITH], s[L.IPHB + leg], s[L.IL_B + leg]
            return s[L.IY] + sL * math.sin(th) - ll * math.cos(th + phi)

        # located to the event tolerance, then the pinned toe is put on the ground by its
        # leg length alone: the configuration is kept, the other leg's length too
        assert abs(toe_height(before)) < 1e-9, j
        assert abs(toe_height(after)) < 1e-14, j
        np.testing.assert_array_equal(after[: L.NQ], before[: L.NQ])
        assert after[L.IL_B + 1 - leg] == before[L.IL_B + 1 - leg]
        kin = []
        for state, col in ((before, L.EVR_E_BEFORE), (after, L.EVR_E_AFTER)):
            q, dq, l = state[: L.NQ], state[L.NQ : 2 * L.NQ], state[L.IL_B : L.IL_B + 2]
            kin.append(sym.kinetic_energy(q, dq, prm))
            e = kin[-1] + sym.potential_energy(q, l, prm)
            assert e == pytest.approx(ev[j, col], rel=1e-10), (j, col)
        # the kinetic energy the impact dissipated (logged as v3) is the drop between the
        # two states, when this is the only touchdown at that instant
        alone = (
            np.sum((ev[:, L.EVR_T] == ev[j, L.EVR_T]) & (ev[:, L.EVR_KIND] == L.EK_TOUCHDOWN)) == 1
        )
        if alone:
            assert kin[0] - kin[1] == pytest.approx(ev[j, L.EVR_V3], rel=1e-9, abs=1e-12)


def test_steps_tile_the_run(run_ii):
    st = run_ii.steps
    assert st.shape[1] == L.NSTEPREC
    t = st[:, L.STP_T]
    assert np.all(np.diff(t) >= 0.0) and t[-1] == run_ii.t_end
    # every control period ends with a step exactly at the next sample time
    on_grid = np.isin(run_ii.t[1:], t)
    assert on_grid.all()
    # a 1 kHz run of 3 s at the default tolerance takes more than one step per period
    assert len(st) > len(run_ii.t)
    modes = st[:, L.STP_CONTACT_B : L.STP_CONTACT_B + 2]
    assert set(np.unique(modes)) <= set(range(len(L.CONTACT_NAMES)))


@pytest.mark.parametrize("model", ["II", "I"])
def test_a_sample_is_the_last_step_unless_settling_changed_a_mode_there(run_ii, model):
    """At a sample the recorded state is bit for bit the end state of the last integrator
    step, except where settling the new command changed a plant mode at that sample (a
    transition logged at the sample time; the new mode projects the state). Measured: the
    3 s Model II run has no such sample, the 3 s Model I run one (a slide start moving a
    leg length at 2.941 s)."""
    r = run_ii if model == "II" else scoutsim.simulate(duration=3.0, model="I", record_steps=True)
    st = r.steps
    idx = np.searchsorted(st[:, L.STP_T], r.t[1:], side="right") - 1
    same = np.all(st[idx, L.STP_STATE : L.STP_STATE + L.NS] == r.state[1:], axis=1)
    controller = [L.EK_CTRL_TOUCHDOWN, L.EK_CTRL_LIFTOFF, L.EK_CTRL_SWEEP]
    plant = r.events[~np.isin(r.events[:, L.EVR_KIND], controller), L.EVR_T]
    settled_here = np.isin(r.t[1:], plant)
    assert np.all(same | settled_here), r.t[1:][~(same | settled_here)]


def test_step_recording_survives_chunking_and_buffer_growth(monkeypatch):
    whole = scoutsim.simulate(duration=1.5, model="I", record_steps=True, chunk_seconds=1.5)
    chunked = scoutsim.simulate(duration=1.5, model="I", record_steps=True, chunk_seconds=0.001)
    np.testing.assert_array_equal(whole.steps, chunked.steps)
    np.testing.assert_array_equal(whole.state, chunked.state)
    # a buffer with room for 16 steps beyond the headroom grows after the first periods
    monkeypatch.setattr(scoutsim.simulation.engine.HybridEngine, "STEP_ROWS", 16)
    grown = scoutsim.simulate(duration=1.5, model="I", record_steps=True)
    assert len(grown.steps) > 16
    np.testing.assert_array_equal(grown.steps, whole.steps)
    assert len(whole.steps) == whole.stats["steps"]  # (this run has no zero-length event step)


def test_saved_result_keeps_event_states_and_steps(run_ii, tmp_path):
    p = run_ii.save(tmp_path / "r.npz")
    back = scoutsim.SimulationResult.load(p)
    np.testing.assert_array_equal(back.event_states, run_ii.event_states)
    np.testing.assert_array_equal(back.steps, run_ii.steps)
