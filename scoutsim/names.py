"""Names of the codes a run records, for the layers above the compiled core.

The compiled core (Numba) works on plain integer codes whose slots and values
:mod:`scoutsim._core.model.layout` names; a result carries the same codes (``result.leg_state``,
``result.contact_mode``, the event log). This module gives each family of codes an
:class:`~enum.IntEnum` with the same values, so that analysis, validation, presentation,
the command line and the environments compare a code with a name (``LegState.FLIGHT``)
instead of a bare integer, and read the back / front legs' names from one place. A member
is an ``int``: it compares, indexes and hashes as its code, and ``np.asarray`` of members
is an integer array. ``tests/test_names.py`` checks that every value agrees with
``layout``'s constant.

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

Every enum has :attr:`label`, the name a table or a user writes for a member ("back",
"stance-retraction", "stick", "II", "touchdown"), and :meth:`from_label`, its inverse.

This module imports nothing of the package, so every layer may use it.
"""

from __future__ import annotations

import numbers
from enum import IntEnum, IntFlag

__all__ = ["Leg", "LEG_NAMES", "leg_index", "LegState", "LEG_STATE_NAMES", "ContactMode",
           "CONTACT_NAMES", "MotorJointMode", "MOTOR_JOINT_NAMES", "Model", "MODEL_LABELS",
           "EventKind", "EVENT_KIND_NAMES", "Violation", "VIOLATION_NAMES"]


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
        raise ValueError(f"{label!r} is not allowed: must be one of "
                         f"{[m.label for m in cls]}")


class Leg(_Coded):
    """A virtual leg: its index in every (back, front) pair and in the compiled arrays."""

    BACK = 0
    FRONT = 1


#: The legs' names, in the order of a (back, front) pair.
LEG_NAMES = ("back", "front")


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

    FLIGHT = 0
    RETRACTION = 1
    BRAKE = 2


#: Display names of the leg states, indexed by the code.
LEG_STATE_NAMES = ("flight", "stance-retraction", "stance-brake")


class ContactMode(_Coded):
    """The plant's contact mode of a toe: in the air; pinned at its anchor with the leg's
    spring and damper acting (stick); sliding on the floor; pinned with the leg at its stop
    l0, a rigid strut."""

    FLIGHT = 0
    STICK = 1
    SLIDE = 2
    STRUT = 3


#: Names of the contact modes, indexed by the code.
CONTACT_NAMES = ("flight", "stick", "slide", "strut")


class MotorJointMode(_Coded):
    """The stiction mode of a Model II motor joint: slipping in the negative direction,
    held by its stiction, slipping in the positive direction (0 in the other variants)."""

    SLIP_NEG = -1
    STUCK = 0
    SLIP_POS = 1


#: Names of the motor-joint modes by code.
MOTOR_JOINT_NAMES = {-1: "slip_neg", 0: "stuck", 1: "slip_pos"}


class Model(_Coded):
    """A model variant of the hip units (docs/model.md): the ideal actuator, Model I (motor
    and gears, rigid transmission), Model II (with the belt and the motor joint's
    stiction) and the passive model (no actuators, no controller). :attr:`label` is the
    name a user gives (``simulate(..., model="II")``), :attr:`display_name` the one a table
    or legend shows."""

    IDEAL = 0
    I = 1  # noqa: E741 (the paper's name of the variant)
    II = 2
    PASSIVE = 3

    @property
    def display_name(self) -> str:
        """"ideal actuator", "Model I", "Model II" or "passive (no controller)"."""
        return MODEL_LABELS[self.label]


#: Display name of each model variant by its name (tables, legends, titles).
MODEL_LABELS = {"ideal": "ideal actuator", "I": "Model I", "II": "Model II",
                "passive": "passive (no controller)"}


class EventKind(_Coded):
    """The kind of a record of the event log: the plant's transitions (touchdown, lift-off,
    the toe starting to slide and sticking again, the leg becoming a strut and a spring leg
    again, the motor joint sticking and slipping, the fall) and the controller's detections
    (touchdown, lift-off, the sweep limit passed); a jam is a sliding toe stopped by an
    impact without collision (docs/model.md "A sliding toe that jams")."""

    TOUCHDOWN = 1
    LIFTOFF = 2
    SLIDE_START = 3
    STICK = 4
    STRUT_START = 5
    STRUT_END = 6
    MOTOR_STICK = 7
    MOTOR_SLIP = 8
    FALL = 9
    CONTROLLER_TOUCHDOWN = 10
    CONTROLLER_LIFTOFF = 11
    CONTROLLER_SWEEP = 12
    JAM = 13


#: Names of the event kinds by code (the kinds ``result.event_times`` takes).
EVENT_KIND_NAMES = {
    1: "touchdown", 2: "liftoff", 3: "slide_start", 4: "stick", 5: "strut_start",
    6: "strut_end", 7: "motor_stick", 8: "motor_slip", 9: "fall",
    10: "controller_touchdown", 11: "controller_liftoff", 12: "controller_sweep_limit",
    13: "jam",
}

class Violation(IntFlag):
    """A mode invariant violated after a transition: one bit of an event record's
    ``violations`` mask (:meth:`SimulationResult.event_log`; 0: none)."""

    GROUND_PULLS = 1          # a pinned toe or strut whose ground normal force pulls
    OUTSIDE_CONE = 2          # a pinned toe (Coulomb floor) needing more than mu |F_n|
    SLIDE_DIRECTION = 4       # a sliding toe moving against its recorded slide direction
    SLIDE_NOT_PUSHING = 8     # a sliding toe whose leg no longer pushes
    TOE_BELOW_GROUND = 16     # a toe in flight below the ground
    STICTION_EXCEEDED = 32    # a stuck motor joint held by more than its stiction
    SLIP_DIRECTION = 64       # a slipping motor joint moving against its slip direction
    STRUT_COMPRESSED = 128    # a rigid strut in compression
    SINGULAR = 256            # the constrained dynamics could not be solved
    BEYOND_STOP = 512         # a spring leg with its pinned toe beyond the stop l0
    TOE_ENTERS_GROUND = 1024  # a toe in flight at ground level moving into it


#: What each bit of a violations mask means, in the order of the bits.
VIOLATION_NAMES = {
    1: "ground pulls a pinned toe", 2: "pinned toe outside the friction cone",
    4: "toe slides against its slide direction", 8: "sliding leg does not push",
    16: "toe in flight below the ground", 32: "stuck motor joint beyond breakaway",
    64: "motor joint slips against its slip direction", 128: "strut in compression",
    256: "constrained dynamics singular", 512: "pinned leg extended beyond its stop",
    1024: "toe in flight at the ground moving into it",
}

_LABELS = {
    Leg: dict(enumerate(LEG_NAMES)),
    LegState: dict(enumerate(LEG_STATE_NAMES)),
    ContactMode: dict(enumerate(CONTACT_NAMES)),
    MotorJointMode: MOTOR_JOINT_NAMES,
    Model: dict(enumerate(("ideal", "I", "II", "passive"))),
    EventKind: EVENT_KIND_NAMES,
}
