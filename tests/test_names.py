"""The named codes of scoutsim.names (the codes a run records, named for the layers above the
compiled core): every code of the core's table (scoutsim._core.model.layout) has a member,
every code a run records is a member, each family's names are unique and its labels
round-trip (``from_label(m.label) is m``), and a member is its integer code."""

import numpy as np
import pytest

import scoutsim
from scoutsim import names as N
from scoutsim._core.model import layout as L

#: every labelled enum and the table of its labels by code
LABELLED = [N.Leg, N.LegState, N.ContactMode, N.MotorJointMode, N.Model, N.EventKind]


def _table_codes(prefix):
    """The integer constants of the core's table whose names start with ``prefix``."""
    return {name: v for name, v in vars(L).items() if name.startswith(prefix) and type(v) is int}


@pytest.mark.parametrize(
    "enum, prefix",
    [(N.LegState, "LS_"), (N.EventKind, "EK_"), (N.Violation, "V_"), (N.Model, "MODEL_")],
)
def test_every_code_of_a_family_in_the_table_has_a_member(enum, prefix):
    """A code the core gains (a new ``EK_*``, ``V_*``, ...) without a member fails here."""
    codes = _table_codes(prefix)
    assert codes, prefix
    assert sorted(codes.values()) == sorted(int(m) for m in enum)


def test_contact_and_motor_joint_modes_cover_the_tables_names():
    """The contact and motor-joint modes (codes without a prefix in the table) are the
    codes their name tables name, and the core's arrays index the contact names by code."""
    assert sorted(int(m) for m in N.ContactMode) == list(range(len(L.CONTACT_NAMES)))
    assert sorted(int(m) for m in N.MotorJointMode) == sorted(L.MOTOR_JOINT_NAMES)
    assert sorted(int(m) for m in N.Leg) == list(range(len(L.LEG_NAMES)))
    assert sorted(int(m) for m in N.LegState) == list(range(len(L.LEG_STATE_NAMES)))


@pytest.mark.parametrize("enum", LABELLED + [N.Violation], ids=lambda e: e.__name__)
def test_codes_and_member_names_are_unique(enum):
    """No two members share a code (an alias would hide one of them from iteration)."""
    assert len(enum.__members__) == len(list(enum)) == len({int(m) for m in enum})


@pytest.mark.parametrize("enum", LABELLED, ids=lambda e: e.__name__)
def test_labels_are_unique_and_round_trip(enum):
    labels = [m.label for m in enum]
    assert all(isinstance(x, str) and x for x in labels)
    assert len(set(labels)) == len(labels)
    for m in enum:
        assert enum.from_label(m.label) is m


def test_label_tables_name_exactly_the_members():
    """The public tables of names have one entry per member, keyed or indexed by its code."""
    assert set(N.EVENT_KIND_NAMES) == {int(m) for m in N.EventKind}
    assert set(N.MOTOR_JOINT_NAMES) == {int(m) for m in N.MotorJointMode}
    assert set(N.VIOLATION_NAMES) == {int(m) for m in N.Violation}
    assert len(N.LEG_NAMES) == len(N.Leg) and len(N.CONTACT_NAMES) == len(N.ContactMode)
    assert len(N.LEG_STATE_NAMES) == len(N.LegState)
    assert {m.label: m.display_name for m in N.Model} == N.MODEL_LABELS
    assert len(set(N.MODEL_LABELS.values())) == len(N.Model)


def test_violations_are_single_bits_with_distinct_descriptions():
    for m in N.Violation:
        assert int(m) > 0 and int(m) & (int(m) - 1) == 0, m
    assert list(N.VIOLATION_NAMES) == sorted(N.VIOLATION_NAMES)
    assert len(set(N.VIOLATION_NAMES.values())) == len(N.VIOLATION_NAMES)


def test_every_code_a_run_records_has_a_name():
    """A Model II bound on a Coulomb floor (controller states, contact and motor-joint
    modes, plant and controller events) records only codes that are members."""
    r = scoutsim.simulate(duration=0.8)
    assert not r.fell
    for leg in N.Leg:
        assert set(np.unique(r.leg_state(leg))) <= {int(m) for m in N.LegState}
        assert set(np.unique(r.contact_mode(leg))) <= {int(m) for m in N.ContactMode}
        assert set(np.unique(r.motor_joint_mode(leg))) <= {int(m) for m in N.MotorJointMode}
    log = r.event_log()
    kinds = set(log["kind"].tolist())
    assert {N.EventKind.TOUCHDOWN, N.EventKind.CONTROLLER_TOUCHDOWN} <= kinds
    assert kinds <= {int(m) for m in N.EventKind}
    assert set(log["leg"].tolist()) <= {-1} | {int(m) for m in N.Leg}
    every_bit = 0
    for m in N.Violation:
        every_bit |= int(m)
    masks = log["violations"].astype(np.int64)
    assert np.all(masks & ~every_bit == 0)


def test_members_are_their_codes():
    """A member compares, indexes and formats as its integer code."""
    assert N.LegState.BRAKE == L.LS_BRAKE and hash(N.LegState.BRAKE) == hash(L.LS_BRAKE)
    assert N.LEG_STATE_NAMES[N.LegState.BRAKE] == "stance-brake"
    assert f"{N.Leg.FRONT}" == str(L.FRONT)
    assert np.asarray([N.ContactMode.STRUT, N.ContactMode.STICK]).dtype.kind == "i"
    assert N.EventKind.from_label("liftoff") == L.EK_LIFTOFF
    assert N.Model.from_label("II") is N.Model.II and N.Model.II.display_name == "Model II"
    assert isinstance(N.Violation.SINGULAR | N.Violation.GROUND_PULLS, N.Violation)


def test_leg_index():
    assert [N.leg_index(x) for x in ("back", "front", 0, 1, N.Leg.BACK, N.Leg.FRONT)] == [
        0,
        1,
        0,
        1,
        0,
        1,
    ]
    assert type(N.leg_index(N.Leg.FRONT)) is int
    for bad in ("left", 2, -1, True, None, 1.0, [0]):
        with pytest.raises(ValueError, match="leg"):
            N.leg_index(bad)


def test_unknown_label():
    with pytest.raises(ValueError, match="'III' is not allowed"):
        N.Model.from_label("III")
