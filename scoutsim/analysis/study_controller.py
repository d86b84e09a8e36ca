"""The controller of a study (basin map, sweep, tuning): what a user may give, checked
before the first point runs, described in the study's settings, and made where a point
runs.

A study's ``controller`` is

- None or a :class:`~scoutsim.parameters.ControllerParameters`: the Table I law;
- a controller object: a :class:`~scoutsim.CompiledController` or any object with the
  controller protocol (:mod:`scoutsim.control.protocol`, ``command(t, sensors)``);
- a :class:`~scoutsim.control.factory.ControllerSpec`, or a ``"MODULE:FACTORY"`` string
  (made into ``ControllerSpec(string, robot, ControllerParameters())`` with the study's
  robot): the controller is made by the factory where the point runs, for that point's
  robot (and controller parameters, in a sweep or a tuning). A factory that returns a
  CompiledController costs one compilation per worker process, not one per point
  (:func:`scoutsim.control.compiled._wrap`).

Runs. Every point's run starts the controller afresh (``reset``, a compiled controller's
state from its initial state): in one process one object runs every point in turn, in
worker processes each has its own copy, so a Python controller must keep no memory of an
earlier run beyond what ``reset`` sets, or the table depends on the number of workers.

Sending. With ``workers`` > 1 or a ``scheduler`` the controller travels to other
processes by pickle: a controller object must pickle, and its class (a CompiledController:
its command function) must be defined at the top level of a module the workers can
import. :func:`check_controller_travels` tries it before the first point runs and refuses
a closure, a lambda, a class defined in a function, an object holding something that does
not pickle, with :class:`~scoutsim.analysis.parallel.NotSendableError` saying which
controller, why and what to do instead. A ControllerSpec always pickles (a string and
parameters); its module must import. Dask workers need scoutsim and the user's modules
importable in their own environment (``PYTHONPATH`` or an installed package), which no
check here can see; a task a Dask worker cannot load is an error of the study.
"""

from __future__ import annotations

import dataclasses
import hashlib
import pickle

from ..control.factory import ControllerSpec, FactoryError, is_factory_spec, load_factory
from ..control.protocol import controller_name
from ..parameters import ControllerParameters
from .parallel import check_sendable, is_importable, leaves_process
from .sweep_points import si_name

__all__ = [
    "study_controller",
    "check_controller_travels",
    "build_controller",
    "check_factory_reads",
    "controller_ranges",
    "describe_controller",
    "controller_label",
    "CONTROLLER_ADVICE",
]

#: what to do instead with a controller that cannot be sent (NotSendableError's end)
CONTROLLER_ADVICE = (
    "define it (its class, or a CompiledController's command function) at the top level of "
    "a module the workers can import (a file on sys.path / PYTHONPATH, or an installed "
    "package), or give the study 'MODULE:FACTORY' (a ControllerSpec: the controller is "
    "made in each worker by a function of such a module), or run with workers=1"
)


def study_controller(controller, robot=None):
    """The controller as the study keeps it: a ``"MODULE:FACTORY"`` string as a
    ControllerSpec with ``robot`` and the default ControllerParameters; a ControllerSpec
    whose factory is imported here once (:class:`~scoutsim.control.factory.FactoryError`
    now, before the first point, if it cannot be); anything else as given."""
    if isinstance(controller, str) and is_factory_spec(controller):
        controller = ControllerSpec(controller.strip(), robot, ControllerParameters())
    if isinstance(controller, ControllerSpec):
        load_factory(controller.spec)
    return controller


def check_controller_travels(controller, workers, scheduler, n_points: int) -> None:
    """:class:`~scoutsim.analysis.parallel.NotSendableError` if the points will run in
    other processes and ``controller`` cannot be sent there (module docstring)."""
    if controller is None or not leaves_process(workers, scheduler, n_points):
        return
    what = f"the controller {controller_label(controller)!r}"
    check_sendable(controller, what, CONTROLLER_ADVICE)
    if isinstance(controller, ControllerSpec):
        module = controller.spec.partition(":")[0]
        if not is_importable(module):
            from .parallel import NotSendableError

            raise NotSendableError(
                f"{what}: module {module!r} was imported here but a worker "
                f"process cannot import it by name; {CONTROLLER_ADVICE}"
            )


def build_controller(controller, robot=None, params: ControllerParameters | None = None):
    """The controller of one run: a ControllerSpec made for ``robot`` (default: the spec's)
    with the controller parameters ``params`` (default: the spec's); anything else as
    given (``params`` then unused)."""
    if isinstance(controller, ControllerSpec):
        if params is not None:
            controller = dataclasses.replace(controller, params=params)
        return controller.build(robot)
    return controller


def check_factory_reads(controller, robot, params: ControllerParameters, ranges: dict) -> None:
    """FactoryError (a ValueError) if a factory (a ControllerSpec) makes the same
    controller at both ends of a study's range of a controller parameter: it does not read
    that field of the parameters it is given, and the study would vary nothing while its
    table, tuning or indices looked like the robot's answer. ``ranges``: {name: (low, high)}, a
    ``controller.<field>`` name as the study takes it (a ``_deg`` angle in degrees), each
    set on ``params`` alone; the two controllers made for ``robot`` are compared by their
    pickles (a compiled controller's: its function, arrays and period). Anything else
    than a ControllerSpec, and a factory that raises or makes a controller that does not
    pickle, is left to the points (reported there, as before)."""
    if not isinstance(controller, ControllerSpec):
        return
    for name, (low, high) in ranges.items():
        si, scale = si_name(name)
        fld = si.partition(".")[2]
        if low == high or not si.startswith("controller."):
            continue
        try:
            made = [
                pickle.dumps(
                    build_controller(
                        controller, robot, dataclasses.replace(params, **{fld: v * scale})
                    )
                )
                for v in (low, high)
            ]
        except Exception:  # noqa: BLE001 - the factory's own failure is the points' to report
            continue
        if made[0] == made[1]:
            raise FactoryError(
                f"{name}: the factory {controller.spec!r} makes the same controller with "
                f"{name} = {low:g} and {high:g}: it does not read {fld} in the "
                "ControllerParameters it is given (make(robot, params)), so the study would "
                "vary nothing; read it in the factory, or vary another parameter"
            )


def controller_ranges(points: list[dict]) -> dict:
    """{name: (lowest, highest)} of the ``controller.<field>`` values of a study's points
    ({name: value as named}), for :func:`check_factory_reads`."""
    out: dict = {}
    for p in points:
        for name, v in p.items():
            if name.startswith("controller."):
                low, high = out.get(name, (v, v))
                out[name] = (min(low, v), max(high, v))
    return out


def controller_label(controller) -> str | None:
    """How a study's settings and messages name the controller (None: Table I)."""
    if controller is None or isinstance(controller, ControllerParameters):
        return None
    if isinstance(controller, ControllerSpec):
        return controller.spec
    return controller_name(controller)


def describe_controller(controller):
    """A JSON-safe description of the controller that stays the same from one session to
    the next (a study's settings, and the key of its checkpoint): Table I's parameters, a
    factory with its parameters, a compiled controller's function, array and period, or
    any other object's class and a hash of its pickle."""
    if controller is None:
        return None
    if isinstance(controller, ControllerParameters):
        return dataclasses.asdict(controller)
    if isinstance(controller, ControllerSpec):
        return {
            "factory": controller.spec,
            "robot": None if controller.robot is None else dataclasses.asdict(controller.robot),
            "params": None if controller.params is None else dataclasses.asdict(controller.params),
        }
    kind = type(controller)
    out = {"class": f"{kind.__module__}.{kind.__qualname__}", "name": controller_label(controller)}
    fn = getattr(controller, "command_function", None)
    if fn is not None:  # a compiled controller: its function and arrays
        cparams = getattr(controller, "controller_parameters", None)
        return out | {
            "command": f"{getattr(fn, '__module__', '')}.{getattr(fn, '__qualname__', fn)}",
            "params": [float(x) for x in controller.params],
            "state": [float(x) for x in controller.initial_state],
            "control_period": float(controller.control_period),
            "controller_parameters": None if cparams is None else dataclasses.asdict(cparams),
        }
    try:
        out["pickle_sha256"] = hashlib.sha256(pickle.dumps(controller)).hexdigest()[:16]
    except Exception:  # noqa: BLE001 - an unpicklable controller runs in one process only
        out["pickle_sha256"] = None
    return out
