"""The run's calls into the carried sensitivities (:mod:`.tangent`), by address.

The integrator and the control loop call the sensitivities at every step, event, sample and
projection of a run that carries them. Called directly, their code (the steps' stages,
transitions, the controller: much of the simulator again) would be compiled into the run
loop, and every run would pay for it, in compile time, whether it carries derivatives or
not (Numba links a callee's code into each caller and optimizes it there again: the first
compile of ``scoutsim run`` took 106 s of CPU against 58 s without them). So the run calls
them through one C function, compiled on its own and only when a run first carries
sensitivities (:func:`hook_address`), the way it calls a user's compiled controller
(:func:`~scoutsim.control.compiled.call_controller`):

- each function here (:func:`projection`, :func:`flow`, :func:`snapshot`, :func:`reset`,
  :func:`margin`, :func:`keep`, :func:`sample`) writes the addresses and shapes of its
  arrays into the pack's table ``calls`` (rows ``A_*``: address, rows, columns) and calls
  a C function with the operation (``OP_*``), one integer, two numbers and the table:
  the flow of a step the method's (``calls[A_HOOK, HOOK_FLOW]``, :func:`_run_flow_dopri5` and its
  like, one per integration method), every other operation the one of all methods
  (``calls[A_HOOK, HOOK_OPS]``, :func:`_run_op`);
- the C function makes arrays of the addresses again and calls the function of
  :mod:`.tangent` the operation names.

The address is the process's: :meth:`~scoutsim.simulation.engine.HybridEngine.advance` sets
it before every run that carries columns (an engine copied to another process gets that
process's). A run that carries none never calls it.
"""

from __future__ import annotations

import functools

from llvmlite import ir
from numba import carray, types
from numba.extending import intrinsic

from ..._numba.jit import allocating, c_function, kernel
from .stepper import METHOD_ARK3, METHOD_ARK4, METHOD_DOPRI5
from .tangent import (
    keep_controller,
    sample_margin,
    tangent_projection,
    tangent_reset,
    tangent_sample,
)
from .tangent import (
    snapshot as tangent_snapshot,
)
from .tangent_flow import flow_ark3, flow_ark4, flow_dopri5
from .tangent_work import (
    A_ARMED,
    A_C,
    A_CMD,
    A_E_END,
    A_E_START,
    A_F,
    A_FLOATS,
    A_GEOM,
    A_HOOK,
    A_INFO,
    A_INTEGERS,
    A_INTS,
    A_LS,
    A_MF,
    A_MI,
    A_P,
    A_PARAMS,
    A_PHI,
    A_S,
    A_SF0,
    A_STATE,
    CALL_ADDRESS,
    CALL_COLS,
    CALL_ROWS,
    HOOK_FLOW,
    HOOK_OPS,
    N_CALL_ROWS,
    TangentPack,
    float_pointer,
    pointer_to,
)

# the operations
OP_PROJECTION, OP_FLOW, OP_SNAPSHOT, OP_RESET, OP_MARGIN, OP_KEEP, OP_SAMPLE = range(7)

#: the C signature of the hook: (operation, an integer, two numbers, the table) -> 0
HOOK_SIGNATURE = types.int64(
    types.int64, types.int64, types.float64, types.float64, types.CPointer(types.int64)
)


# --- the run's side: put the arrays in the table and call ------------------------------


@kernel
def _put(calls, row, x):
    """Row ``row`` of the table: vector ``x``'s address and length."""
    calls[row, CALL_ADDRESS] = x.ctypes.data
    calls[row, CALL_ROWS] = x.shape[0]
    calls[row, CALL_COLS] = 1


@kernel
def _put_matrix(calls, row, x):
    """Row ``row`` of the table: matrix ``x``'s address and shape (C order)."""
    calls[row, CALL_ADDRESS] = x.ctypes.data
    calls[row, CALL_ROWS] = x.shape[0]
    calls[row, CALL_COLS] = x.shape[1]


@intrinsic
def _call_hook(typingctx, address, op, k, a, b, calls):
    """Call the C function at ``address`` (:data:`HOOK_SIGNATURE`) with ``op``, ``k``,
    ``a``, ``b`` and the table's data."""
    sig = types.int64(types.int64, types.int64, types.int64, types.float64, types.float64, calls)

    def codegen(context, builder, signature, args):
        a_addr, a_op, a_k, a_a, a_b, a_calls = args
        table = context.make_array(signature.args[5])(context, builder, a_calls)
        i64 = ir.IntType(64)
        dbl = ir.DoubleType()
        fnty = ir.FunctionType(i64, [i64, i64, dbl, dbl, i64.as_pointer()])
        fn = builder.inttoptr(a_addr, fnty.as_pointer())
        return builder.call(fn, [a_op, a_k, a_a, a_b, table.data])

    return sig, codegen


@kernel
def _call(pack, op, k, a, b):
    """Put the pack's own arrays in its table and call the hook (a flow: the method's)."""
    calls = pack.calls
    _put_matrix(calls, A_PHI, pack.Phi)
    _put(calls, A_INFO, pack.info)
    _put(calls, A_FLOATS, pack.f)
    _put(calls, A_INTEGERS, pack.i)
    hook = calls[A_HOOK, HOOK_FLOW] if op == OP_FLOW else calls[A_HOOK, HOOK_OPS]
    _call_hook(hook, op, k, a, b, calls)


@kernel
def _put_plant(calls, s, P, mi, mf):
    """The rows of the state, the robot's parameters, the modes and the anchors."""
    _put(calls, A_S, s)
    _put(calls, A_P, P)
    _put(calls, A_MI, mi)
    _put(calls, A_MF, mf)


@kernel
def projection(s, P, mi, mf, pack):
    """:func:`~.tangent.tangent_projection`, by address."""
    _put_plant(pack.calls, s, P, mi, mf)
    _call(pack, OP_PROJECTION, 0, 0.0, 0.0)


@kernel
def flow(method, s, h, P, mi, mf, cmd, SF0, pack):
    """The flow's derivative over the step just taken (:mod:`.tangent_flow`, the
    method's), by address."""
    calls = pack.calls
    _put_plant(calls, s, P, mi, mf)
    _put(calls, A_CMD, cmd)
    _put_matrix(calls, A_SF0, SF0)
    _call(pack, OP_FLOW, method, h, 0.0)


@kernel
def snapshot(s, mi, mf, f, pack):
    """:func:`~.tangent.snapshot`, by address."""
    calls = pack.calls
    _put(calls, A_S, s)
    _put(calls, A_MI, mi)
    _put(calls, A_MF, mf)
    _put(calls, A_F, f)
    _call(pack, OP_SNAPSHOT, 0, 0.0, 0.0)


@kernel
def reset(k, t, mi, f_plus, P, cmd, pack):
    """:func:`~.tangent.tangent_reset`, by address."""
    calls = pack.calls
    _put(calls, A_MI, mi)
    _put(calls, A_F, f_plus)
    _put(calls, A_P, P)
    _put(calls, A_CMD, cmd)
    _call(pack, OP_RESET, k, t, 0.0)


@kernel
def margin(h, armed, e_start, e_end, pack):
    """:func:`~.tangent.sample_margin`, by address."""
    calls = pack.calls
    _put(calls, A_ARMED, armed)
    _put(calls, A_E_START, e_start)
    _put(calls, A_E_END, e_end)
    _call(pack, OP_MARGIN, 0, h, 0.0)


@kernel
def keep(cmd, cs, ls, pack):
    """:func:`~.tangent.keep_controller`, by address."""
    calls = pack.calls
    _put(calls, A_CMD, cmd)
    _put(calls, A_STATE, cs)
    _put(calls, A_LS, ls)
    _call(pack, OP_KEEP, 0, 0.0, 0.0)


@kernel
def sample(t, s, P, mi, mf, builtin, C, cb, pack):
    """:func:`~.tangent.tangent_sample`, by address (``cb``: the control block)."""
    calls = pack.calls
    _put_plant(calls, s, P, mi, mf)
    _put(calls, A_C, C)
    _put(calls, A_GEOM, cb.geom)
    _put(calls, A_INTS, cb.ints)
    _put(calls, A_PARAMS, cb.params)
    _call(pack, OP_SAMPLE, 1 if builtin else 0, t, 0.0)


# --- the hook's side: the arrays again, and the call -----------------------------------


_int_pointer = pointer_to(types.int64)
_byte_pointer = pointer_to(types.uint8)


@kernel(inline="always")
def _floats(calls, row):
    return carray(float_pointer(calls[row, CALL_ADDRESS]), calls[row, CALL_ROWS])


@kernel(inline="always")
def _float_matrix(calls, row):
    return carray(
        float_pointer(calls[row, CALL_ADDRESS]), (calls[row, CALL_ROWS], calls[row, CALL_COLS])
    )


@kernel(inline="always")
def _ints(calls, row):
    return carray(_int_pointer(calls[row, CALL_ADDRESS]), calls[row, CALL_ROWS])


@kernel(inline="always")
def _plant_of(calls):
    """The state, packed parameters, integer and float modes and held commands the table
    ``calls`` gives (views)."""
    return (
        _floats(calls, A_S),
        _floats(calls, A_P),
        _ints(calls, A_MI),
        _floats(calls, A_MF),
        _floats(calls, A_CMD),
    )


@allocating
def _pack_of(calls):
    """The pack whose arrays the table ``calls`` gives."""
    return TangentPack(
        _float_matrix(calls, A_PHI),
        _floats(calls, A_INFO),
        _floats(calls, A_FLOATS),
        _ints(calls, A_INTEGERS),
        calls,
    )


@allocating
def _run_op(op, k, a, table):
    """Operation ``op`` (any but a flow) on the arrays of the table (module docstring);
    ``k``: the event's slot (a reset), 1 for the built-in law (a sample); ``a``: the step
    [s] (a margin) or the time [s] (a reset, a sample). (Reference counting on: ``carray``
    needs it.)"""
    calls = carray(table, (N_CALL_ROWS, 3))
    pack = _pack_of(calls)
    # (every array of the table, also those this operation does not use: a view of an
    # address left from another call is made, never read)
    s, P, mi, mf, cmd = _plant_of(calls)
    f = _floats(calls, A_F)
    if op == OP_PROJECTION:
        tangent_projection(s, P, mi, mf, pack)
    elif op == OP_SNAPSHOT:
        tangent_snapshot(s, mi, mf, f, pack)
    elif op == OP_RESET:
        tangent_reset(k, a, mi, f, P, cmd, pack)
    elif op == OP_MARGIN:
        armed = carray(_byte_pointer(calls[A_ARMED, CALL_ADDRESS]), calls[A_ARMED, CALL_ROWS])
        sample_margin(a, armed, _floats(calls, A_E_START), _floats(calls, A_E_END), pack)
    elif op == OP_KEEP:
        keep_controller(cmd, _floats(calls, A_STATE), _ints(calls, A_LS), pack)
    elif op == OP_SAMPLE:
        C, geom, params = _floats(calls, A_C), _floats(calls, A_GEOM), _floats(calls, A_PARAMS)
        tangent_sample(a, s, P, mi, mf, k == 1, C, geom, _ints(calls, A_INTS), params, pack)
    return 0


@allocating
def _run_flow_dopri5(h, table):
    """The flow over a Dormand-Prince step of ``h`` [s] on the arrays of the table."""
    calls = carray(table, (N_CALL_ROWS, 3))
    s, P, mi, mf, cmd = _plant_of(calls)
    flow_dopri5(s, h, P, mi, mf, cmd, _pack_of(calls))
    return 0


@allocating
def _run_flow_ark4(h, table):
    """The flow over an ARK4 step of ``h`` [s] on the arrays of the table."""
    calls = carray(table, (N_CALL_ROWS, 3))
    s, P, mi, mf, cmd = _plant_of(calls)
    flow_ark4(s, h, (P, mi, mf, cmd), _float_matrix(calls, A_SF0), _pack_of(calls))
    return 0


@allocating
def _run_flow_ark3(h, table):
    """The flow over an ARK3 step of ``h`` [s] on the arrays of the table."""
    calls = carray(table, (N_CALL_ROWS, 3))
    s, P, mi, mf, cmd = _plant_of(calls)
    flow_ark3(s, h, (P, mi, mf, cmd), _float_matrix(calls, A_SF0), _pack_of(calls))
    return 0


def _entry(op, k, a, b, table):
    return _run_op(op, k, a, table)


def _flow_dopri5(op, k, a, b, table):
    return _run_flow_dopri5(a, table)


def _flow_ark4(op, k, a, b, table):
    return _run_flow_ark4(a, table)


def _flow_ark3(op, k, a, b, table):
    return _run_flow_ark3(a, table)


#: the flow of each method (its steps are the method's)
_FLOWS = {METHOD_DOPRI5: _flow_dopri5, METHOD_ARK4: _flow_ark4, METHOD_ARK3: _flow_ark3}


@functools.cache
def hook_address(which) -> int:
    """The address in this process of a hook: ``"op"`` (every operation but a flow) or a
    method's code (stepper.METHOD_*, not METHOD_AUTO: its flow), compiled (or loaded from
    the disk cache) on the first call."""
    entry = _entry if which == "op" else _FLOWS[which]
    return c_function(HOOK_SIGNATURE, entry).address
