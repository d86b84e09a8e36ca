"""The controller a tuning (:func:`scoutsim.analysis.tune.tune`) tunes: which kind it is
(Table I, pitch feedback, a compiled or Python controller object, a user's factory), the
base parameters it starts from, what the workers are sent to make it, and which tuned
parameters it reads.
"""

from __future__ import annotations

from ..parameters import ControllerParameters
from .study_controller import study_controller


def controller_spec(controller, robot):
    """(kind, base ControllerParameters, spec for the workers) of the controller given:
    Table I, pitch feedback, a compiled controller (its parameter array can be tuned), a
    Python controller, or a user's factory (``"MODULE:FACTORY"`` / ControllerSpec: it gets
    each candidate's robot and controller parameters)."""
    from ..control.compiled import CompiledController
    from ..control.factory import ControllerSpec
    from ..control.pitch_feedback import PitchFeedbackController

    if controller is None or isinstance(controller, ControllerParameters):
        return "table-i", controller or ControllerParameters(), {"kind": "table-i"}
    controller = study_controller(controller, robot)
    if isinstance(controller, str):
        if controller not in ("table-i", "pitch-feedback"):
            raise ValueError(
                f"controller = {controller!r} is not allowed: table-i, "
                "pitch-feedback, MODULE:FACTORY, ControllerParameters, a "
                "ControllerSpec or a controller object"
            )
        return controller, ControllerParameters(), {"kind": controller}
    if isinstance(controller, PitchFeedbackController):
        return ("pitch-feedback", controller.controller_parameters, {"kind": "pitch-feedback"})
    if isinstance(controller, ControllerSpec):
        return (
            "factory",
            controller.params or ControllerParameters(),
            {"kind": "factory", "controller": controller},
        )
    if isinstance(controller, CompiledController):
        base = controller.controller_parameters or ControllerParameters()
        return (
            "compiled",
            base,
            {
                "kind": "compiled",
                "controller": controller,
                "params": [float(x) for x in controller.params],
            },
        )
    if callable(getattr(controller, "command", None)):
        return "python", ControllerParameters(), {"kind": "python", "controller": controller}
    raise TypeError(
        f"controller of type {type(controller).__name__} cannot be tuned: give "
        "ControllerParameters, a controller object, or MODULE:FACTORY"
    )


def check_tuned_fields(kind: str, params: list) -> None:
    """ValueError for a tuned ``controller.<field>`` that the controller does not read (a
    compiled or Python controller object: it does not take ControllerParameters)."""
    if kind in ("compiled", "python"):
        bad = [p.name for p in params if p.key.startswith("controller.")]
        if bad:
            raise ValueError(
                f"parameter {bad[0]!r} is not allowed with a {kind} controller "
                "object, which does not read ControllerParameters: tune its "
                "controller.params[i] (a CompiledController), robot.<field>, or "
                "give the controller as MODULE:FACTORY (a factory make(robot, "
                "params) gets each candidate's parameters)"
            )
