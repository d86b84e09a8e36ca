"""The start-up from standing: how the robot gets from rest on its four legs into the
Table I bound (``simulate(..., initial_state="standing")``; docs/model.md "Standing start").

The bounding controller (:mod:`scoutsim.control.bounding`) has no torso feedback, and a
robot standing still gives it nothing to work with: its stance-brake law holds vertical
legs at the sweep limit for ever. The start-up is a step of the back legs and a push of
all four, made with the controller's own laws (stance-brake PD, stance-retraction at full
motor torque, flight servo); it changes only set-points, gains and, once, the front legs'
state:

1. **Stand** (``stand_duration``): both legs in stance-brake about the standing angle
   (vertical, phi = 0), the robot at rest (:func:`scoutsim.state.standing_state`).
2. **Step**: the back legs' stance-brake set-point jumps to their touchdown angle (19 deg,
   Table I). The hip torque (at the motor's current limit, 31 N m per leg) swings the back
   legs forward: their toes are dragged forward and unload, and the legs leave the ground
   when their compression falls below the lift-off threshold. From that lift-off on the
   back legs run the unmodified Table I controller: the flight servo holds them at the
   touchdown angle and they land about 2 cm ahead of where they stood.
3. **Push**: when the back legs' touchdown is detected (they enter stance-retraction,
   Table I), the front legs enter stance-retraction too, with the push-off angle
   (``front_pushoff_angle``, -5 deg) as their sweep limit: all four legs sweep back at
   full motor torque. The thrust moves the robot forward and pitches its nose up; the
   front legs unload and lift off.
4. **Hand-over**: each leg's set-point and gains return to Table I's at its first
   lift-off; the start-up ends at the **hand-over**, the first control sample at which
   both legs have lifted off and run the Table I controller with its own parameters
   (``StartupRecord.handover_s``, the summary's ``startup_duration_s``, counted from
   t = 0, standing). The next strides are the bound's transient.

Why this sequence (measured, docs/model.md "Standing start"): a step of the front legs
alone (to 10-25 deg) leaves the robot standing or shuffling in all three models; the back
step alone bounds with the default robot but falls with a 10 % weaker motor (Model II);
the push of the front legs with the back legs' thrust makes the first stride faster and
the start robust to that. It is what the bound itself does: the back legs land ahead of
the hips and thrust, and the front legs push off after them.

The start-up runs in the compiled loop, one control sample per call while it lasts
(a few hundred samples), then the run continues in the usual chunks: one
:func:`~scoutsim.simulate` call, one result.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

from .._core.model.layout import IPHB, LEG_NAMES, LS_FLIGHT, LS_RETRACTION
from ..parameters import ControllerParameters

__all__ = ["StartupParameters", "StartupRecord", "run_startup"]

#: the standing legs' angle relative to the torso [rad] of a robot whose legs are equal
#: (:func:`scoutsim.state.standing_state`: vertical legs under a level torso)
STANDING_LEG_ANGLE = 0.0
BACK, FRONT = 0, 1


def standing_leg_angle(s, leg: int) -> float:
    """The angle [rad] relative to the torso at which the stand holds leg ``leg``: its
    angle in the standing state ``s`` (vertical, phi = -theta; :data:`STANDING_LEG_ANGLE`
    for a level torso)."""
    return float(s[IPHB + leg])


@dataclass(frozen=True)
class StartupParameters:
    """The start-up from standing (SI units, angles in rad relative to the torso, gains per
    physical leg).

    stand_duration : float
        Time [s] the robot stands at rest before the step (default 0.2 s; assumed: long
        enough to see it stand, short against a run).
    step_angle_back : float or None
        Stance-brake set-point of the back legs during the step [rad]; None = the
        controller's back touchdown angle (Table I: 19 deg), where the flight servo then
        holds the leg, so the step ends where a bounding touchdown starts.
    step_kp, step_kd : float or None
        PD gains of the stepping back legs' stance-brake law [N m/rad], [N m s/rad]; None
        = the controller's stance-brake gains (Table I: 300, 5). The command saturates at
        the motor's current limit (31 N m) for most of the step.
    front_pushoff_angle : float or None
        Sweep limit [rad] of the front legs' stance-retraction while they push with the
        back legs' thrust (default -5 deg: a little behind vertical; chosen from a sweep
        of 0 to -20 deg, where -3 to -7 deg start the bound most robustly); None = the
        front legs do not push: they stand in stance-brake until the thrust lifts them.
    handover_timeout : float
        Longest time [s] after the step to wait for a leg's lift-off; a leg that has not
        lifted off by then is handed over anyway and the start-up counts as not completed
        (default 1 s; assumed: with the default parameters both legs lift off within
        0.2 s of the step).
    """

    stand_duration: float = 0.2
    step_angle_back: float | None = None
    step_kp: float | None = None
    step_kd: float | None = None
    front_pushoff_angle: float | None = math.radians(-5.0)
    handover_timeout: float = 1.0

    def __post_init__(self):
        optional = ("step_angle_back", "step_kp", "step_kd", "front_pushoff_angle")
        for name in ("stand_duration", "handover_timeout") + optional:
            v = getattr(self, name)
            if v is None and name in optional:
                continue
            if isinstance(v, bool) or not (isinstance(v, (int, float)) and math.isfinite(v)):
                raise ValueError(
                    f"startup.{name} = {v!r} is not allowed: must be a finite "
                    "number" + (" or None" if name in optional else "")
                )
        if self.stand_duration < 0.0:
            raise ValueError(
                f"startup.stand_duration = {self.stand_duration} s is not allowed: must be >= 0"
            )
        if not 0.0 < self.handover_timeout <= 5.0:
            raise ValueError(
                f"startup.handover_timeout = {self.handover_timeout} s is not "
                "allowed: must be in (0, 5] s"
            )
        for name in ("step_angle_back", "front_pushoff_angle"):
            v = getattr(self, name)
            if v is not None and not abs(v) < math.pi / 2:
                raise ValueError(
                    f"startup.{name} = {math.degrees(v):.1f} deg is not "
                    "allowed: must be in (-90, 90) deg"
                )
        for name in ("step_kp", "step_kd"):
            v = getattr(self, name)
            if v is not None and v < 0.0:
                raise ValueError(f"startup.{name} = {v} is not allowed: must be >= 0")

    def replace(self, **changes) -> StartupParameters:
        """A copy with some fields changed."""
        return replace(self, **changes)

    def resolved(self, controller: ControllerParameters) -> StartupParameters:
        """The parameters with every None that stands for a controller value filled in."""
        return replace(
            self,
            step_angle_back=(
                controller.touchdown_angle_back
                if self.step_angle_back is None
                else self.step_angle_back
            ),
            step_kp=controller.brake_kp_back if self.step_kp is None else self.step_kp,
            step_kd=controller.brake_kd_back if self.step_kd is None else self.step_kd,
        )

    def back_step(self, controller: ControllerParameters) -> tuple[float, float, float]:
        """The back legs' step: (sweep limit [rad], stance-brake gains [N m/rad],
        [N m s/rad]), each None filled in from ``controller``."""
        p = self.resolved(controller)
        assert p.step_angle_back is not None and p.step_kp is not None and p.step_kd is not None
        return p.step_angle_back, p.step_kp, p.step_kd


@dataclass(frozen=True)
class StartupRecord:
    """What a start-up did (times [s] from t = 0, the robot standing).

    step_s : when the step began.
    push_s : when the front legs began to push (the back legs' touchdown after the step
        was detected), None if they did not.
    liftoff_s : (back, front) the control sample at which each leg's first lift-off was
        detected (None if it did not lift off before the timeout or the end of the run).
    handover_s : the first sample at which both legs run the unmodified Table I
        controller (None if the start-up did not complete): the start-up's duration.
    completed : both legs lifted off before the timeout.
    parameters : the :class:`StartupParameters` used, resolved.
    """

    step_s: float
    push_s: float | None
    liftoff_s: tuple
    handover_s: float | None
    completed: bool
    parameters: StartupParameters

    def to_dict(self) -> dict:
        """JSON-safe (a run's provenance)."""
        return {
            "step_s": self.step_s,
            "push_s": self.push_s,
            "liftoff_s": list(self.liftoff_s),
            "handover_s": self.handover_s,
            "completed": self.completed,
            "parameters": asdict(self.parameters),
        }


def _set_brake(engine, leg: int, angle: float, kp: float, kd: float) -> None:
    """Set leg ``leg``'s sweep limit (the stance-brake set-point) [rad] and stance-brake
    gains [N m/rad], [N m s/rad] of the engine's Table I controller."""
    name = LEG_NAMES[leg]
    engine.retune(**{f"sweep_limit_{name}": angle, f"brake_kp_{name}": kp, f"brake_kd_{name}": kd})


def run_startup(
    engine, params: StartupParameters, controller: ControllerParameters
) -> StartupRecord:
    """Drive ``engine`` through the start-up from standing, up to the hand-over.

    ``engine`` runs the compiled Table I controller over the plant
    (:class:`scoutsim.simulation.engine.HybridEngine`: its state ``s``, leg states ``ls``,
    sample index ``k``, period ``dt``, ``running``, ``advance(k_stop)``, and the
    controller's set-points and gains changed by ``retune(**fields)`` and its leg states by
    ``set_leg_state(leg, state)``), starting from :func:`scoutsim.state.standing_state` at
    sample 0. The start-up changes the sweep limits and stance-brake gains and puts the
    front legs into stance-retraction once (the push); each leg's values return to
    ``controller``'s at its first lift-off. Returns when both legs are handed over (or
    the run ended); the caller continues the run.
    """
    p = params.resolved(controller)
    dt = engine.dt
    table = [
        (controller.sweep_limit_back, controller.brake_kp_back, controller.brake_kd_back),
        (controller.sweep_limit_front, controller.brake_kp_front, controller.brake_kd_front),
    ]
    for leg in range(2):  # stand: hold the standing angle with the stance-brake law
        _set_brake(engine, leg, standing_leg_angle(engine.s, leg), table[leg][1], table[leg][2])
    k_step = int(round(p.stand_duration / dt))
    k_timeout = k_step + int(round(p.handover_timeout / dt))
    liftoff = [None, None]
    handed = [False, False]
    push = None
    stepped = False
    while engine.running and not all(handed):
        if not stepped and engine.k >= k_step:
            stepped = True
            _set_brake(engine, BACK, *params.back_step(controller))
        if engine.k > k_step and engine.k >= k_timeout:
            break
        engine.advance(engine.k + 1)
        # (ls now holds the leg states the sample just run, k - 1, set)
        if (
            push is None
            and handed[BACK]
            and not handed[FRONT]
            and p.front_pushoff_angle is not None
            and engine.ls[BACK] == LS_RETRACTION
        ):
            # the stepped back legs touched down and thrust: the front legs push with them
            push = round((engine.k - 1) * dt, 9)
            engine.retune(sweep_limit_front=p.front_pushoff_angle)
            engine.set_leg_state(FRONT, LS_RETRACTION)
        for leg in range(2):
            # this leg's lift-off detected: from the next sample on it runs Table I
            if not handed[leg] and engine.ls[leg] == LS_FLIGHT:
                handed[leg] = True
                liftoff[leg] = round((engine.k - 1) * dt, 9)
                _set_brake(engine, leg, *table[leg])
    completed = all(handed)
    for leg in range(2):  # timeout or end of the run: every leg back to Table I
        if not handed[leg]:
            _set_brake(engine, leg, *table[leg])
    return StartupRecord(
        step_s=round(k_step * dt, 9),
        push_s=push,
        liftoff_s=tuple(liftoff),
        handover_s=round(engine.k * dt, 9) if completed else None,
        completed=completed,
        parameters=p,
    )
