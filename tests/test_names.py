"""The named codes of scoutsim.names agree with the compiled core's plain integers
(scoutsim._core.model.layout): every value, every label, and nothing missing on either side."""

import pytest

from scoutsim import names as N
from scoutsim._core.model import layout as L


def test_legs_agree_with_the_layout():
    assert [(m.name, int(m)) for m in N.Leg] == [("BACK", L.BACK), ("FRONT", L.FRONT)]
    assert N.LEG_NAMES == L.LEG_NAMES
    assert [m.label for m in N.Leg] == list(L.LEG_NAMES)


def test_leg_states_agree_with_the_layout():
    assert {m.name: int(m) for m in N.LegState} == {
        "FLIGHT": L.LS_FLIGHT, "RETRACTION": L.LS_RETRACTION, "BRAKE": L.LS_BRAKE}
    assert N.LEG_STATE_NAMES == L.LEG_STATE_NAMES
    assert tuple(m.label for m in N.LegState) == L.LEG_STATE_NAMES


def test_contact_modes_agree_with_the_layout():
    assert {m.name: int(m) for m in N.ContactMode} == {
        "FLIGHT": L.FLIGHT, "STICK": L.STICK, "SLIDE": L.SLIDE, "STRUT": L.STRUT}
    assert N.CONTACT_NAMES == L.CONTACT_NAMES
    assert tuple(m.label for m in N.ContactMode) == L.CONTACT_NAMES


def test_motor_joint_modes_agree_with_the_layout():
    assert {m.name: int(m) for m in N.MotorJointMode} == {
        "SLIP_NEG": L.SLIP_NEG, "STUCK": L.STUCK, "SLIP_POS": L.SLIP_POS}


def test_models_agree_with_the_layout():
    assert {m.label: int(m) for m in N.Model} == L.MODEL_NAMES
    assert N.MODEL_LABELS == L.MODEL_LABELS
    assert {m.label: m.display_name for m in N.Model} == L.MODEL_LABELS
    assert N.Model.from_label("II") is N.Model.II
    assert N.Model.from_label("passive") is N.Model.PASSIVE


def test_event_kinds_agree_with_the_layout():
    assert N.EVENT_KIND_NAMES == L.EVENT_KIND_NAMES
    assert {int(m): m.label for m in N.EventKind} == L.EVENT_KIND_NAMES
    codes = {name[3:]: v for name, v in vars(L).items() if name.startswith("EK_")}
    renamed = {"CTRL_TOUCHDOWN": "CONTROLLER_TOUCHDOWN", "CTRL_LIFTOFF": "CONTROLLER_LIFTOFF",
               "CTRL_SWEEP": "CONTROLLER_SWEEP"}
    assert {renamed.get(k, k): v for k, v in codes.items()} == \
        {m.name: int(m) for m in N.EventKind}


def test_violation_bits_agree_with_the_layout():
    bits = {name[2:]: v for name, v in vars(L).items()
            if name.startswith("V_") and isinstance(v, int)}
    assert bits == {m.name: int(m) for m in N.Violation}
    assert list(N.VIOLATION_NAMES.items()) == list(L.VIOLATION_NAMES.items())


def test_members_are_their_codes():
    """A member compares, indexes and formats as its integer code."""
    assert N.LegState.BRAKE == 2 and ("a", "b", "c")[N.LegState.BRAKE] == "c"
    assert f"{N.Leg.FRONT}" == "1"
    assert N.EventKind.from_label("liftoff") == L.EK_LIFTOFF


def test_leg_index():
    assert [N.leg_index(x) for x in ("back", "front", 0, 1, N.Leg.BACK, N.Leg.FRONT)] == \
        [0, 1, 0, 1, 0, 1]
    assert type(N.leg_index(N.Leg.FRONT)) is int
    for bad in ("left", 2, -1, True, None, 1.0, [0]):
        with pytest.raises(ValueError, match="leg"):
            N.leg_index(bad)


def test_unknown_label():
    with pytest.raises(ValueError, match="'III' is not allowed"):
        N.Model.from_label("III")
