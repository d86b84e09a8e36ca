"""The robot's state at the start of a run: a physical start (:class:`InitialState`) or the
hybrid state of a control sample (:class:`HybridState`), from which a run resumes (to the
integration tolerance, not bit for bit: see :class:`HybridState`). Used by
:func:`scoutsim.simulate` and :meth:`SimulationResult.hybrid_state`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from .model import layout as L

__all__ = ["InitialState", "HybridState"]


@dataclass(frozen=True)
class InitialState:
    """Initial state of the robot (SI units, angles in rad; docs/specification.md section 1 conventions).

    The default is how such a robot is set going into a bound: released in flight with
    both legs at their touchdown angles, torso level at a COM height of 0.33 m (toes about
    2 cm above the ground), moving forward at 1.2 m/s with the nose rising at 150 deg/s,
    the motion the robot has after its front legs push off in its own bound (at front
    lift-off the cycle pitches up at 90-100 deg/s and moves at 1.3-1.6 m/s). The controller
    has no torso feedback, so a start without pitch motion tends not to enter bounding;
    from this one, ideal, Model I and Model II all reach their bounding cycles, and so do
    all their neighbours (speed 1.0-1.4 m/s, pitch rate 100-200 deg/s, height 0.32-0.35 m)
    on the default floor (docs/model.md, "Default start and floor"). Leg lengths default
    to l0.
    """

    x: float = 0.0
    y: float = 0.33
    theta: float = 0.0
    dx: float = 1.2
    dy: float = 0.0
    dtheta: float = math.radians(150.0)
    phi_back: float | None = None
    phi_front: float | None = None
    dphi_back: float = 0.0
    dphi_front: float = 0.0
    leg_length_back: float | None = None
    leg_length_front: float | None = None

    def replace(self, **changes) -> "InitialState":
        return dataclasses.replace(self, **changes)


@dataclass(frozen=True)
class HybridState:
    """The hybrid state at a control sample: where a run can be resumed.

    Unlike :class:`InitialState` (a physical start in double flight, the rest derived), it
    holds the continuous state and every mode the model carries from one sample to the
    next, so Model II gear angles, legs in stance and the controller's leg states can be
    set (used by :func:`scoutsim.analysis.orbits.controlled_fixed_point`). Take one from a
    run with :meth:`SimulationResult.hybrid_state`; a run from it starts at t = 0.

    A resumed run continues the original to the integration tolerance, not bit for bit: it
    starts from the sample's state and modes but not from the integrator's own state (its
    step-size guess, the ARK splitting, the kept evaluation), so its steps differ. Measured
    over 1 s from sample 1500 of the default 3 s Model II run: largest difference 1.4e-3
    rad/s in a leg rate and 3.5e-8 rad in pitch with the default ARK3 (rtol 1e-5); 3.6e-8
    in any component with DOPRI5 (rtol 1e-8).

    state : (16,) [x, y, theta, phi_b, phi_f, alpha_b, alpha_f, their rates, l_b, l_f]
        (SI; layout.py; dependent coordinates are projected at the start).
    leg_states : controller leg states (back, front): 0 flight, 1 stance-retraction,
        2 stance-brake.
    contact_modes : plant toe modes (back, front): 0 flight, 1 stick, 2 slide, 3 strut.
    motor_modes : Model II motor-joint modes (back, front): 0 stuck, +1 / -1 slipping in
        that direction.
    slide_directions : +1 / -1, direction of a sliding toe (back, front).
    toe_anchors : world x [m] of pinned (stick / strut) toes (back, front).
    """

    state: tuple
    leg_states: tuple = (0, 0)
    contact_modes: tuple = (0, 0)
    motor_modes: tuple = (0, 0)
    slide_directions: tuple = (1, 1)
    toe_anchors: tuple = (0.0, 0.0)

    def __post_init__(self):
        s = np.asarray(self.state, dtype=float)
        if s.shape != (L.NS,) or not np.all(np.isfinite(s)):
            raise ValueError(f"HybridState.state must be {L.NS} finite numbers, got shape "
                             f"{s.shape}")
        object.__setattr__(self, "state", tuple(float(v) for v in s))
        allowed = {"leg_states": (L.LS_FLIGHT, L.LS_RETRACTION, L.LS_BRAKE),
                   "contact_modes": (L.FLIGHT, L.STICK, L.SLIDE, L.STRUT),
                   "motor_modes": (L.STUCK, L.SLIP_POS, L.SLIP_NEG),
                   "slide_directions": (1, -1)}
        for name, ok in allowed.items():
            v = tuple(int(x) for x in getattr(self, name))
            if len(v) != 2 or any(x not in ok for x in v):
                raise ValueError(f"HybridState.{name} = {getattr(self, name)!r} is not "
                                 f"allowed: two values from {sorted(ok)}")
            object.__setattr__(self, name, v)
        a = tuple(float(x) for x in self.toe_anchors)
        if len(a) != 2 or not all(math.isfinite(x) for x in a):
            raise ValueError(f"HybridState.toe_anchors = {self.toe_anchors!r} is not allowed: "
                             "two finite positions [m]")
        object.__setattr__(self, "toe_anchors", a)
