"""A robot or floor parameter as a row of the sensitivities a run carries: its derivative
of the packed arrays the compiled loop reads (:mod:`scoutsim.simulation.sensitivities`)."""

from __future__ import annotations

import numpy as np

from ..parameters import DEFAULT_FRICTION_COEFFICIENT, RobotParameters
from ..parameters.robot_fields import robot_value, robot_with_value
from .engine import start_engine

__all__ = ["robot_parameter_derivatives", "packing_derivatives"]


def robot_parameter_derivatives(fields, robot=None, relative_step: float = 1e-6, **run):
    """(dP, dC, dcp) of the robot parameters ``fields`` (names of RobotParameters' float
    fields, ``<field>.back`` / ``<field>.front`` for one leg of a per-leg field
    (:mod:`scoutsim.parameters.robot_fields`); ``"friction_coefficient"`` the floor's): central differences of the packing,
    steps ``relative_step`` |value| (absolute at 0), for the run ``run`` describes
    (:func:`~scoutsim.simulation.engine.start_engine`'s keywords: model, controller, ...).
    The rows to pass to ``carry_sensitivities``."""
    robot = robot or RobotParameters()

    def value_of(field):
        if field == "friction_coefficient":
            return run.get(field, DEFAULT_FRICTION_COEFFICIENT)
        return robot_value(robot, field)

    def engine_for(field, value):
        if field == "friction_coefficient":
            return start_engine(None, 1.0, robot=robot, **{**run, field: value})
        return start_engine(None, 1.0, robot=robot_with_value(robot, field, value), **run)

    return packing_derivatives(fields, value_of, engine_for, relative_step)


def packing_derivatives(fields, value_of, engine_for, relative_step: float = 1e-6):
    """(dP, dC, dcp): each field's derivative of the packed arrays an engine reads (the
    robot's, the Table I law's, a compiled controller's), by central differences of
    ``engine_for(field, value)`` (an engine of the run with that one value changed) at
    ``value_of(field)`` +- ``relative_step`` |value| (absolute at 0)."""
    rows = []
    for field in fields:
        value = value_of(field)
        h = relative_step * abs(value) if value != 0.0 else relative_step
        ends = [engine_for(field, v) for v in (value + h, value - h)]
        packed = [(e.P, e.C, e.block.params) for e in ends]
        rows.append([(a - b) / (2.0 * h) for a, b in zip(*packed)])
    return tuple(np.array([r[i] for r in rows]) for i in range(3))
