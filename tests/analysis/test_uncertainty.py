"""Sobol' indices (scoutsim.analysis.uncertainty.sobol) against the closed forms of two
standard test functions, Ishigami and Sobol's G-function; an input that does not enter
the model (a function's, and the belt stiffness in Model I, which has no belt) has total
index 0; the uncertain parameters' distributions, allowed ranges and the robot file's
[uncertainty] section (scoutsim.analysis.uncertainty.uncertain_parameters)."""

import math

import numpy as np
import pytest

from scoutsim.analysis.uncertainty import (
    BOUNDS,
    GAIT_METRICS,
    METRICS,
    UncertainParameter,
    check_parameters,
    parse_parameter,
    read_uncertainty,
    sobol_indices,
    uncertainty_study,
)
from scoutsim.analysis.uncertainty import study as study_module
from scoutsim.analysis.uncertainty.study import MIN_BASE_OUTCOMES, UncertaintyResult
from scoutsim.parameters import ParameterError, load_parameters

#: base sample size of the closed-form checks: n (d + 2) evaluations of a cheap function
N_CLOSED_FORM = 4096
#: the estimate must lie within this many half-widths of its 95% bootstrap interval of
#: the exact value: 1.5 half-widths is about 3 standard errors (half-width = 1.96 SE)
WITHIN_HALF_WIDTHS = 1.5
#: and the interval must be narrow enough for that to say something
MAX_HALF_WIDTH = 0.05


def _ishigami(x, a=7.0, b=0.1):
    return np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2 + b * x[:, 2] ** 4 * np.sin(x[:, 0])


def _ishigami_exact(a=7.0, b=0.1):
    """Ishigami & Homma (1990) on [-pi, pi]^3: the partial variances in closed form."""
    pi = math.pi
    v1 = 0.5 * (1 + b * pi**4 / 5) ** 2
    v2 = a**2 / 8
    v13 = 8 * b**2 * pi**8 / 225
    v = v1 + v2 + v13
    return np.array([v1, v2, 0.0]) / v, np.array([v1 + v13, v2, v13]) / v


def _check_against(ix, s1, st):
    for est, half, exact in ((ix.S1[0], ix.S1_conf[0], s1), (ix.ST[0], ix.ST_conf[0], st)):
        assert np.all(half < MAX_HALF_WIDTH), half
        assert np.all(np.abs(est - exact) <= WITHIN_HALF_WIDTHS * half + 1e-12), (est, exact, half)


def test_ishigami_indices_agree_with_the_closed_form():
    s1, st = _ishigami_exact()
    # (the closed form gives the textbook values: the formulas are the right ones)
    assert s1 == pytest.approx([0.3139, 0.4424, 0.0], abs=1e-4)
    assert st == pytest.approx([0.5576, 0.4424, 0.2437], abs=1e-4)
    ix = sobol_indices(_ishigami, [(-math.pi, math.pi)] * 3, n=N_CLOSED_FORM, seed=3)
    _check_against(ix, s1, st)


def test_g_function_indices_agree_with_the_closed_form():
    """Sobol's G-function, prod (|4 x_i - 2| + a_i) / (1 + a_i) on [0, 1]^d: partial
    variances V_i = 1 / (3 (1 + a_i)^2), V = prod (1 + V_i) - 1."""
    a = np.array([0.0, 1.0, 4.5, 9.0, 99.0])

    def g(x):
        return np.prod((np.abs(4 * x - 2) + a) / (1 + a), axis=1)

    vi = 1 / (3 * (1 + a) ** 2)
    v = np.prod(1 + vi) - 1
    s1 = vi / v
    st = np.array([vi[i] * np.prod(np.delete(1 + vi, i)) for i in range(len(a))]) / v
    ix = sobol_indices(g, [(0.0, 1.0)] * len(a), n=N_CLOSED_FORM, seed=5)
    _check_against(ix, s1, st)


def test_an_input_that_does_not_enter_has_indices_exactly_zero():
    ix = sobol_indices(lambda x: x[:, 0] ** 2 + 0.0 * x[:, 1], [(0, 1), (0, 1)], n=64, seed=1)
    assert ix.S1[0, 1] == 0.0 and ix.ST[0, 1] == 0.0
    assert ix.S1_conf[0, 1] == 0.0 and ix.ST_conf[0, 1] == 0.0
    assert ix.ST[0, 0] > 0.5


def test_the_same_seed_gives_the_same_indices_and_leaves_numpys_generator_alone():
    np.random.seed(11)
    before = np.random.random()
    np.random.seed(11)
    first = sobol_indices(_ishigami, [(-math.pi, math.pi)] * 3, n=64, seed=2)
    assert np.random.random() == before  # (the bootstrap's seeding was undone)
    second = sobol_indices(_ishigami, [(-math.pi, math.pi)] * 3, n=64, seed=2)
    for k in ("S1", "ST", "S1_low", "S1_high", "ST_low", "ST_high"):
        assert np.array_equal(getattr(first, k), getattr(second, k))


def test_belt_stiffness_has_total_index_zero_in_model_i(tmp_path):
    """Model I's hip is the motor through an ideal gearbox, without the belt: the belt
    stiffness changes nothing, so its samples give bit-identical runs and its indices
    are exactly 0 for every metric, while the touchdown angle's are not."""
    params = [
        parse_parameter("controller.touchdown_angle_front_deg=20:22"),
        parse_parameter("robot.belt_stiffness=300:500"),
    ]
    res = uncertainty_study(params, n=8, model="I", duration=4.5, workers=1, out=tmp_path)
    belt = np.array([r["robot.belt_stiffness"] for r in res.rows])
    assert np.ptp(belt) > 100  # (the belt stiffness did vary)
    assert res.share_not_bounding() == 0.0
    assert set(res.indices) == set(GAIT_METRICS) and res.not_computed == {
        BOUNDS: "every sample bounds"
    }
    for metric, ix in res.indices.items():
        assert ix.ST[0, 1] == 0.0 and ix.S1[0, 1] == 0.0 and ix.ST_conf[0, 1] == 0.0, metric
    assert res.indices["mean_speed_m_s"].ST[0, 0] > 0
    lines = (tmp_path / "indices.csv").read_text().splitlines()
    assert lines[0] == "metric,parameter,S1,S1_conf,ST,ST_conf"
    assert len(lines) == 1 + 2 * len(GAIT_METRICS)


def test_gait_metrics_are_not_computed_when_some_samples_do_not_bound():
    """A run that falls is counted (share not bounding), not dropped: the indicator's
    indices are computed, a gait metric's are not, with the reason."""
    params = [parse_parameter("controller.touchdown_angle_front_deg=12:28")]
    res = uncertainty_study(params, n=16, model="I", duration=4.5, workers=1)
    share = res.share_not_bounding()
    assert 0 < share < 1
    assert set(res.indices) == {BOUNDS}
    n_not = round(share * len(res.rows))
    for m in GAIT_METRICS:
        assert res.not_computed[m].startswith(f"{n_not} of {len(res.rows)} samples do not bound")
    assert res.summary()["share_not_bounding"] == share


def test_one_legs_value_has_the_fields_allowed_range_and_is_one_field_with_it():
    """A per-leg field's one leg is drawn within the field's allowed range (a normal
    truncated at zero stiffness) and is refused beside the field itself."""
    front = parse_parameter("robot.leg_stiffness.front=normal:100:400")
    x = front.values(np.linspace(0.001, 0.999, 50))
    assert np.all(x > 0.0)
    with pytest.raises(ValueError, match="low = -5 is not allowed"):
        parse_parameter("robot.leg_stiffness.back=-5:10")
    both = parse_parameter("robot.leg_stiffness=3000:3800")
    with pytest.raises(ValueError, match="set the same field"):
        check_parameters([front, both])
    check_parameters([front, parse_parameter("robot.leg_stiffness.back=3000:3800")])


def test_runs_too_short_to_bound_steadily_are_named_as_such():
    """Runs that end without falling but before seven steady strides do not count as
    bounding: the reason says so and names the duration, not the ranges."""
    params = [parse_parameter("robot.leg_stiffness=3400:3600")]
    res = uncertainty_study(params, n=2, model="II", duration=2.0, workers=1)
    assert res.share_not_bounding() == 1.0
    assert all(r["outcome"] == "completed" for r in res.rows)
    why = res.not_computed["mean_speed_m_s"]
    assert f"{len(res.rows)} of them ran to the end without falling but with fewer than 7" in why
    assert "longer duration" in why and "narrow the ranges" not in why


def test_uniform_and_normal_parameters_stay_in_the_allowed_range():
    u = np.linspace(0.0, 1.0, 1001)[1:-1]
    p = parse_parameter("controller.touchdown_angle_front_deg=normal:88:5")
    x = p.values(u)
    assert np.all(x < 90.0) and np.all(np.diff(x) > 0)  # truncated, still increasing
    q = parse_parameter("robot.leg_stiffness=normal:3000:100")  # far from its ends
    assert np.median(q.values(u)) == pytest.approx(3000.0, rel=1e-6)
    assert np.std(q.values(u)) == pytest.approx(100.0, rel=0.02)
    w = parse_parameter("friction_coefficient=0.5:1.0")
    assert w.values(np.array([0.0, 0.5])) == pytest.approx([0.5, 0.75])


@pytest.mark.parametrize(
    "text,words",
    [
        ("controller.touchdown_angle_front_deg=80:95", ["high = 95", "(-90, 90)"]),
        ("robot.leg_stiffness=normal:-5:1", ["mean = -5", "robot.leg_stiffness", "(0,"]),
        ("friction_coefficient=-1:1", ["low = -1", "(0, inf)"]),
        ("robot.leg_stiffness=3:2", ["low = 3 must be below high = 2"]),
        ("robot.leg_stiffnes=1:2", ["did you mean 'robot.leg_stiffness'"]),
        ("robot.leg_stiffness=uniform:1:2", ["NAME=LOW:HIGH or NAME=normal:MEAN:SD"]),
        ("robot.leg_stiffness=normal:3000:0", ["sd = 0"]),
    ],
)
def test_a_bad_parameter_is_refused_naming_the_field_and_its_range(text, words):
    with pytest.raises(ValueError) as exc:
        parse_parameter(text)
    for w in words:
        assert w in str(exc.value)


def test_the_robot_files_uncertainty_section_is_read_with_its_units(tmp_path):
    f = tmp_path / "robot.toml"
    f.write_text(
        "[robot]\nleg_stiffness = 3500.0\n"
        "[uncertainty]\n"
        'belt_stiffness = { low = 6.0, high = 8.0, unit = "N m/deg" }\n'
        'touchdown_angle_front = { mean = 21.0, sd = 0.5, unit = "deg" }\n'
        "friction_coefficient = { low = 0.6, high = 1.0 }\n"
    )
    params = read_uncertainty(f)
    assert [p.name for p in params] == [
        "robot.belt_stiffness",
        "controller.touchdown_angle_front_deg",
        "friction_coefficient",
    ]
    per_deg = 180.0 / math.pi  # N m/deg -> N m/rad
    assert params[0] == UncertainParameter(
        "robot.belt_stiffness", "uniform", 6 * per_deg, 8 * per_deg
    )
    assert params[1] == UncertainParameter(
        "controller.touchdown_angle_front_deg", "normal", 21.0, 0.5
    )
    robot, _ = load_parameters(f)  # (the parameter loaders skip the section)
    assert robot.leg_stiffness == 3500.0


@pytest.mark.parametrize(
    "entry,words",
    [
        (
            "leg_stifness = { low = 1.0, high = 2.0 }",
            ["leg_stifness", "did you mean 'leg_stiffness'"],
        ),
        ('leg_stiffness = { low = 1.0, high = 2.0, unit = "deg" }', ["unit 'deg'", "N/m"]),
        ("leg_stiffness = { low = 1.0, sd = 2.0 }", ["low and high", "mean and sd"]),
        (
            'touchdown_angle_back = { low = 80.0, high = 100.0, unit = "deg" }',
            ["high = 100", "(-90, 90)"],
        ),
        ("leg_stiffness = 5.0", ["must be a table"]),
    ],
)
def test_a_bad_uncertainty_entry_is_refused_naming_the_field(tmp_path, entry, words):
    f = tmp_path / "robot.toml"
    f.write_text("[uncertainty]\n" + entry + "\n")
    with pytest.raises(ParameterError) as exc:
        read_uncertainty(f)
    for w in words:
        assert w in str(exc.value)


def test_a_friction_sample_sets_the_floor_of_its_run():
    """``friction_coefficient`` is not a robot field: the sample's value becomes the run's
    floor, as the sweep's own ``friction_coefficient`` setting would."""
    from scoutsim.analysis.sweep import sweep_task
    from scoutsim.analysis.uncertainty import uncertainty_task
    from scoutsim.parameters import ControllerParameters, RobotParameters

    task = {
        "model": "I",
        "duration": 1.0,
        "robot": RobotParameters(),
        "controller": ControllerParameters(),
        "initial_state": None,
        "friction_coefficient": 1.0,
    }
    point = {"controller.touchdown_angle_front_deg": 21.0}
    sampled = uncertainty_task(task | {"point": point | {"friction_coefficient": 0.2}})
    floor = sweep_task(task | {"point": point, "friction_coefficient": 0.2})
    default = sweep_task(task | {"point": point})
    assert sampled.pop("friction_coefficient") == 0.2
    assert sampled == floor
    assert floor["max_friction_ratio"] != default["max_friction_ratio"]


def test_two_names_of_one_field_and_controller_fields_of_a_controller_object_are_refused():
    with pytest.raises(ValueError, match="set the same field"):
        uncertainty_study(
            [
                parse_parameter("controller.touchdown_angle_front_deg=20:22"),
                parse_parameter("controller.touchdown_angle_front=0.35:0.38"),
            ],
            n=2,
        )
    from scoutsim.control import BoundingController

    with pytest.raises(ValueError, match="not allowed with a controller object"):
        uncertainty_study(
            [parse_parameter("controller.touchdown_angle_front_deg=20:22")],
            n=2,
            controller=BoundingController(),
        )


def test_a_range_reaching_far_from_scout_ii_is_warned_of_once_not_per_run():
    from scoutsim.parameters import ImplausibleParameterWarning

    with pytest.warns(ImplausibleParameterWarning) as record:
        uncertainty_study(
            [parse_parameter("robot.leg_stiffness=3000:300000")],
            n=4,
            model="I",
            duration=0.2,
            workers=1,
        )
    implausible = [w for w in record if issubclass(w.category, ImplausibleParameterWarning)]
    assert len(implausible) == 1 and "leg_stiffness" in str(implausible[0].message)


def _indicator_result(bounding: np.ndarray, n: int, d: int) -> UncertaintyResult:
    """A study's result whose runs bound where ``bounding`` says (rows A, B, AB_1..AB_d)."""
    params = [parse_parameter(f"robot.leg_stiffness={3000 + i}:{3500 + i}") for i in range(d)]
    rows = [{"steady_bounding": bool(b)} for b in bounding]
    return UncertaintyResult(parameters=params, rows=rows, n=n)


@pytest.mark.parametrize(
    "failing, computed",
    [
        ("ab only", False),  # the indicator does not vary over A and B
        ("one in B", False),  # one base row: indices and intervals rest on it
        ("enough", True),
    ],
)
def test_the_indicators_indices_need_each_outcome_in_enough_base_samples(failing, computed):
    """The Saltelli estimator divides by the indicator's variance over the base samples A
    and B: failures only in the AB rows, or in one base row, give indices of 0 or 1 with
    intervals of zero width that rest on single rows; those are refused with the reason,
    and computed once each outcome holds for MIN_BASE_OUTCOMES base samples."""
    n, d = 32, 2
    b = np.ones(n * (d + 2))
    if failing == "ab only":
        b[2 * n + 3] = b[3 * n + 7] = 0.0
    elif failing == "one in B":
        b[n + 4] = b[2 * n + 4] = 0.0
    else:
        b[:MIN_BASE_OUTCOMES] = b[n : n + MIN_BASE_OUTCOMES] = 0.0
        b[2 * n : 2 * n + MIN_BASE_OUTCOMES] = 0.0
    res = _indicator_result(b, n, d)
    study_module._indices(res, seed=0)
    assert (BOUNDS in res.indices) == computed
    if not computed:
        assert "base samples (A and B)" in res.not_computed[BOUNDS]
    else:
        assert np.all(np.isfinite(res.indices[BOUNDS].ST))


def test_with_energy_the_cost_of_transport_is_a_metric_and_the_gait_is_the_same():
    """energy=True accounts for every run's energy: the cost of transport joins the
    metrics (indices and samples.parquet), and the gait metrics are the study's without
    it, bit for bit (the accounting does not change a run's trajectory)."""
    params = [
        parse_parameter("controller.touchdown_angle_front_deg=20:22"),
        parse_parameter("robot.belt_stiffness=300:500"),  # (no belt in Model I: no effect)
    ]
    plain = uncertainty_study(params, n=8, model="I", duration=4.5, workers=1)
    costed = uncertainty_study(params, n=8, model="I", duration=4.5, workers=1, energy=True)
    assert plain.metrics == METRICS
    assert costed.metrics == (*METRICS, "cost_of_transport")
    cot = costed.metric("cost_of_transport")
    assert np.all(np.isfinite(cot)) and np.all(cot > 0)  # every sample bounds here
    assert "cost_of_transport" in costed.indices
    assert costed.indices["cost_of_transport"].ST[0, 1] == 0.0  # the belt's
    assert costed.indices["cost_of_transport"].ST[0, 0] > 0.0  # the touchdown angle's
    assert "cost_of_transport" in costed.samples_columns()
    for m in GAIT_METRICS:
        assert np.array_equal(plain.metric(m), costed.metric(m)), m
        assert np.array_equal(plain.indices[m].ST, costed.indices[m].ST), m
