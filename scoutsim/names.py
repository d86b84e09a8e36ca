"""Names of the codes a run records, for the layers above the compiled core.

The compiled core (Numba) works on plain integer codes whose slots, values and names
:mod:`scoutsim._core.model.layout` holds, the one table of them; a result carries the same
codes (``result.leg_state``, ``result.contact_mode``, the event log). This module gives each
family of codes an :class:`~enum.IntEnum` whose members take their values from that table
(``LegState.FLIGHT = layout.LS_FLIGHT``) and whose labels are the table's names, so no code
or name is written twice, and analysis, validation, presentation, the command line and the
environments compare a code with a name (``LegState.FLIGHT``) instead of a bare integer. A
member is an ``int``: it compares, indexes and hashes as its code, and ``np.asarray`` of
members is an integer array. ``tests/test_names.py`` checks that every code of the table has
a member, and that the labels are unique and round-trip.

* :class:`Leg` (``BACK`` 0, ``FRONT`` 1), :data:`LEG_NAMES` and :func:`leg_index`: the
  virtual legs, in the order of every (back, front) pair (the back hip at -L, the front
  hip at +L along the torso axis; docs/specification.md section 1).
* :class:`LegState`: the controller's leg states (paper Sec. II, Table I).
* :class:`ContactMode`: the plant's toe contact modes.
* :class:`MotorJointMode`: the Model II motor joint's stiction modes.
* :class:`Model`: the model variants, with the names a user gives (``model="II"``) and
  their display names (:data:`MODEL_LABELS`).
* :class:`EventKind`: the kinds of the event log (:meth:`SimulationResult.event_times`).
* :class:`Violation`: the bits of the mode invariants a transition may violate (the
  transition audit, :mod:`scoutsim.analysis.transition_audit`), described by
  :data:`VIOLATION_NAMES`.

Every enum but :class:`Violation` has :attr:`label`, the name a table or a user writes for
a member ("back", "stance-retraction", "stick", "II", "touchdown"), and :meth:`from_label`,
its inverse.

This module imports only the table (:mod:`scoutsim._core.model.layout`, which imports
nothing), so every layer may use it.
"""

from __future__ import annotations

import numbers
from enum import IntEnum, IntFlag

from ._core.model import layout as _layout

__all__ = [
    "Leg",
    "LEG_NAMES",
    "leg_index",
    "LegState",
    "LEG_STATE_NAMES",
    "ContactMode",
    "CONTACT_NAMES",
    "MotorJointMode",
    "MOTOR_JOINT_NAMES",
    "Model",
    "MODEL_LABELS",
    "EventKind",
    "EVENT_KIND_NAMES",
    "Violation",
    "VIOLATION_NAMES",
]


class _Coded(IntEnum):
    """An integer code with a label (:attr:`label`, :meth:`from_label`)."""

    @property
    def label(self) -> str:
        """The name a table or a user writes for this code."""
        return _LABELS[type(self)][self]

    @classmethod
    def from_label(cls, label: str):
        """The member whose :attr:`label` is ``label``; ValueError for any other string."""
        for member in cls:
            if member.label == label:
                return member
        raise ValueError(f"{label!r} is not allowed: must be one of {[m.label for m in cls]}")


class Leg(_Coded):
    """A virtual leg: its index in every (back, front) pair and in the compiled arrays."""

    BACK = _layout.BACK
    FRONT = _layout.FRONT


#: The legs' names, in the order of a (back, front) pair.
LEG_NAMES = _layout.LEG_NAMES


def leg_index(leg) -> int:
    """0 for the back leg, 1 for the front: from a :class:`Leg`, 0 / 1 or "back" / "front"
    (ValueError for anything else, a bool included)."""
    if isinstance(leg, str) and leg in LEG_NAMES:
        return LEG_NAMES.index(leg)
    if isinstance(leg, numbers.Integral) and not isinstance(leg, bool) and leg in (0, 1):
        return int(leg)
    raise ValueError(f"leg = {leg!r} is not allowed: must be 'back' (0) or 'front' (1)")


class LegState(_Coded):
    """The controller's state of a leg (paper Sec. II, Table I): flight, stance with the
    leg driven backwards (retraction, eqs. 2-5), stance past the sweep limit (brake)."""

    FLIGHT = _layout.LS_FLIGHT
    RETRACTION = _layout.LS_RETRACTION
    BRAKE = _layout.LS_BRAKE


#: Display names of the leg states, indexed by the code.
LEG_STATE_NAMES = _layout.LEG_STATE_NAMES


class ContactMode(_Coded):
    """The plant's contact mode of a toe: in the air; pinned at its anchor with the leg's
    spring and damper acting (stick); sliding on the floor; pinned with the leg at its stop
    l0, a rigid strut."""

    FLIGHT = _layout.FLIGHT
    STICK = _layout.STICK
    SLIDE = _layout.SLIDE
    STRUT = _layout.STRUT


#: Names of the contact modes, indexed by the code.
CONTACT_NAMES = _layout.CONTACT_NAMES


class MotorJointMode(_Coded):
    """The stiction mode of a Model II motor joint: slipping in the negative direction,
    held by its stiction, slipping in the positive direction (0 in the other variants)."""

    SLIP_NEG = _layout.SLIP_NEG
    STUCK = _layout.STUCK
    SLIP_POS = _layout.SLIP_POS


#: Names of the motor-joint modes by code.
MOTOR_JOINT_NAMES = _layout.MOTOR_JOINT_NAMES


class Model(_Coded):
    """A model variant of the hip units (docs/model.md): the ideal actuator, Model I (motor
    and gears, rigid transmission), Model II (with the belt and the motor joint's
    stiction) and the passive model (no actuators, no controller). :attr:`label` is the
    name a user gives (``simulate(..., model="II")``), :attr:`display_name` the one a table
    or legend shows."""

    IDEAL = _layout.MODEL_IDEAL
    I = _layout.MODEL_I  # noqa: E741 (the paper's name of the variant)
    II = _layout.MODEL_II
    PASSIVE = _layout.MODEL_PASSIVE

    @property
    def display_name(self) -> str:
        """ "ideal actuator", "Model I", "Model II" or "passive (no controller)"."""
        return MODEL_LABELS[self.label]


#: Display name of each model variant by its name (tables, legends, titles).
MODEL_LABELS = _layout.MODEL_LABELS


class EventKind(_Coded):
    """The kind of a record of the event log: the plant's transitions (touchdown, lift-off,
    the toe starting to slide and sticking again, the leg becoming a strut and a spring leg
    again, the motor joint sticking and slipping, the fall) and the controller's detections
    (touchdown, lift-off, the sweep limit passed); a jam is a sliding toe stopped by an
    impact without collision (docs/model.md "A sliding toe that jams")."""

    TOUCHDOWN = _layout.EK_TOUCHDOWN
    LIFTOFF = _layout.EK_LIFTOFF
    SLIDE_START = _layout.EK_SLIDE_START
    STICK = _layout.EK_STICK
    STRUT_START = _layout.EK_STRUT_START
    STRUT_END = _layout.EK_STRUT_END
    MOTOR_STICK = _layout.EK_MOTOR_STICK
    MOTOR_SLIP = _layout.EK_MOTOR_SLIP
    FALL = _layout.EK_FALL
    CONTROLLER_TOUCHDOWN = _layout.EK_CTRL_TOUCHDOWN
    CONTROLLER_LIFTOFF = _layout.EK_CTRL_LIFTOFF
    CONTROLLER_SWEEP = _layout.EK_CTRL_SWEEP
    JAM = _layout.EK_JAM


#: Names of the event kinds by code (the kinds ``result.event_times`` takes).
EVENT_KIND_NAMES = _layout.EVENT_KIND_NAMES


class Violation(IntFlag):
    """A mode invariant violated after a transition: one bit of an event record's
    ``violations`` mask (:meth:`SimulationResult.event_log`; 0: none); what each bit means:
    :data:`VIOLATION_NAMES`."""

    GROUND_PULLS = _layout.V_GROUND_PULLS
    OUTSIDE_CONE = _layout.V_OUTSIDE_CONE
    SLIDE_DIRECTION = _layout.V_SLIDE_DIRECTION
    SLIDE_NOT_PUSHING = _layout.V_SLIDE_NOT_PUSHING
    TOE_BELOW_GROUND = _layout.V_TOE_BELOW_GROUND
    STICTION_EXCEEDED = _layout.V_STICTION_EXCEEDED
    SLIP_DIRECTION = _layout.V_SLIP_DIRECTION
    STRUT_COMPRESSED = _layout.V_STRUT_COMPRESSED
    SINGULAR = _layout.V_SINGULAR
    BEYOND_STOP = _layout.V_BEYOND_STOP
    TOE_ENTERS_GROUND = _layout.V_TOE_ENTERS_GROUND


#: What each bit of a violations mask means, in the order of the bits.
VIOLATION_NAMES = _layout.VIOLATION_NAMES

#: Each labelled enum's label by code: the table's names (a model's label is the name a
#: user gives, the key of ``layout.MODEL_NAMES``).
_LABELS = {
    Leg: dict(enumerate(LEG_NAMES)),
    LegState: dict(enumerate(LEG_STATE_NAMES)),
    ContactMode: dict(enumerate(CONTACT_NAMES)),
    MotorJointMode: MOTOR_JOINT_NAMES,
    Model: {code: name for name, code in _layout.MODEL_NAMES.items()},
    EventKind: EVENT_KIND_NAMES,
}
