"""The work arrays of the sensitivities a run carries (:mod:`.tangent`): the rows of the
extended state, the slots of what they met, and the packing in which a run carries the
arrays (``TangentPack``: five arrays however many parts; :func:`unpacked` gives them back
as a ``TangentWork`` in compiled code)."""

from __future__ import annotations

from collections import namedtuple

import numpy as np
from numba import types
from numba.core import cgutils
from numba.core.imputils import impl_ret_borrowed
from numba.extending import intrinsic
from numba.np.arrayobj import populate_array

from ..._numba.jit import kernel
from ..model.derivative.evaluate import derivative_workspace
from ..model.evaluate import NSTIFF
from ..model.layout import NAUX, NEV, NEVBUF, NIMP, NMF, NMI, NS
from .ark import Z_COLS, Z_ROWS
from .dopri5 import eval_workspace
from .stats import NSTAT
from .work import StepEnergy, StepWork

# rows of Phi (the extended state x)
X_S = 0  # the plant state s (layout.NS)
X_MF = NS  # the toe anchors (layout.MF_*)
X_CMD = NS + NMF  # the held commands [N m]
X_CS = NS + NMF + 2  # the controller state (its own layout)

# rows of ``ft`` (the flow's derivative, all columns at once: :mod:`.tangent_flow`)
FT_Y = 0  # a stage's state's tangents (NS)
FT_K = NS  # the stages' derivatives' (7 x NS: stage k's from row FT_K + k NS)
FT_MF = 8 * NS  # the anchors' tangents (NMF)
FT_CMD = 8 * NS + NMF  # the commands' tangents (2)
FT_SIZE = FT_CMD + 2

# slots of info
TI_NONSMOOTH = 0  # resets where a perturbed copy ended in other modes than the run
#: smallest transversality |n.f-| / (|n| |f-|) of a located event, |n| taken along the
#: carried state directions (1: none)
TI_GRAZING = 1
TI_EVENTS = 2  # located events differentiated
TI_UNSUPPORTED = 3  # samples whose readings are not differentiated (a measurement model)
#: the smallest time [s] from a control sample to the zero of an armed event function
#: that was approaching it over the period's last step (linear extrapolation; 1: none):
#: an event that close to a sample boundary moves to the other side of it under a
#: perturbation of that size, where the sampled map jumps
TI_SAMPLE_MARGIN = 4
NTI = 5

#: rows of the scratch event log the perturbed copies' transitions write to (a transition
#: and its settling log a few records; log_event drops any beyond)
EVENT_SCRATCH_ROWS = 16
#: relative size of the central-difference step along a column (of the largest entry of
#: the column, in the state's units): the copies' rounding over it is most of the exact
#: Jacobian's noise (docs/explanation/derivatives.md; 1e-6 left twice as much of it)
DIFFERENCE_STEP = 1e-5

#: What the sensitivities work on: ``Phi`` (NX x m, the derivatives), ``out`` (NX x
#: (m + 1) scratch: the columns being built), ``work`` (a ``StepWork`` of its own: the
#: flow's stages, evaluated again, and the perturbed copies' evaluations), the snapshot of the state before a reset (``s0``, ``mf0``, ``mi0``,
#: ``f0`` its vector field; ``cmd0``, ``cs0``, ``ls0`` before a control sample), the
#: perturbed copies (``sp``, ``mfp``, ``mip``, ``auxp``, ``cmdp``, ``csp``, ``lsp``,
#: ``trp``, ``yp``, ``ep``, ``ds``), a scratch event log (``ev``, ``stats``, ``imp``), the
#: column's event-function differences ``gd`` (m + 1), ``info`` (``TI_*``) and the
#: difference step ``delta`` (one entry); the parameters' derivatives ``dP``, ``dC``,
#: ``dcp``, ``pscale`` and the moved copies ``Pp``, ``Cp``, ``cpp`` (:func:`tangent_work`);
#: for the flow's derivative stage by stage (:mod:`.tangent_flow`): the stages' tangents
#: ``Kt`` (the ARK flows': 7 rows per column, NS), the ARK splitting's per column ``Zt`` (``Z_ROWS`` rows
#: per column), a column's stage state's tangent ``yt`` (NS), the columns' stage states,
#: stage derivatives, anchors and commands ``ft`` (rows ``FT_*``, m columns), a column's
#: tangents of the commands ``cmdt``, each column's tangent of the packed parameters ``Pt``
#: (m x len(P)) and the right-hand side derivative's scratch ``dw`` (m columns); a
#: sample's readings' tangents ``ytr`` (the Table I law's sample in closed form).
TangentWork = namedtuple(
    "TangentWork",
    "Phi out work s0 mf0 mi0 f0 cmd0 cs0 ls0 sp mfp mip auxp cmdp csp lsp trp yp ep ds "
    "ev stats imp gd w info delta dP dC dcp pscale Pp Cp cpp Kt Zt yt ft cmdt Pt dw ytr",
)

#: What a run carries (in ``Carry.tangent`` and ``AdvanceScratch.tan``): ``Phi`` and
#: ``info`` as in ``TangentWork``, and every other array of the ``TangentWork`` packed
#: into one float buffer ``f`` and one int buffer ``i``, whose header holds, for each
#: part k (the ``TangentWork`` leaves other than ``Phi`` and ``info``, depth first), its
#: start and stop in ``f`` or ``i`` and its rows and columns (0, 0: a vector). Five arrays, not
#: fifty: a tuple of arrays is passed to a compiled call as its arrays' fields, one
#: argument each, and a plain run pays for every one of them on each control period.
#: :func:`unpacked` gives the ``TangentWork`` back (views, no copy). ``calls``: the table
#: through which the run calls the sensitivities (:mod:`.tangent_call`; int64, one row per
#: argument: address, rows, columns).
TangentPack = namedtuple("TangentPack", "Phi info f i calls")

# rows of the table ``TangentPack.calls`` (:mod:`.tangent_call`): the C function's address (column 0), then for
# each array argument its address, rows and columns (1 for a vector)
A_HOOK = 0  # the hooks' addresses: columns HOOK_OPS, HOOK_FLOW
A_S = 1  # the state [layout.NS]
A_P = 2  # the packed robot parameters
A_MI = 3  # the modes (int64)
A_MF = 4  # the toe anchors [m]
A_CMD = 5  # the held commands [N m]
A_F = 6  # a vector field (the state's derivative) at the state
A_SF0 = 7  # the ARK splitting factors (matrix)
A_ARMED = 8  # the armed events (bool, one byte each)
A_E_START = 9  # the event functions at the step's start
A_E_END = 10  # ... and end
A_C = 11  # the Table I law's parameters
A_GEOM = 12  # the control block's sensor geometry
A_INTS = 13  # ... its integers (int64)
A_PARAMS = 14  # ... a compiled controller's parameters
A_STATE = 15  # ... the controller's state
A_LS = 16  # the leg states (int64)
A_PHI = 17  # the pack: Phi (matrix)
A_INFO = 18  # ... info
A_FLOATS = 19  # ... its float buffer
A_INTEGERS = 20  # ... its int buffer (int64)
N_CALL_ROWS = 21
#: the columns of row A_HOOK: every operation but a flow, the flow of the run's method
HOOK_OPS, HOOK_FLOW = 0, 1
#: the columns of a row of the table
CALL_ADDRESS, CALL_ROWS, CALL_COLS = 0, 1, 2


#: the header entries of a part in ``TangentPack.i``: start, stop, rows, columns
PART_START, PART_STOP, PART_ROWS, PART_COLS = 0, 1, 2, 3
PART_HEADER = 4


def tangent_work(
    m: int,
    n_state: int,
    n_readings: int,
    tolerances: tuple[float, float],
    sizes: tuple[int, int, int],
    parameters=None,
) -> TangentWork:
    """The work arrays (a ``TangentWork``) for ``m`` columns (0: a run without
    sensitivities), a controller state of ``n_state`` entries and ``n_readings`` sensor
    readings; ``tolerances``: the run's (rtol [-], atol [state units]) (the perturbed
    steps' error estimate is not used); ``sizes``: the lengths of the packed robot
    parameters P, the Table I law's C and the compiled controller's parameters.
    ``parameters``: None, or (dP, dC, dcp, pscale) for n_p parameters carried as the last
    n_p rows of x (constant along the run): each one's derivative of P, C and the
    controller's parameters (n_p x size) and the scale of its packed values (1 / the
    largest |P_k| it moves, so that a difference step is relative).
    ``Phi`` starts at zero: the caller seeds it."""
    rtol, atol = tolerances
    n_P, n_C, n_cp = sizes
    if parameters is None:
        parameters = (np.zeros((0, n_P)), np.zeros((0, n_C)), np.zeros((0, n_cp)), np.zeros(0))
    dP, dC, dcp, pscale = (np.ascontiguousarray(a, dtype=float) for a in parameters)
    n_par = pscale.shape[0]
    nx = X_CS + n_state + n_par
    info = np.zeros(NTI)
    info[TI_GRAZING] = 1.0
    info[TI_SAMPLE_MARGIN] = 1.0
    sf = (NS, 2 * NSTIFF)
    none = np.zeros(0)
    work = StepWork(
        np.zeros((7, NS)),
        np.zeros(NS),
        np.zeros(NAUX),
        np.zeros(NS),
        eval_workspace(),
        np.zeros(sf),
        np.zeros(sf),
        np.zeros((Z_ROWS, Z_COLS)),
        float(rtol),
        float(atol),
        StepEnergy(none, none, none, none),
    )
    return TangentWork(
        np.zeros((nx, m)),
        np.zeros((nx, m + 1)),
        work,
        np.zeros(NS),
        np.zeros(NMF),
        np.zeros(NMI, dtype=np.int64),
        np.zeros(NS),
        np.zeros(2),
        np.zeros(n_state),
        np.zeros(2, dtype=np.int64),
        np.zeros(NS),
        np.zeros(NMF),
        np.zeros(NMI, dtype=np.int64),
        np.zeros(NAUX),
        np.zeros(2),
        np.zeros(n_state),
        np.zeros(2, dtype=np.int64),
        np.zeros(2, dtype=np.int64),
        np.zeros(n_readings),
        np.zeros(NEV),
        np.zeros(NS),
        np.zeros((EVENT_SCRATCH_ROWS, NEVBUF)),
        np.zeros(NSTAT),
        np.zeros(NIMP),
        np.zeros(m + 1),
        np.zeros(nx),
        info,
        np.array([DIFFERENCE_STEP]),
        dP,
        dC,
        dcp,
        pscale,
        np.zeros(n_P),
        np.zeros(n_C),
        np.zeros(n_cp),
        np.zeros((7 * m, NS)),
        np.zeros((Z_ROWS * m, Z_COLS)),
        np.zeros(NS),
        np.zeros((FT_SIZE, m)),
        np.zeros(2),
        np.zeros((m, n_P)),
        derivative_workspace(m),
        np.zeros(n_readings),
    )


def _leaves(tree):
    """The arrays and numbers of a tree of tuples, depth first."""
    for x in tree:
        if isinstance(x, tuple):
            yield from _leaves(x)
        else:
            yield x


def packed(tw: TangentWork) -> TangentPack:
    """``tw`` as a ``TangentPack`` (its parts copied; :func:`unpacked` is the inverse)."""
    parts = [
        np.atleast_1d(np.asarray(leaf))
        for name, x in zip(tw._fields, tw)
        if name not in ("Phi", "info")
        for leaf in (_leaves(x) if isinstance(x, tuple) else (x,))
    ]
    header = np.zeros(PART_HEADER * len(parts), dtype=np.int64)
    floats: list[np.ndarray] = []
    ints: list[np.ndarray] = []
    n_f, n_i = 0, header.shape[0]
    for k, x in enumerate(parts):
        integer = np.issubdtype(x.dtype, np.integer)
        start = n_i if integer else n_f
        header[PART_HEADER * k + PART_START] = start
        header[PART_HEADER * k + PART_STOP] = start + x.size
        header[PART_HEADER * k + PART_ROWS] = x.shape[0] if x.ndim == 2 else 0
        header[PART_HEADER * k + PART_COLS] = x.shape[1] if x.ndim == 2 else 0
        (ints if integer else floats).append(x.ravel())
        if integer:
            n_i += x.size
        else:
            n_f += x.size
    f = np.concatenate(floats).astype(float) if floats else np.zeros(0)
    i = np.concatenate([header] + [x.astype(np.int64) for x in ints])
    return TangentPack(
        np.ascontiguousarray(tw.Phi), tw.info, f, i, np.zeros((N_CALL_ROWS, 3), dtype=np.int64)
    )


def pointer_to(ty):
    """A compiled function: an address (int64) as a pointer to ``ty``."""

    @intrinsic
    def pointer(typingctx, address):
        sig = types.CPointer(ty)(types.int64)

        def codegen(context, builder, signature, args):
            return builder.inttoptr(args[0], context.get_value_type(signature.return_type))

        return sig, codegen

    return pointer


float_pointer = pointer_to(types.float64)


@intrinsic
def _as_matrix(typingctx, vec, rows, cols):
    """The contiguous float vector ``vec`` seen as a ``rows`` x ``cols`` C-order matrix (a
    view: its data and owner). What ``reshape`` does, without its call into Numba's C
    helpers, which the compiler cannot leave out where the view is not used."""
    ret = types.Array(types.float64, 2, "C")
    sig = ret(vec, rows, cols)

    def codegen(context, builder, signature, args):
        v, r, c = args
        src = context.make_array(signature.args[0])(context, builder, v)
        out = context.make_array(ret)(context, builder)
        intp = context.get_value_type(types.intp)
        itemsize = context.get_constant(types.intp, 8)
        populate_array(
            out,
            data=src.data,
            shape=cgutils.pack_array(builder, [r, c], ty=intp),
            strides=cgutils.pack_array(builder, [builder.mul(c, itemsize), itemsize], ty=intp),
            itemsize=itemsize,
            meminfo=src.meminfo,
            parent=src.parent,
        )
        # (a view: a reference to its owner, counted where reference counting is on)
        return impl_ret_borrowed(context, builder, ret, out._getvalue())

    return sig, codegen


@kernel(inline="always")
def _fv(pack, k):
    """Part ``k`` of ``pack``: a float vector (a view)."""
    h = pack.i
    return pack.f[h[PART_HEADER * k + PART_START] : h[PART_HEADER * k + PART_STOP]]


@kernel(inline="always")
def _fm(pack, k):
    """Part ``k`` of ``pack``: a float matrix (a view)."""
    h = pack.i
    return _as_matrix(_fv(pack, k), h[PART_HEADER * k + PART_ROWS], h[PART_HEADER * k + PART_COLS])


@kernel(inline="always")
def _iv(pack, k):
    """Part ``k`` of ``pack``: an int vector (a view)."""
    h = pack.i
    return h[h[PART_HEADER * k + PART_START] : h[PART_HEADER * k + PART_STOP]]


@kernel(inline="always")
def unpacked(pack):
    """The ``TangentWork`` of a ``TangentPack``: views of its buffers, the parts in the
    order of the fields of ``TangentWork`` (and, inside it, of ``StepWork``, the
    evaluation workspace and ``StepEnergy``). Compiled callers only (it is inlined into
    them: a compiled function may return views of its arguments only if inlined)."""
    work = StepWork(
        _fm(pack, 1),
        _fv(pack, 2),
        _fv(pack, 3),
        _fv(pack, 4),
        (_fv(pack, 5), _fm(pack, 6), _iv(pack, 7), _fm(pack, 8)),
        _fm(pack, 9),
        _fm(pack, 10),
        _fm(pack, 11),
        _fv(pack, 12)[0],
        _fv(pack, 13)[0],
        StepEnergy(_fv(pack, 14), _fv(pack, 15), _fv(pack, 16), _fv(pack, 17)),
    )
    return TangentWork(
        pack.Phi,
        _fm(pack, 0),
        work,
        _fv(pack, 18),
        _fv(pack, 19),
        _iv(pack, 20),
        _fv(pack, 21),
        _fv(pack, 22),
        _fv(pack, 23),
        _iv(pack, 24),
        _fv(pack, 25),
        _fv(pack, 26),
        _iv(pack, 27),
        _fv(pack, 28),
        _fv(pack, 29),
        _fv(pack, 30),
        _iv(pack, 31),
        _iv(pack, 32),
        _fv(pack, 33),
        _fv(pack, 34),
        _fv(pack, 35),
        _fm(pack, 36),
        _fv(pack, 37),
        _fv(pack, 38),
        _fv(pack, 39),
        _fv(pack, 40),
        pack.info,
        _fv(pack, 41),
        _fm(pack, 42),
        _fm(pack, 43),
        _fm(pack, 44),
        _fv(pack, 45),
        _fv(pack, 46),
        _fv(pack, 47),
        _fv(pack, 48),
        _fm(pack, 49),
        _fm(pack, 50),
        _fv(pack, 51),
        _fm(pack, 52),
        _fv(pack, 53),
        _fm(pack, 54),
        _fm(pack, 55),
        _fv(pack, 56),
    )


@kernel(inline="always")
def carrying(pack):
    """True if the run carries sensitivities (``Phi`` has columns)."""
    return pack.Phi.shape[1] > 0
