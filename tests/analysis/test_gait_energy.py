"""What a gait costs (scoutsim.analysis.stride_energy per stride, the gait summary, the energy
accessors of scoutsim.result.simulation_result): the cumulative energy of every flow at every sample, the power
series, the energy of each stride and the cost of transport.

Laws checked: the accumulator recorded at the samples ends at the run's totals and never
decreases for a dissipation; the strides' energies add up to the run's; each stride's
mechanical balance (hip work = friction + dampers + impacts + change of mechanical energy)
closes to the integration tolerance; the instantaneous electrical power of the motor
equation integrates to the accumulated energy; the cost of transport is E / (m g d) from the
position and the robot's mass; the series survive saving and loading bit for bit.
"""

import json
import math

import numpy as np
import pytest

import scoutsim
from scoutsim import IntegratorSettings, RobotParameters
from scoutsim._core.model import layout as L

#: flows that only ever take energy out (each a square or a friction force against its
#: sliding velocity: R_A i^2, b w^2, c l'^2, -F_t v_toe)
DISSIPATIONS = (
    "copper",
    "joint_viscous",
    "joint_coulomb",
    "belt_damper",
    "leg_damper",
    "toe_slide",
)


@pytest.fixture(scope="module")
def run_II():
    """4 s of Model II bounding (the steady strides start after the 2 s transient), with
    the reference integrator: its balance closes to ~1e-8 of the input."""
    return scoutsim.simulate(
        duration=4.0, model="II", energy=True, integrator=IntegratorSettings(method="dopri5")
    )


@pytest.fixture(scope="module")
def run_I_noslip():
    """3 s of Model I on a no-slip floor: its touchdowns are impacts that lose energy."""
    return scoutsim.simulate(duration=3.0, model="I", energy=True, friction_coefficient=math.inf)


@pytest.fixture(scope="module")
def run_default():
    """4 s of Model II with the default integrator (ARK3), with and without accounting."""
    return (
        scoutsim.simulate(duration=4.0, model="II", energy=True),
        scoutsim.simulate(duration=4.0, model="II"),
    )


def test_cumulative_series_ends_at_the_run_totals_and_dissipations_never_decrease(run_II):
    r = run_II
    assert r.energy_series.shape == (len(r.t), L.NEN)
    assert np.all(r.energy_series[0] == 0.0)  # nothing accumulated at the start
    for leg in L.LEG_NAMES:
        for name in L.EN_LEG_NAMES:
            assert r.cumulative_energy(name, leg)[-1] == r.energy_flows[f"{name}_{leg}"]
        for name in DISSIPATIONS:
            assert np.all(np.diff(r.cumulative_energy(name, leg)) >= -1e-12), (name, leg)
    assert r.cumulative_energy("battery_loss")[-1] == r.energy_flows["battery_loss"]
    # a group is the sum of its flows, both legs the sum of the two
    both = r.cumulative_energy("transmission")
    parts = sum(
        r.cumulative_energy(n, leg) for n in ("conversion", "gear_loss") for leg in L.LEG_NAMES
    )
    np.testing.assert_allclose(both, parts, rtol=1e-12, atol=1e-9)


def test_stride_energies_add_up_to_the_run_totals(run_II, run_I_noslip):
    """Over the strides and the pieces of the run before and after them, every energy adds
    up to the run's total (the touchdown impacts too, on a floor where they lose energy)."""
    for r in (run_II, run_I_noslip):
        strides = r.strides
        assert len(strides) >= 5
        t = r.t
        first = int(np.searchsorted(t, strides[0].energy_t_start))
        last = int(np.searchsorted(t, strides[-1].energy_t_end))
        for field, name in (
            ("electrical_energy_j", "electrical"),
            ("copper_loss_j", "copper"),
            ("hip_work_j", "hip_work"),
        ):
            total = sum(r.energy_flows[f"{name}_{leg}"] for leg in L.LEG_NAMES)
            e = r.cumulative_energy(name)
            inside = sum(s[field] for s in strides)
            assert inside + e[first] + (total - e[last]) == pytest.approx(total, rel=1e-12)
        imp = r.impacts()
        outside = imp[(imp[:, 0] < t[first]) | (imp[:, 0] >= t[last]), 4].sum()
        assert sum(s.impact_loss_j for s in strides) + outside == pytest.approx(
            r.energy_flows["impacts"], rel=1e-12
        )
    assert run_I_noslip.energy_flows["impacts"] > 1.0  # the no-slip floor's impacts
    assert all(s.impact_loss_j > 0 for s in run_I_noslip.strides)


def test_stride_table_has_the_stride_energies(run_II):
    from scoutsim.analysis.gait import stride_table

    cols = stride_table(run_II)
    strides = run_II.strides
    assert len(cols["electrical_energy_j"]) == len(strides)
    assert cols["cost_of_transport"][-1] == strides[-1].cost_of_transport
    assert "electrical_energy_j" not in stride_table(scoutsim.simulate(duration=1.0, model="II"))


def test_stride_energy_balance_closes(run_II, run_I_noslip):
    """Per stride: electrical = copper + transmission + hip work (term by term), and
    hip work = friction and dampers + constraint work + impacts + change of mechanical
    energy, to 100 x the integrator's rtol (1e-8) of the stride's input, the margin the
    transition audit allows the whole run (measured: 8.3e-11 for Model II, 4.5e-10 for
    Model I on the no-slip floor)."""
    for r in (run_II, run_I_noslip):
        rtol = r.provenance["integrator"]["rtol"]
        assert rtol == 1e-8
        for s in r.strides:
            assert s.copper_loss_j + s.transmission_loss_j + s.hip_work_j == pytest.approx(
                s.electrical_energy_j, rel=1e-12
            )
            assert abs(s.energy_residual_j) <= 100 * rtol * s.electrical_energy_j, s.index
            # the residual is what the stride's mechanical balance leaves: the change of
            # mechanical energy read from the recorded samples
            i, j = np.searchsorted(r.t, [s.energy_t_start, s.energy_t_end])
            d_mech = r.energy[j] - r.energy[i]
            constraint = r.cumulative_energy("constraint")[j] - r.cumulative_energy("constraint")[i]
            left = s.hip_work_j - s.friction_loss_j - constraint - s.impact_loss_j - d_mech
            assert left == pytest.approx(s.energy_residual_j, rel=1e-9, abs=1e-12)


class _HeldTorques:
    """A controller that holds the same hip torques at every sample [N m]."""

    def command(self, t, sensors):
        return (2.0, -1.5)


@pytest.mark.parametrize("model", ["I", "II"])
def test_electrical_power_integrates_to_the_accumulated_energy(model):
    """The electrical power of the motor equation at the samples, integrated by the
    trapezoid rule at 1 kHz, gives the energy the integrator accumulated on its own steps.
    With the torques held (no jump of the current at a sample) the power is smooth between
    the events, and the trapezoid's error is its h^2 term and the kinks at the events:
    measured 9.2e-5 (Model II) and 1.0e-5 (Model I) of the energy over 0.5 s, asserted
    below 2e-4 (the accumulated energies are within 9e-6 and 7e-8 of a DOPRI5 rtol 1e-12
    reference)."""
    r = scoutsim.simulate(duration=0.5, model=model, energy=True, controller=_HeldTorques())
    p = r.electrical_power()
    e = r.cumulative_energy("electrical")
    trapezoid = np.sum(0.5 * (p[1:] + p[:-1]) * np.diff(r.t))
    assert e[-1] > 1.0
    assert abs(trapezoid - e[-1]) <= 2e-4 * e[-1]
    # per leg too, and the leg's own accumulated energy
    for leg in L.LEG_NAMES:
        pl = r.electrical_power(leg)
        el = r.cumulative_energy("electrical", leg)
        assert abs(np.sum(0.5 * (pl[1:] + pl[:-1]) * np.diff(r.t)) - el[-1]) <= 2e-4 * e[-1]


def test_electrical_power_under_the_sampled_controller(run_default):
    """Under the 1 kHz bounding controller the current jumps at every sample (the command
    is held between samples) and the recorded power is the value just after the jump, so
    the trapezoid rule misplaces half of each jump: measured 0.65-0.72 % of the electrical
    energy (Models I and II, ARK3 and DOPRI5 alike: sampling, not integration error),
    asserted below 1 %. The period means of ``power`` carry the exact energy."""
    r, _ = run_default
    p = r.electrical_power()
    e = r.cumulative_energy("electrical")
    trapezoid = np.sum(0.5 * (p[1:] + p[:-1]) * np.diff(r.t))
    assert abs(trapezoid - e[-1]) <= 0.01 * e[-1]
    mean = r.power("electrical")
    assert np.isnan(mean[-1])
    assert np.sum(mean[:-1] * np.diff(r.t)) == pytest.approx(e[-1], rel=1e-9)
    with pytest.raises(ValueError, match="ideal"):
        scoutsim.simulate(duration=0.05, model="ideal").electrical_power()


def test_cost_of_transport_is_energy_over_weight_and_distance(run_default):
    """The summary's cost of transport over the steady strides is E / (m g d): E the
    electrical energy between the samples nearest to the first steady stride's start and
    the last one's end, d the distance the torso travelled between them, m the robot's
    total mass (torso and every physical leg)."""
    r, _ = run_default
    s = r.summary()
    steady = [st for st in r.strides if st.steady]
    assert len(steady) >= 5
    i = int(np.argmin(np.abs(r.t - steady[0].t_start)))
    j = int(np.argmin(np.abs(r.t - steady[-1].t_end)))
    robot = RobotParameters()
    mass = robot.torso_mass + 2 * robot.legs_per_virtual_leg * robot.leg_mass
    energy = r.cumulative_energy("electrical")[j] - r.cumulative_energy("electrical")[i]
    distance = r.x[j] - r.x[i]
    assert s["cost_of_transport"] == pytest.approx(
        energy / (mass * robot.gravity * distance), rel=1e-12
    )
    assert s["mean_electrical_power_w"] == pytest.approx(energy / (r.t[j] - r.t[i]), rel=1e-12)
    # the whole run's terms, as the balance gives them
    b = r.energy_balance()
    assert s["electrical_energy_j"] == b.input_J
    assert s["copper_loss_j"] + s["transmission_loss_j"] + s["hip_work_j"] == pytest.approx(
        s["electrical_energy_j"], rel=1e-12
    )
    assert s["energy_residual_j"] == b.residual_J
    json.dumps(s, allow_nan=False)


def test_energy_series_saved_and_loaded_bit_for_bit(run_default, tmp_path):
    r, _ = run_default
    copies = {"npz": scoutsim.SimulationResult.load(r.save(tmp_path / "run.npz"))}
    for fmt in ("parquet", "csv"):
        r.save_tables(tmp_path / fmt, fmt=fmt)
        copies[fmt] = scoutsim.SimulationResult.load(tmp_path / fmt)
    for fmt, back in copies.items():
        assert back.energy_series.tobytes() == r.energy_series.tobytes(), fmt
        assert back.summary() == r.summary(), fmt
    w = scoutsim.SimulationResult.load(tmp_path / "parquet", t_range=(1.0, 2.0))
    assert w.energy_series.tobytes() == r.window(1.0, 2.0).energy_series.tobytes()
    k = np.searchsorted(r.t, 1.0)
    assert w.energy_series[0].tobytes() == r.energy_series[k].tobytes()  # since the start


def test_streamed_run_has_the_same_series(run_default, tmp_path):
    r, _ = run_default
    kept = scoutsim.simulate(
        duration=4.0, model="II", energy=True, stream_to=tmp_path / "s", keep_seconds=1.0
    )
    whole = scoutsim.SimulationResult.load(tmp_path / "s")
    assert whole.energy_series.tobytes() == r.energy_series.tobytes()
    n = len(kept.t)
    assert kept.energy_series.tobytes() == r.energy_series[-n:].tobytes()
    assert kept.summary()["electrical_energy_j"] == r.summary()["electrical_energy_j"]


def test_run_without_accounting_has_no_series(run_default, tmp_path):
    r_on, r = run_default
    assert r.energy_series is None and r.energy_flows is None
    # the motion is the same bit for bit
    assert r.state.tobytes() == r_on.state.tobytes()
    s = r.summary()
    for key in (
        "electrical_energy_j",
        "cost_of_transport",
        "mean_electrical_power_w",
        "copper_loss_j",
        "transmission_loss_j",
        "friction_loss_j",
        "hip_work_j",
        "energy_residual_j",
    ):
        assert s[key] is None
    assert all(st.electrical_energy_j is None for st in r.strides)
    with pytest.raises(ValueError, match="energy=True"):
        r.cumulative_energy("electrical")
    assert not any(c.startswith("cumulative_energy") for c in r.columns())
    r.save_tables(tmp_path)
    assert scoutsim.SimulationResult.load(tmp_path).energy_series is None


def test_cli_run_summary_has_the_cost_of_transport(tmp_path, capsys):
    """``scoutsim run`` accounts for the energy by default (summary.json has what the gait
    costs, the figure of a stride's power is drawn); ``--no-energy`` leaves it out."""
    from scoutsim.cli import main

    assert (
        main(["run", "--duration", "3", "--out", str(tmp_path / "on"), "--no-progress", "--plots"])
        == 0
    )
    printed = capsys.readouterr().out
    assert "cost of transport" in printed
    saved = json.loads((tmp_path / "on" / "summary.json").read_text())
    assert saved["electrical_energy_j"] > 0 and saved["cost_of_transport"] > 0
    assert (tmp_path / "on" / "stride_power.png").stat().st_size > 0
    assert (
        main(
            [
                "run",
                "--duration",
                "0.2",
                "--out",
                str(tmp_path / "off"),
                "--no-progress",
                "--no-energy",
            ]
        )
        == 0
    )
    saved = json.loads((tmp_path / "off" / "summary.json").read_text())
    assert saved["electrical_energy_j"] is None and saved["cost_of_transport"] is None
