"""The paper's reported results (SPEC.md 9), checked on the default Scout II configuration.

Floor: Coulomb friction mu = 0.8 (carpet; see docs/model.md for why no-slip is the
assumption that fails). Default start: scoutsim.default_initial_state().
"""


import numpy as np
import pytest

import scoutsim

MU = 0.8


@pytest.fixture(scope="module")
def model_ii():
    return scoutsim.simulate(duration=20.0, model="II", friction_coefficient=MU)


def test_model_ii_bounds_steadily_for_20_s(model_ii):
    g = model_ii.gait()
    assert model_ii.outcome == "completed"
    assert g.n_steady_strides >= 7
    assert g.is_steady_bounding()


def test_model_ii_speed_near_paper_1_3_m_s(model_ii):
    assert 1.0 <= model_ii.gait().mean_speed_m_s <= 1.6


def test_model_ii_belt_deflection_below_8_deg(model_ii):
    for leg in ("back", "front"):
        assert np.max(np.abs(np.degrees(model_ii.belt_deflection(leg)))) < 8.0


def test_motors_saturated_most_of_stance_retraction(model_ii):
    g = model_ii.gait()
    for leg in ("back", "front"):
        assert g.motor_saturation_fraction(model_ii, leg) > 0.5


def test_bounding_is_a_gait_both_legs_alternate(model_ii):
    g = model_ii.gait()
    for st in g.steady_strides:
        assert 0.2 < st.duty_factor_back < 0.8 and 0.2 < st.duty_factor_front < 0.8
        assert st.pitch_max_deg > 0 > st.pitch_min_deg


@pytest.mark.parametrize("model", ["I", "ideal"])
def test_model_i_and_ideal_do_not_reach_cyclic_motion_from_the_default_start(model):
    """Paper: without saturation the models do not converge to cyclic motion; Model I may
    not reach it with the experimental gains."""
    r = scoutsim.simulate(duration=10.0, model=model, friction_coefficient=MU)
    assert not r.gait().is_steady_bounding()
