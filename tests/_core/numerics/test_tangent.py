"""Sensitivities carried with a run (scoutsim._core.numerics.tangent).

Law checked: the derivative of the hybrid flow. The sensitivities a run carries through
its steps, located events (saltation matrices), control samples (zero-order hold) and
settlings must equal central differences of whole runs from perturbed starts, run for
run, where the flow is smooth; carrying them must not change the run.
"""

from __future__ import annotations

import copy
import dataclasses

import numpy as np
import pytest

from scoutsim._core.model.layout import EVENT_KIND_NAMES, IL_B, IL_F, NMF, NS
from scoutsim._core.numerics import tangent_work as T
from scoutsim._core.numerics.hybrid import HW_EVAL_KEPT
from scoutsim.parameters import RobotParameters
from scoutsim.simulation.engine import start_engine
from scoutsim.simulation.integrator import IntegratorSettings
from scoutsim.simulation.parameter_rows import robot_parameter_derivatives

# tight tolerances, so that differences of whole runs are accurate to ~1e-5 of scale
TIGHT = IntegratorSettings(rtol=1e-9, atol=1e-11)
# the leg lengths sit at their stops in flight: a one-sided constraint, where the flow is
# not differentiable (a shortened leg extends back, a lengthened one is held at the stop)
AT_STOP = (IL_B, IL_F)
SMOOTH_COLUMNS = [j for j in range(T.X_CS) if j not in AT_STOP]
#: the plant event kinds of Model II's first stride from the default start
PLANT_KINDS = {"touchdown", "slide_start", "stick", "liftoff", "motor_slip", "motor_stick"}


def _x(e) -> np.ndarray:
    return np.concatenate([e.s, e.mf, e.cmd, e.block.state])


def _set_x(e, x) -> None:
    # (the engine's kept evaluation is of the state it was at: evaluate afresh)
    e.hwork[HW_EVAL_KEPT] = 0.0
    e.s[:] = x[:NS]
    e.mf[:] = x[NS : NS + NMF]
    e.cmd[:] = x[T.X_CMD : T.X_CMD + 2]
    e.block.state[:] = x[T.X_CS :]


def _differences(base, k_stop: int, columns, h: float = 1e-6) -> np.ndarray:
    """Central differences of the extended state at sample ``k_stop`` with respect to the
    extended state of the engine ``base`` (not advanced), column by column."""
    x0 = _x(base)
    out = np.zeros((len(x0), len(columns)))
    for c, j in enumerate(columns):
        step = h * max(1.0, abs(x0[j]))
        ends = []
        for sign in (1.0, -1.0):
            e = copy.deepcopy(base)
            x = x0.copy()
            x[j] += sign * step
            _set_x(e, x)
            e.advance(k_stop)
            ends.append(_x(e))
        out[:, c] = (ends[0] - ends[1]) / (2.0 * step)
    return out


def _carried(base, k_stop: int, columns) -> tuple[np.ndarray, object]:
    e = copy.deepcopy(base)
    e.carry_sensitivities(np.eye(len(_x(e)))[:, columns])
    e.advance(k_stop)
    return e.sensitivities.copy(), e


def _column_errors(phi, fd) -> np.ndarray:
    """Each column's largest difference, relative to the column's largest entry (a column
    the projection zeroes, a velocity of a stuck joint, relative to the whole matrix's)."""
    scale = np.maximum(np.abs(fd).max(axis=0), 1e-6 * np.abs(fd).max())
    return np.abs(phi - fd).max(axis=0) / scale


@pytest.fixture(scope="module")
def bound_start():
    """Model II from the default start, at the tight tolerance (sample 0)."""
    return start_engine(None, 1.0, model="II", integrator=TIGHT)


def test_a_python_controller_is_refused():
    """A Python controller runs outside the compiled loop: its commands would be carried
    as constants, so the engine refuses to carry derivatives through it."""

    class Hold:
        control_period = 1e-3

        def command(self, t, sensors):
            return (0.0, 0.0)

    e = start_engine(None, 1.0, model="II", controller=Hold())
    with pytest.raises(ValueError, match="Python controller"):
        e.carry_sensitivities(np.eye(e.sensitivities.shape[0]))


def test_carrying_sensitivities_leaves_the_run_unchanged(bound_start):
    plain = copy.deepcopy(bound_start)
    plain.advance(120)
    _, carried = _carried(bound_start, 120, SMOOTH_COLUMNS)
    assert np.array_equal(plain.out_s[: plain.n_out], carried.out_s[: carried.n_out])
    assert np.array_equal(plain.ev[: plain.nev], carried.ev[: carried.nev], equal_nan=True)


def test_a_stride_of_model_ii_matches_differences_of_the_run(bound_start):
    """250 ms: flight, the back leg's touchdown (with a slide and stick), motor-joint slip and
    stick, lift-off, the front leg's touchdown; about 250 control samples."""
    phi, e = _carried(bound_start, 250, SMOOTH_COLUMNS)
    kinds = {kind for kind, _ in e.plant_events()}
    assert PLANT_KINDS <= kinds
    assert e.smoothness()["events"] >= 10
    fd = _differences(bound_start, 250, SMOOTH_COLUMNS)
    # measured: 2e-6 .. 9e-5 per column (the differences' own error at this tolerance)
    assert _column_errors(phi, fd).max() < 1e-3


def test_the_default_model_ii_integrator_carries_them_too():
    """ARK3, the default Model II integrator, whose steps treat the belt springs with a
    splitting matrix: the perturbed steps must use the run's (with a zero splitting the
    stiff belt made the carried derivatives grow by a factor of 55 per control period)."""
    start = start_engine(
        None, 1.0, model="II", integrator=IntegratorSettings(method="ark3", rtol=1e-9, atol=1e-11)
    )
    phi, e = _carried(start, 250, SMOOTH_COLUMNS)
    assert e.smoothness()["events"] >= 10
    fd = _differences(start, 250, SMOOTH_COLUMNS)
    # measured 3.7e-4 (median over the columns 3.4e-5); ARK4 1.5e-4
    assert _column_errors(phi, fd).max() < 3e-3


def test_the_jump_across_each_event_kind_matches_differences(bound_start):
    """Each plant event kind of a stride, at the control sample right after its first
    occurrence (before the stiff belt modes can damp an error out): the sensitivities
    carried from the start against differences of the run from perturbed starts. (From
    the start: its directions are those of the state's manifold; a unit perturbation of
    one coordinate mid-run is not, and the run's projection decides its fate.)"""
    ref = copy.deepcopy(bound_start)
    ref.advance(250)
    dt = float(ref.dt)
    first: dict[str, int] = {}
    for r in ref.ev[: ref.nev]:
        kind = EVENT_KIND_NAMES[int(r[1])]
        if kind in PLANT_KINDS and kind not in first:
            first[kind] = int(np.floor(r[0] / dt + 1e-9)) + 1
    assert set(first) == PLANT_KINDS
    for kind, k in sorted(first.items(), key=lambda item: item[1]):
        phi, _ = _carried(bound_start, k, SMOOTH_COLUMNS)
        fd = _differences(bound_start, k, SMOOTH_COLUMNS)
        err = _column_errors(phi, fd).max()
        assert err < 1e-3, (kind, k, err)


def test_the_ideal_actuator_stride_matches_differences():
    base = start_engine(None, 1.0, model="ideal", integrator=TIGHT)
    phi, e = _carried(base, 250, SMOOTH_COLUMNS)
    assert {"touchdown", "liftoff"} <= {kind for kind, _ in e.plant_events()}
    fd = _differences(base, 250, SMOOTH_COLUMNS)
    assert _column_errors(phi, fd).max() < 1e-3


def _engine(field: str, value: float):
    """Model II's default start at the tight tolerance with the robot field (or the
    floor's friction) ``field`` at ``value``."""
    if field == "friction_coefficient":
        return start_engine(None, 1.0, model="II", integrator=TIGHT, friction_coefficient=value)
    robot = dataclasses.replace(RobotParameters(), **{field: value})
    return start_engine(None, 1.0, model="II", integrator=TIGHT, robot=robot)


@pytest.mark.parametrize(
    "field",
    ["leg_stiffness", "belt_stiffness", "battery_voltage", "current_limit", "friction_coefficient"],
)
def test_a_parameter_column_matches_differences_of_runs(field):
    """A robot or floor parameter carried as a row of x (its derivative of the packed
    arrays by differences of the packing): the state's derivative after 250 ms against
    runs with the parameter moved."""
    floor = field == "friction_coefficient"
    value = 0.8 if floor else getattr(RobotParameters(), field)
    run = dict(model="II", integrator=TIGHT, **({field: value} if floor else {}))
    derivative = robot_parameter_derivatives([field], **run)
    base = _engine(field, value)
    nx = len(_x(base))
    seed = np.zeros((nx + 1, 1))
    seed[nx, 0] = 1.0  # the parameter's own row
    base.carry_sensitivities(seed, derivative)
    base.advance(250)
    h = 1e-6 * value
    hi, lo = _engine(field, value + h), _engine(field, value - h)
    hi.advance(250)
    lo.advance(250)
    fd = (_x(hi) - _x(lo)) / (2.0 * h)
    carried = base.sensitivities[:nx, 0]
    assert base.smoothness()["events"] >= 10
    # measured: 4e-7 .. 2e-5 (the differences' own error)
    assert np.abs(carried - fd).max() < 1e-3 * np.abs(fd).max()


def test_an_event_near_a_sample_boundary_is_reported():
    """The ideal actuator on a no-slip floor releases the back toe at a control sample (the
    new command makes the ground pull): the normal force is 0.8 us from its zero at that
    sample, so a perturbation of the start moves the lift-off across the sample boundary,
    where the sampled map jumps (differences of runs there average two branches). The
    run carrying derivatives says how close: the time from a sample to the zero of an
    event function approaching it."""
    base = start_engine(
        None, 1.0, model="ideal", integrator=TIGHT, friction_coefficient=float("inf")
    )
    _, before = _carried(base, 160, SMOOTH_COLUMNS)
    _, at = _carried(base, 161, SMOOTH_COLUMNS)
    assert before.smoothness()["sample_margin_s"] > 1e-4
    assert at.smoothness()["sample_margin_s"] < 1e-5


def test_a_touchdown_with_the_leg_just_short_of_its_stop_matches_differences(bound_start):
    """A massive leg in flight relaxes towards its stop l0 and touches down a little short
    of it: here the back leg, shortened by 2 um at the start, lands about 0.2 um short,
    less than the resets' difference step. A copy of the state moved outwards by that step
    would be clamped at the stop by the projection (a kink of the touchdown's reset map
    that the run, on the free side, does not meet), and a difference across it averages
    the two sides (about half the leg length's derivative). The column along the leg's
    length through the touchdown against central differences of runs whose step (0.5 um)
    keeps every run's leg free of its stop."""
    gap = 2e-6
    base = copy.deepcopy(bound_start)
    x0 = _x(base)
    x0[IL_B] -= gap
    _set_x(base, x0)
    touchdown = 42  # the control sample right after the back leg's touchdown
    phi, e = _carried(base, touchdown, [IL_B])
    kinds = [EVENT_KIND_NAMES[int(r[1])] for r in e.ev[: e.nev]]
    assert "touchdown" in kinds
    fd = _differences(base, touchdown, [IL_B], h=0.25 * gap)
    # measured: 8e-9 (with the copies' difference across the stop: 0.43)
    assert _column_errors(phi, fd).max() < 1e-3
