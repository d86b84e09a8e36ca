"""Controllers and the controller boundary.

* :mod:`~scoutsim.control.protocol`: what a controller is (``control_period``, ``reset``,
  ``command(t, sensors)``), :class:`Controller`, :class:`ControllerError`;
* :mod:`~scoutsim.control.sensors`: what it sees (:class:`Sensors`) and how the sensors
  measure (:class:`SensorParameters`, a robot file's ``[sensors]``);
* :mod:`~scoutsim.control.bounding`: the paper's Table I controller;
* :mod:`~scoutsim.control.compiled`: controllers compiled into the simulator's loop
  (:class:`CompiledController`);
* :mod:`~scoutsim.control.pitch_feedback`: Table I with the touchdown angles corrected by
  torso pitch and pitch rate (:class:`PitchFeedbackController`);
* :mod:`~scoutsim.control.dispatch`: which controller runs how.
"""

from .bounding import BoundingController
from .compiled import CompiledController
from .pitch_feedback import PitchFeedbackController
from .protocol import DEFAULT_CONTROL_PERIOD, Controller, ControllerError
from .sensors import SensorChannel, SensorParameters, Sensors, load_sensors

__all__ = [
    "Controller",
    "ControllerError",
    "DEFAULT_CONTROL_PERIOD",
    "Sensors",
    "SensorChannel",
    "SensorParameters",
    "load_sensors",
    "BoundingController",
    "CompiledController",
    "PitchFeedbackController",
]
