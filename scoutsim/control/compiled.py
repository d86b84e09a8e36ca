"""Controllers that run inside the compiled loop, called through a function pointer.

The run loop (:mod:`scoutsim._core.loop`) is compiled once; it calls a controller that is not the
built-in Table I law through the controller function's machine address, with one fixed C
signature (:data:`CONTROLLER_SIGNATURE`)::

    int64 command(double t, double *sensors, double *params, int64 n_params,
                  double *state, int64 n_state, double *torque, int64 *leg_states)

So writing or editing a controller compiles that controller alone (seconds), never the
simulator core again. Two kinds of controller have such a function:

* :class:`CompiledController`: a user's Numba-compilable Python function, wrapped in a
  C callback (``numba.cfunc``) when the controller is made;
* any Python controller object (``command(t, sensors)``), through a ``ctypes`` callback made
  by :mod:`scoutsim.control.dispatch`, so even a plain Python controller runs inside the
  compiled loop, without a return to Python's run loop at every sample.

Writing a compiled controller::

    import numpy as np
    from scoutsim.control import CompiledController, sensors as S

    def pd(t, y, params, state, torque, leg_states):
        # y: the sensor readings (slots S.HIP_ANGLE, S.PITCH, ...; SI units)
        for leg in range(2):
            torque[leg] = params[0] * (params[2 + leg] - y[S.HIP_ANGLE + leg]) \\
                - params[1] * y[S.HIP_RATE + leg]
        return 0

    ctrl = CompiledController(pd, params=np.array([250.0, 5.0, 0.33, 0.37]))
    scoutsim.simulate(controller=ctrl)

The function must compile with ``numba.njit`` (nopython mode). It writes the hip torques
per physical leg at the leg [N m] (back, front) into ``torque``, may update its ``state``
and ``leg_states`` (logged with the run: the codes of :class:`~scoutsim.names.LegState`), and returns 0, or any other
integer to stop the run with a :class:`~scoutsim.control.protocol.ControllerError`; so do
torques that are not finite.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic

from .._core.model import layout as L
from .protocol import DEFAULT_CONTROL_PERIOD, Controller

if TYPE_CHECKING:
    from ..parameters import ControllerParameters

__all__ = ["CompiledController", "CONTROLLER_SIGNATURE", "call_controller"]

#: the C signature of a controller function (see the module docstring)
CONTROLLER_SIGNATURE = types.int64(
    types.float64,
    types.CPointer(types.float64),
    types.CPointer(types.float64),
    types.int64,
    types.CPointer(types.float64),
    types.int64,
    types.CPointer(types.float64),
    types.CPointer(types.int64),
)


@intrinsic
def call_controller(typingctx, address, t, sensors, params, state, torque, leg_states):
    """Call the controller function at machine ``address`` (:data:`CONTROLLER_SIGNATURE`)
    with the data of the given arrays; returns its int64 status. The address is a run-time
    value: the caller compiles once for every controller."""
    sig = types.int64(address, t, sensors, params, state, torque, leg_states)

    def codegen(context, builder, signature, args):
        a_addr, a_t, a_y, a_p, a_st, a_tau, a_ls = args
        ty = signature.args

        def array(i, value):
            return context.make_array(ty[i])(context, builder, value)

        y, p, st, tau, ls = (
            array(2, a_y),
            array(3, a_p),
            array(4, a_st),
            array(5, a_tau),
            array(6, a_ls),
        )
        i64 = ir.IntType(64)
        dbl = ir.DoubleType()
        fnty = ir.FunctionType(
            i64,
            [
                dbl,
                dbl.as_pointer(),
                dbl.as_pointer(),
                i64,
                dbl.as_pointer(),
                i64,
                dbl.as_pointer(),
                i64.as_pointer(),
            ],
        )
        fn = builder.inttoptr(a_addr, fnty.as_pointer())
        return builder.call(
            fn, [a_t, y.data, p.data, p.nitems, st.data, st.nitems, tau.data, ls.data]
        )

    return sig, codegen


#: the C callbacks compiled in this process, by their command function: a controller made
#: again from the same function (a copy sent to a worker process, a controller a factory
#: makes for every point of a study) does not compile it again
_CALLBACKS: dict = {}


def wrap_command(command):
    """The C callback (``numba.cfunc``) of a Numba-compilable ``command(t, y, params, state,
    torque, leg_states)``: compiles ``command`` and the wrapper, nothing else; once per
    process and function (:data:`_CALLBACKS`)."""
    try:
        return _CALLBACKS[command]
    except (KeyError, TypeError):  # (TypeError: an unhashable callable, never cached)
        pass
    wrapper = _compile_callback(command)
    try:
        _CALLBACKS[command] = wrapper
    except TypeError:
        pass
    return wrapper


def _compile_callback(command):
    """:func:`wrap_command` without the cache."""
    from numba import carray, cfunc, njit

    inner = njit(command)
    nsn = L.NSN

    @cfunc(CONTROLLER_SIGNATURE)
    def wrapper(t, y, params, n_params, state, n_state, torque, leg_states):
        return inner(
            t,
            carray(y, nsn),
            carray(params, n_params),
            carray(state, n_state),
            carray(torque, 2),
            carray(leg_states, 2),
        )

    return wrapper


class CompiledController(Controller):
    """A controller whose command runs compiled inside the simulator's loop.

    Parameters
    ----------
    command : function ``command(t, y, params, state, torque, leg_states) -> int``
        Numba-compilable (nopython). ``t`` [s] the sample time; ``y`` the sensor readings
        (float64 array, slots :mod:`scoutsim.control.sensors` ``HIP_ANGLE`` ... ``BATTERY``,
        SI units); ``params`` and ``state`` this controller's arrays; ``torque`` (2,) the
        output, hip torque per physical leg at the leg [N m], back then front, held for
        one control period; ``leg_states`` (2,) int64, the leg states to log (0 flight,
        1 stance-retraction, 2 stance-brake; optional). Returns 0 to go on, anything else
        to stop the run with a ControllerError.
    params : array-like, optional
        The controller's parameters (float64, read-only by convention), given to every call.
    state : array-like, optional
        The controller's initial state (float64): every run starts from a copy of it.
    control_period : float
        Sample-and-hold period [s] (default 1 ms, the paper's 1 kHz loop).
    name : str, optional
        How errors and provenance name it (default: the function's name).

    Attributes
    ----------
    compile_time_s : float
        Wall time [s] it took to compile ``command`` and its C wrapper.
    address : int
        Machine address of the C wrapper (what the run loop calls).

    A compiled controller pickles (so it can run in the worker processes of a parallel
    study, or on a Dask worker) when ``command`` is defined at the top level of a module
    the worker can import: the function travels by its module and name, with
    ``params``, ``state``, ``control_period``, ``name`` and a subclass's own attributes,
    and the worker wraps it again (compiled once per process and function).
    """

    def __init__(
        self,
        command,
        params=None,
        state=None,
        *,
        control_period: float = DEFAULT_CONTROL_PERIOD,
        name: str | None = None,
    ):
        self.command_function = command
        self.params = np.array([] if params is None else params, dtype=np.float64).ravel()
        self.initial_state = np.array([] if state is None else state, dtype=np.float64).ravel()
        self.control_period = float(control_period)
        self.name = name or getattr(command, "__name__", type(self).__name__)
        self._compile()
        self.leg_states = np.zeros(2, dtype=np.int64)

    def _compile(self) -> None:
        """Wrap ``command_function`` in its C callback (compiled once per process and
        function) and set ``_cfunc``, ``address`` and ``compile_time_s``."""
        t0 = time.perf_counter()
        try:
            self._cfunc = wrap_command(self.command_function)
        except Exception as exc:
            raise TypeError(
                f"CompiledController({self.name}): the command function does not "
                f"compile with Numba (nopython mode) for command(t, y, params, "
                f"state, torque, leg_states): {exc}"
            ) from exc
        self.compile_time_s = time.perf_counter() - t0
        self.address = int(self._cfunc.address)

    # Pickling (a copy for a worker process, a Dask worker, copy.copy): everything but the
    # compiled callback and its address, which belong to this process; the command function
    # pickles by reference (its module and qualified name), so it must be defined at the
    # top level of a module the receiving process can import. Unpickling wraps it again
    # (compiled once per process). A subclass's own attributes travel with the rest of the
    # instance dictionary; its __init__ is not called again.
    _NOT_PICKLED = ("_cfunc", "address", "compile_time_s", "_py_state")

    def __getstate__(self):
        return {k: v for k, v in self.__dict__.items() if k not in self._NOT_PICKLED}

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._compile()

    #: the Table I parameters the controller builds on, if any
    #: (:class:`~scoutsim.parameters.ControllerParameters`): a run then starts its legs at
    #: their touchdown angles and reads the hip encoders on the side they say, as for the
    #: Table I controller, and records them in its provenance
    controller_parameters: ControllerParameters | None = None

    def params_for(self, robot):
        """The parameter array a run of ``robot`` (a
        :class:`~scoutsim.parameters.RobotParameters`) gives the function (the default:
        ``params``; a subclass that packs robot constants packs the run's robot's)."""
        return self.params

    def reset(self, robot, sensors):
        """Called before a run (the default does nothing): a subclass may set
        ``self.initial_state`` from the robot and the first readings."""

    def command(self, t, sensors):
        """One command from Python (for testing the function; :func:`scoutsim.simulate`
        calls the compiled function directly): hip torques (back, front) [N m] for the
        readings ``sensors`` (a :class:`~scoutsim.control.sensors.Sensors`). Updates a
        state of its own, started from ``initial_state`` at the first call."""
        if not hasattr(self, "_py_state"):
            self._py_state = self.initial_state.copy() if self.initial_state.size else np.zeros(1)
        params = self.params if self.params.size else np.zeros(1)
        torque = np.zeros(2)
        rc = self._cfunc.ctypes(
            float(t),
            _ptr(sensors.vector, np.float64),
            _ptr(params),
            params.size,
            _ptr(self._py_state),
            self._py_state.size,
            _ptr(torque),
            _ptr(self.leg_states, np.int64),
        )
        if rc != 0:
            raise RuntimeError(f"{self.name} returned status {rc}")
        return float(torque[0]), float(torque[1])

    def __repr__(self):
        return (
            f"CompiledController({self.name}, params={self.params.size}, "
            f"state={self.initial_state.size}, control_period={self.control_period})"
        )


def _ptr(a, dtype=np.float64):
    import ctypes

    a = np.ascontiguousarray(a, dtype=dtype)
    ctype = ctypes.c_double if dtype == np.float64 else ctypes.c_int64
    return a.ctypes.data_as(ctypes.POINTER(ctype))
