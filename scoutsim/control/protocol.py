"""The controller protocol: what :func:`scoutsim.simulate` asks of a controller.

A controller is an object with

``control_period`` : float
    its sample-and-hold period [s]; the paper's controller runs at 1 kHz
    (:data:`DEFAULT_CONTROL_PERIOD`, 1 ms; an object without the attribute gets it).
``reset(robot, sensors)`` (optional)
    called once before a run with the robot (:class:`~scoutsim.parameters.RobotParameters`)
    and the readings of the first sample (:class:`~scoutsim.control.sensors.Sensors`).
``command(t, sensors) -> (tau_back, tau_front)``
    at every control sample t = k ``control_period`` [s]: the hip torque per physical leg
    at the leg [N m] (back, front), held until the next sample, from the sensor readings
    (:class:`~scoutsim.control.sensors.Sensors`: hip encoders, leg lengths, IMU, laser
    ranges, motor currents, battery voltage; what the robot's own sensors give, with the
    robot file's noise, bias, resolution and delay).
``leg_states`` (optional)
    length-2 sequence of leg-state codes (0 flight, 1 stance-retraction, 2 stance-brake)
    logged with each sample.
``get_state() -> sequence of float`` and ``set_state(values)`` (optional, together)
    the controller's own state (timers, filters, estimates; its ``leg_states`` too if it
    keeps them), read at a control sample before its command there and put back before a
    run resumes from that sample (:class:`~scoutsim.state.HybridState`'s
    ``controller_state``). A stateless controller returns an empty sequence. The periodic
    orbits (:func:`scoutsim.analysis.controlled_orbit.controlled_fixed_point`, ``scoutsim
    orbit``) restart strides from section states and need them; a compiled controller's
    state is its state array, read and set by scoutsim itself.

:class:`Controller` is a base class with these defaults. The built-in Table I controller
(:class:`~scoutsim.control.bounding.BoundingController`) and the compiled controllers
(:class:`~scoutsim.control.compiled.CompiledController`) implement the same protocol; how
each kind is run is decided in :mod:`scoutsim.control.dispatch`.

A controller whose ``command`` raises, or returns anything but two finite numbers, stops
the run with :class:`ControllerError`.
"""

from __future__ import annotations

import reprlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np

__all__ = ["Controller", "ControllerError", "DEFAULT_CONTROL_PERIOD", "failure_message"]

#: the paper's control period [s]: "a 1 kHz control loop" (Sec. IV.A)
DEFAULT_CONTROL_PERIOD = 1e-3


class Controller:
    """Base class of controllers (see the module docstring for the protocol).

    Subclasses override :meth:`command`, and :meth:`reset` if they keep state.
    """

    #: sample-and-hold period [s]
    control_period: float = DEFAULT_CONTROL_PERIOD
    #: leg states to log (None: not logged)
    leg_states: np.ndarray | None = None

    def reset(self, robot, sensors) -> None:
        """Prepare for a run of ``robot`` whose first readings are ``sensors``."""

    def command(self, t: float, sensors) -> tuple[float, float]:
        """Hip torques (back, front) per physical leg at the leg [N m] for sample time
        ``t`` [s] and the readings ``sensors``."""
        raise NotImplementedError


class ControllerError(RuntimeError):
    """A controller's ``command(t, sensors)`` raised an exception, or returned something
    other than finite hip torques: :func:`scoutsim.simulate` stops the run at that control
    sample and raises this error (the controller's own exception is its ``__cause__``).

    Attributes
    ----------
    controller : the controller object.
    t : time of the control sample [s] (``sample * control_period``).
    sample : index of the control sample.
    returned : what ``command`` returned (None if it raised; a compiled controller: its
        torques, or its status if that was not 0).
    result : the run up to the sample before (a :class:`~scoutsim.result.simulation_result.SimulationResult`
        with ``outcome = "controller_error"`` and the message in
        ``provenance["controller_error"]``; a streamed run: its kept end, the tables hold
        all of it).
    """

    def __init__(
        self, message: str, *, controller, t: float, sample: int, returned=None, result=None
    ):
        super().__init__(message)
        self.controller, self.t, self.sample = controller, t, sample
        self.returned, self.result = returned, result


def controller_name(controller) -> str:
    """How messages name a controller: its ``name`` if it has one, else its class."""
    name = getattr(controller, "name", None)
    return name if isinstance(name, str) else type(controller).__name__


def failure_message(
    controller, sample: int, dt: float, returned, exc: BaseException | None, status: int = 0
) -> str:
    """What :class:`ControllerError` says: the controller, the sample time, what it raised
    or returned (a compiled controller's nonzero ``status``), and up to where the run's
    data go."""
    if exc is not None:
        what = f"raised {type(exc).__name__}: {exc}"
    elif status != 0:
        what = f"returned status {status} (0 goes on), torques {reprlib.repr(returned)}"
    else:
        what = f"returned {reprlib.repr(returned)}, not two finite hip torques [N m] (back, front)"
    kept = (
        f"its samples up to t = {(sample - 1) * dt:.10g} s are in the error's .result"
        if sample > 0
        else "before its first sample"
    )
    return (
        f"controller {controller_name(controller)}.command(t = {sample * dt:.10g} s, "
        f"sensors) {what}; the run stopped at that sample ({kept})"
    )
