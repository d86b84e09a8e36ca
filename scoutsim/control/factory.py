"""A user's controller named by where it lives: ``MODULE:FACTORY``.

A researcher's controller is usually a function or class in a module of their own. The
command line (``--controller mypkg.gaits:make``), the Gymnasium environment
(``controller="mypkg.gaits:make"``) and the parallel studies name it by that string, so it
can be imported again wherever it runs, on a worker process or a Dask worker included.

The factory is called with the robot (a :class:`~scoutsim.parameters.RobotParameters`) and
the controller parameters (a :class:`~scoutsim.parameters.ControllerParameters`, the robot
file's ``[controller]``)::

    def make(robot, params):            # or make(robot), or make()
        return MyController(...)        # any controller scoutsim.simulate accepts

and returns any controller :func:`scoutsim.simulate` accepts: a
:class:`~scoutsim.parameters.ControllerParameters` (the Table I law), an object with the
controller protocol (:mod:`scoutsim.control.protocol`) or a
:class:`~scoutsim.control.compiled.CompiledController`. The factory may take fewer
arguments: ``make(robot)`` or ``make()``.

``MODULE`` is imported with :func:`importlib.import_module`, so it must be on
``sys.path`` (the current directory for ``python -m``, ``PYTHONPATH``, or an installed
package); ``FACTORY`` may be a dotted attribute path (``module:Class.build``).
"""

from __future__ import annotations

import importlib
import inspect
import re
from dataclasses import dataclass
from typing import Any

__all__ = [
    "ControllerSpec",
    "FactoryError",
    "is_factory_spec",
    "load_factory",
    "controller_from_spec",
]

#: ``module.path:attribute.path`` (Python identifiers separated by dots)
_SPEC = re.compile(r"^[A-Za-z_][\w]*(\.[A-Za-z_][\w]*)*:[A-Za-z_][\w]*(\.[A-Za-z_][\w]*)*$")


class FactoryError(ValueError):
    """A ``MODULE:FACTORY`` that cannot be imported, found, called, or that returned
    something that is not a controller; the message names the string and what to do."""


def is_factory_spec(text) -> bool:
    """True if ``text`` has the form ``MODULE:FACTORY`` (a string; nothing is imported)."""
    return isinstance(text, str) and bool(_SPEC.match(text.strip()))


def load_factory(spec: str):
    """The callable that ``spec`` (``MODULE:FACTORY``) names; :class:`FactoryError` if the
    string is malformed, the module cannot be imported or has no such attribute."""
    if not is_factory_spec(spec):
        raise FactoryError(
            f"controller {spec!r} is not of the form MODULE:FACTORY "
            "(e.g. 'my_controllers:make', a function in my_controllers.py "
            "that returns a controller)"
        )
    module_name, attr_path = spec.strip().split(":")
    try:
        obj = importlib.import_module(module_name)
    except ImportError as exc:
        raise FactoryError(
            f"controller {spec!r}: cannot import module {module_name!r} "
            f"({exc}); put its directory on PYTHONPATH (or run from it) so "
            "that `python -c 'import " + module_name + "'` works"
        ) from exc
    for part in attr_path.split("."):
        if not hasattr(obj, part):
            raise FactoryError(
                f"controller {spec!r}: module {module_name!r} has no attribute {attr_path!r}"
            )
        obj = getattr(obj, part)
    if not callable(obj):
        raise FactoryError(
            f"controller {spec!r}: {attr_path!r} is not callable; it must be "
            "a function (or class) called with (robot, params)"
        )
    return obj


def _call(factory, spec: str, robot, params):
    """``factory(robot, params)``, or with as many of them as it takes."""
    try:
        sig = inspect.signature(factory)
        positional = [
            p
            for p in sig.parameters.values()
            if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)
        ]
        varargs = any(p.kind == p.VAR_POSITIONAL for p in sig.parameters.values())
        n = 2 if varargs else min(2, len(positional))
    except (TypeError, ValueError):  # a builtin without a signature: try both
        n = 2
    try:
        return factory(*(robot, params)[:n])
    except Exception as exc:  # the user's code: say where it failed, not a traceback
        raise FactoryError(
            f"controller {spec!r} failed when called as "
            f"{spec.partition(':')[2]}({', '.join(('robot', 'params')[:n])}) with the "
            f"robot's RobotParameters and the controller settings' ControllerParameters: "
            f"{type(exc).__name__}: {exc}"
        ) from exc


def _is_controller(obj) -> bool:
    from ..parameters import ControllerParameters

    return isinstance(obj, ControllerParameters) or callable(getattr(obj, "command", None))


def controller_from_spec(spec: str, robot=None, params=None):
    """The controller that ``spec`` (``MODULE:FACTORY``) makes for ``robot`` and the
    controller parameters ``params`` (defaults: Scout II's). :class:`FactoryError` if it
    cannot be loaded or does not return a controller."""
    from ..parameters import ControllerParameters, RobotParameters

    robot = RobotParameters() if robot is None else robot
    params = ControllerParameters() if params is None else params
    factory = load_factory(spec)
    controller = _call(factory, spec, robot, params)
    if not _is_controller(controller):
        raise FactoryError(
            f"controller {spec!r} returned {type(controller).__name__}, not "
            "a controller: return ControllerParameters, an object with "
            "command(t, sensors), or a CompiledController"
        )
    return controller


@dataclass(frozen=True)
class ControllerSpec:
    """A controller to be made where it runs: the ``MODULE:FACTORY`` string and what the
    factory is called with. It pickles as the string and the parameter objects, so it can
    be sent to any worker that can import ``MODULE``; :meth:`build` makes the controller
    there."""

    spec: str
    robot: Any = None
    params: Any = None

    def __post_init__(self):
        if not is_factory_spec(self.spec):
            load_factory(self.spec)  # raises FactoryError with the explanation

    def build(self, robot=None):
        """The controller, made for ``robot`` (default: the spec's robot)."""
        return controller_from_spec(self.spec, self.robot if robot is None else robot, self.params)

    def __str__(self):
        return self.spec
