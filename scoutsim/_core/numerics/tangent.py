"""First-order sensitivities of the hybrid flow, carried with a run (compiled).

A run can carry the derivatives ``Phi`` (NX x m) of its extended state

    x = [s (NS), toe anchors mf (NMF), held commands cmd (2), controller state (n_c)]

with respect to m chosen variables (the columns: directions in the start's x, or a
parameter's column). They are obtained by internal differentiation of the integrator
(Bock's internal numerical differentiation): every map the run applies is differentiated
with the run's own discrete choices held (the step sizes, the ARK splitting matrix, the
event sequence and the control samples), so the derivatives are those of the computed
trajectory, not of a neighbouring one integrated with other steps:

- a step from ``s`` of size ``h``: y -> proj(step(y; h)) with the splitting matrix of the
  nominal step, stage by stage with the right-hand side's derivative in closed form
  (:mod:`.tangent_flow`); a Dormand-Prince step across which a motor current meets or
  leaves the torque-speed line is differentiated over sub-steps split at that kink (the
  flow's derivative along the computed trajectory);
- a plant event at ``t_e`` (:func:`tangent_reset` with the event slot): the saltation
  matrix S = DR + (f+ - DR f-) n^T / (n^T f-) (docs/explanation/derivatives.md), with DR
  the derivative of the transition and the settling after it, n the gradient of the event
  function, f-/f+ the vector fields either side; DR and n by central differences of the
  compiled transition and event function, f-/f+ from the run's own evaluations;
- a reset at a fixed instant (a control sample's settling: slot -1): DR only, the
  projection's derivative in closed form where no transition fired
  (:func:`~.tangent_flow.projection_derivative`), else by central differences; a
  projection (:func:`tangent_projection`): in closed form;
- a control sample (:func:`tangent_sample`): the new held commands and controller state
  as functions of the state, the anchors, the old commands and the old controller state
  (zero-order hold), by central differences of the controller on copies of its arrays.

The differences are of smooth maps (each with its discrete choices held), so their error
is that of a central difference (about 1e-9 of the scale here), not that of differencing a
whole adaptive run; the steps, in closed form, add none. The projection's one clamp, a
massive leg in flight held at its stop, is kept out of them: no copy is moved across the
stop of a leg that is short of it (:func:`_difference_ends`). Where a perturbed copy of
a reset ends in other modes than the run (an event that is not transversal, a mode
decided by a margin smaller than the step), the map is not differentiable there:
``info[TI_NONSMOOTH]`` counts such resets, and ``info[TI_GRAZING]`` keeps the smallest
transversality |n^T f-| / (|n| |f-|) met.

A run without sensitivities carries ``Phi`` with no columns: every function here is then
skipped by the caller (a check of ``Phi.shape[1]``), and the run is the same, bit for bit.
"""

from __future__ import annotations

import numpy as np

from ..._numba.jit import kernel
from ...control.bounding import bounding_step, bounding_step_t
from ...control.compiled import call_controller
from ..model.evaluate import evaluate_ws, evaluated_state
from ..model.flags import is_set
from ..model.layout import (
    CB_ADDRESS,
    IALB,
    IL_B,
    IPHB,
    MI_CONTACT_B,
    NMF,
    NMI,
    NQ,
    NS,
    P_C,
    P_G,
    P_L0,
    P_MASSLESS,
    SG_MEASURED,
    SG_MOTOR_SIDE,
    SLIDE,
    SN_ANGLE_B,
    SN_RATE_B,
    STICK,
    STRUT,
)
from ..model.leg import held_at_stop
from ..model.sensor_readings import read_encoders, true_readings
from .events import event_values
from .tangent_flow import projection_derivative
from .tangent_work import (
    TI_EVENTS,
    TI_GRAZING,
    TI_NONSMOOTH,
    TI_SAMPLE_MARGIN,
    TI_UNSUPPORTED,
    X_CMD,
    X_CS,
    X_MF,
    X_S,
    unpacked,
)
from .transitions import apply_event, settle_ws
from .work import EventLog

#: a difference step is shortened to keep the copies of a state off a leg's stop
#: (:func:`_difference_ends`), down to this fraction of the step; a leg closer to its
#: stop is differenced one-sided, away from it
STOP_STEP_FRACTION = 0.1


@kernel(inline="always")
def _column_step(v, tan, rows):
    """The difference step along column ``v``: ``tan.delta`` over its largest magnitude,
    among its first ``rows`` entries (state units) and its parameter rows (relative to
    each parameter's packed values, ``tan.pscale``); 0 for a zero column."""
    scale = 0.0
    for i in range(rows):
        a = abs(v[i])
        if a > scale:
            scale = a
    npar = tan.pscale.shape[0]
    par0 = v.shape[0] - npar
    for i in range(npar):
        a = abs(v[par0 + i]) * tan.pscale[i]
        if a > scale:
            scale = a
    return tan.delta[0] / scale if scale > 0.0 else 0.0


@kernel
def _moved_parameters(e, v, P, tan):
    """The robot's packed parameters ``P`` moved by ``e`` along the parameter rows of
    ``v`` (``tan.dP``: each parameter's derivative of P), into ``tan.Pp``."""
    npar = tan.pscale.shape[0]
    par0 = v.shape[0] - npar
    Pp = tan.Pp
    for k in range(P.shape[0]):
        Pp[k] = P[k]
    for i in range(npar):
        w = e * v[par0 + i]
        if w != 0.0:
            for k in range(P.shape[0]):
                Pp[k] += w * tan.dP[i, k]


@kernel
def _moved_controller(e, v, C, params, tan):
    """The Table I law's parameters ``C`` and a compiled controller's ``params`` moved by
    ``e`` along the parameter rows of ``v``, into ``tan.Cp`` and ``tan.cpp``."""
    npar = tan.pscale.shape[0]
    par0 = v.shape[0] - npar
    for k in range(C.shape[0]):
        tan.Cp[k] = C[k]
    for k in range(params.shape[0]):
        tan.cpp[k] = params[k]
    for i in range(npar):
        w = e * v[par0 + i]
        if w != 0.0:
            for k in range(C.shape[0]):
                tan.Cp[k] += w * tan.dC[i, k]
            for k in range(params.shape[0]):
                tan.cpp[k] += w * tan.dcp[i, k]


@kernel
def _moved_state(e, v, s, mf, tan):
    """The state ``s`` and anchors ``mf`` moved by ``e`` along the direction ``v`` (NX
    rows), into ``tan.sp`` and ``tan.mfp``."""
    for i in range(NS):
        tan.sp[i] = s[i] + e * v[X_S + i]
    for i in range(NMF):
        tan.mfp[i] = mf[i] + e * v[X_MF + i]


@kernel
def _moved_commands(e, v, cmd, tan):
    """The held commands ``cmd`` moved by ``e`` along ``v``, into ``tan.cmdp``."""
    for i in range(2):
        tan.cmdp[i] = cmd[i] + e * v[X_CMD + i]


@kernel
def _central(out, row, j, values, side, span):
    """Column ``j`` of ``out`` from ``row`` on: on the first side (``side`` 0) the
    ``values`` at the difference's first end, on the second their difference with those
    at the second end over ``span`` (the first end's step less the second's)."""
    for i in range(values.shape[0]):
        if side == 0:
            out[row + i, j] = values[i]
        else:
            out[row + i, j] = (out[row + i, j] - values[i]) / span


@kernel(inline="always")
def _stop_margins(v, s, mi, P, tan):
    """How far a copy of the state ``s`` (modes ``mi``) may move along ``v`` each way,
    in units of the step (``e`` as in :func:`_moved_state`, with the parameters moved
    along), before a massive leg in flight that is short of its stop in ``s`` (l < l0)
    reaches the stop, where the projection clamps it: (up, down), the largest ``e`` > 0
    for the copy at +e and at -e (infinite where no such leg moves towards it). A leg
    at its stop in ``s`` is held there by the projection on both sides (its column's
    entry is the stop's own tangent), and a leg in contact has no stop to meet here."""
    up = np.inf
    down = np.inf
    if is_set(P[P_MASSLESS]):
        return up, down
    npar = tan.pscale.shape[0]
    par0 = v.shape[0] - npar
    for leg in range(2):
        mode = mi[MI_CONTACT_B + leg]
        if mode == STICK or mode == STRUT or mode == SLIDE:
            continue
        if held_at_stop(P[P_C + leg], P[P_L0 + leg], s[IL_B + leg]):
            continue
        gap = P[P_L0 + leg] - s[IL_B + leg]
        rate = v[X_S + IL_B + leg]  # the gap closes at this rate per unit e
        for i in range(npar):
            rate -= v[par0 + i] * tan.dP[i, P_L0 + leg]
        if rate > 0.0:
            up = min(up, gap / rate)
        elif rate < 0.0:
            down = min(down, -gap / rate)
    return up, down


@kernel(inline="always")
def _difference_ends(eps, v, s, mi, P, tan):
    """The two ends (e1, e2) of the difference along ``v`` from the state ``s`` (modes
    ``mi``) with step ``eps``: (eps, -eps), unless a copy would reach the stop of a leg
    that is short of it in ``s`` (:func:`_stop_margins`; the projection's clamp
    there is a kink of every map that projects the copy, which a difference across it
    would average with the run's own branch). Then the step is shortened to half the
    distance to the stop, down to STOP_STEP_FRACTION of it; below that, the
    difference is one-sided, (e, 0) or (0, -e), on the side away from the stop."""
    up, down = _stop_margins(v, s, mi, P, tan)
    near = 0.5 * min(up, down)
    if eps <= near:
        return eps, -eps
    if near >= STOP_STEP_FRACTION * eps:
        return near, -near
    if up >= down:
        return min(eps, 0.5 * up), 0.0
    return 0.0, -min(eps, 0.5 * down)


@kernel
def sample_margin(h, armed, e_start, e_end, pack):
    """Keep in ``info[TI_SAMPLE_MARGIN]`` the time from the control sample ending the last
    step (of size ``h`` [s]) to the zero of each armed event function falling over it
    (values ``e_start``, ``e_end`` at its ends), extrapolated linearly."""
    tan = unpacked(pack)
    for k in range(e_end.shape[0]):
        fall = e_start[k] - e_end[k]
        if armed[k] and e_end[k] > 0.0 and fall > 0.0:
            dt = e_end[k] * h / fall
            if dt < tan.info[TI_SAMPLE_MARGIN]:
                tan.info[TI_SAMPLE_MARGIN] = dt


@kernel
def snapshot(s, mi, mf, f, pack):
    """Keep the state before a reset (``s``, modes ``mi``, anchors ``mf``, vector field
    ``f`` there) for :func:`tangent_reset`."""
    tan = unpacked(pack)
    for i in range(NS):
        tan.s0[i] = s[i]
        tan.f0[i] = f[i]
    for i in range(NMI):
        tan.mi0[i] = mi[i]
    for i in range(NMF):
        tan.mf0[i] = mf[i]


@kernel
def _perturbed_copy(e, v, P, cmd, tan):
    """The snapshot (:func:`snapshot`) moved by ``e`` along the direction ``v`` (NX rows),
    projected and evaluated (outputs in ``tan.auxp``) under the snapshot's modes, with the
    packed parameters moved with it (``tan.Pp``)."""
    sp, mfp, mip, auxp, cmdp, ds = tan.sp, tan.mfp, tan.mip, tan.auxp, tan.cmdp, tan.ds
    ew = tan.work.ew
    _moved_state(e, v, tan.s0, tan.mf0, tan)
    _moved_commands(e, v, cmd, tan)
    for i in range(NMI):
        mip[i] = tan.mi0[i]
    _moved_parameters(e, v, P, tan)
    evaluate_ws(sp, tan.Pp, mip, mfp, cmdp, ds, auxp, ew, False, ew[3], True)
    evaluated_state(ew, sp)


@kernel
def _event_slope(k, v, P, cmd, tan):
    """The derivative of event function ``k`` at the snapshot along ``v`` (differences
    between the ends of :func:`_difference_ends`; 0 along a zero direction)."""
    eps = _column_step(v, tan, X_CS)
    if eps == 0.0:
        return 0.0
    e1, e2 = _difference_ends(eps, v, tan.s0, tan.mi0, P, tan)
    _perturbed_copy(e1, v, P, cmd, tan)
    event_values(tan.sp, tan.auxp, tan.Pp, tan.mip, tan.ep)
    g_hi = tan.ep[k]
    _perturbed_copy(e2, v, P, cmd, tan)
    event_values(tan.sp, tan.auxp, tan.Pp, tan.mip, tan.ep)
    return (g_hi - tan.ep[k]) / (e1 - e2)


@kernel
def _reset_derivative(k, t, v, mi, P, cmd, tan, j):
    """The derivative of the reset (event ``k``'s transition if k >= 0, then the
    settling) at the snapshot along ``v``, into the rows of the state and the anchors of
    ``tan.out[:, j]`` (differences between the ends of :func:`_difference_ends`); a copy
    that ends in other modes than the run (``mi``) is counted in ``info[TI_NONSMOOTH]``."""
    out = tan.out
    eps = _column_step(v, tan, X_CS)
    if eps == 0.0:
        for i in range(X_CMD):
            out[i, j] = 0.0
        return
    e1, e2 = _difference_ends(eps, v, tan.s0, tan.mi0, P, tan)
    for side in range(2):
        e = e1 if side == 0 else e2
        _perturbed_copy(e, v, P, cmd, tan)
        Pq = tan.Pp
        if k >= 0:
            apply_event(k, t, tan.sp, Pq, tan.mip, tan.mfp, tan.auxp, tan.ev, 0, tan.stats, tan.imp)
        log = EventLog(tan.ev, tan.stats)
        settle_ws(t, tan.sp, Pq, tan.mip, tan.mfp, tan.cmdp, tan.ds, tan.auxp, log, 0, tan.work.ew)
        for i in range(NMI):
            if tan.mip[i] != mi[i]:
                tan.info[TI_NONSMOOTH] += 1
                break
        _central(out, X_S, j, tan.sp, side, e1 - e2)
        _central(out, X_MF, j, tan.mfp, side, e1 - e2)


@kernel
def tangent_reset(k, t, mi, f_plus, P, cmd, pack):
    """Phi := S Phi across the reset from the snapshot (:func:`snapshot`) to the run's
    state now (modes ``mi``, vector field ``f_plus``).

    For a located event (slot ``k`` >= 0) S is the saltation matrix
    S = DR + (f+ - DR f-) n^T / (n^T f-), applied as S v = DR w + f+ (n.v) / (n.f-) with
    w = v - f- (n.v) / (n.f-), the part of v in the event's surface: the reset is
    differenced only along the surface, so no perturbed copy crosses the event (a copy
    moved along f- would, and could take the other branch of a decision taken at the
    event: a lift-off that might have been a slide). For a reset at a fixed instant
    (k < 0: a sample's settling) S = DR. DR (the transition and the settling after it) and
    n (the gradient of event function k) by central differences."""
    tan = unpacked(pack)
    Phi, out, w, gd, info = tan.Phi, tan.out, tan.w, tan.gd, tan.info
    m = Phi.shape[1]
    if k < 0:
        kept = True
        for i in range(NMI):
            if mi[i] != tan.mi0[i]:
                kept = False
        if kept:
            # no transition fired: the settling only projected the snapshot (its anchors
            # are those of its modes)
            projection_derivative(tan.s0, P, tan.mi0, tan.mf0, tan)
            return
        for j in range(m):
            _reset_derivative(k, t, Phi[:, j], mi, P, cmd, tan, j)
        for j in range(m):
            for i in range(X_CMD):
                Phi[i, j] = out[i, j]
        return
    info[TI_EVENTS] += 1
    for i in range(w.shape[0]):
        w[i] = 0.0
    for i in range(NS):
        w[X_S + i] = tan.f0[i]
    nf = _event_slope(k, w, P, cmd, tan)
    ff = 0.0
    for i in range(NS):
        ff += tan.f0[i] * tan.f0[i]
    nn = 0.0  # the event function's largest slope per unit state along a column
    for j in range(m):
        gd[j] = _event_slope(k, Phi[:, j], P, cmd, tan)
        vv = 0.0
        for i in range(NS):
            vv += Phi[X_S + i, j] * Phi[X_S + i, j]
        if vv > 0.0:
            nn = max(nn, abs(gd[j]) / np.sqrt(vv))
    if nn > 0.0:
        tr = abs(nf) / max(np.sqrt(ff) * nn, 1e-300)
        if tr < info[TI_GRAZING]:
            info[TI_GRAZING] = tr
    for j in range(m):
        c = gd[j] / nf if nf != 0.0 else 0.0
        gd[j] = c
        for i in range(w.shape[0]):
            w[i] = Phi[i, j]
        for i in range(NS):
            w[X_S + i] -= c * tan.f0[i]
        _reset_derivative(k, t, w, mi, P, cmd, tan, j)
    for j in range(m):
        for i in range(NS):
            Phi[X_S + i, j] = out[X_S + i, j] + f_plus[i] * gd[j]
        for i in range(NMF):
            Phi[X_MF + i, j] = out[X_MF + i, j]


@kernel
def tangent_projection(s, P, mi, mf, pack):
    """Phi := D[proj] Phi for the projection of the dependent coordinates at ``s``, in
    closed form (:func:`~.tangent_flow.projection_derivative`)."""
    projection_derivative(s, P, mi, mf, unpacked(pack))


@kernel
def keep_controller(cmd, cs, ls, pack):
    """Keep the held commands, the controller state and the leg states before a control
    sample for :func:`tangent_sample`."""
    tan = unpacked(pack)
    for i in range(2):
        tan.cmd0[i] = cmd[i]
        tan.ls0[i] = ls[i]
    for i in range(cs.shape[0]):
        tan.cs0[i] = cs[i]


@kernel
def _table_i_sample(s, C, geom, tan):
    """The held commands' rows of Phi through a sample of the Table I law with ideal
    sensors, in closed form (:func:`~scoutsim.control.bounding.bounding_step_t`): its
    readings are the state's hip encoders and leg lengths, its leg states those the sample
    switched to (the law run again from the snapshot's), its parameters' tangents those of
    the columns' parameter rows (``tan.dC``)."""
    Phi, yp, ytr, lsp, cmdp, trp, Ct = tan.Phi, tan.yp, tan.ytr, tan.lsp, tan.cmdp, tan.trp, tan.Cp
    motor = is_set(geom[SG_MOTOR_SIDE])
    read_encoders(s, motor, yp)
    for i in range(2):
        lsp[i] = tan.ls0[i]
        cmdp[i] = tan.cmd0[i]
    bounding_step(yp, C, lsp, cmdp, trp)
    i0 = IALB if motor else IPHB
    npar = tan.pscale.shape[0]
    par0 = Phi.shape[0] - npar
    for i in range(ytr.shape[0]):
        ytr[i] = 0.0
    for j in range(Phi.shape[1]):
        for leg in range(2):
            ytr[SN_ANGLE_B + leg] = Phi[X_S + i0 + leg, j]
            ytr[SN_RATE_B + leg] = Phi[X_S + NQ + i0 + leg, j]
        for k in range(Ct.shape[0]):
            Ct[k] = 0.0
        for i in range(npar):
            w = Phi[par0 + i, j]
            if w != 0.0:
                for k in range(Ct.shape[0]):
                    Ct[k] += w * tan.dC[i, k]
        bounding_step_t(yp, C, lsp, (ytr, Ct), tan.cmdt)
        for leg in range(2):
            Phi[X_CMD + leg, j] = tan.cmdt[leg]


@kernel
def tangent_sample(t, s, P, mi, mf, builtin, C, geom, ints, params, pack):
    """Phi's rows of the held commands and the controller state := their derivatives
    through the control sample at ``t`` [s] (zero-order hold): the readings of the state
    (``s``, modes ``mi``, anchors ``mf``; under the old commands), the controller
    (``builtin``: the compiled Table I law with parameters ``C``; else the controller
    function of the control block whose sensor geometry, integers and parameters are
    ``geom``, ``ints``, ``params``), on copies of its arrays (the snapshot of
    :func:`keep_controller`). A measurement model (noise, delay) is not differentiated:
    ``info[TI_UNSUPPORTED]`` counts such samples and the readings' derivative is taken as
    that of the true readings."""
    tan = unpacked(pack)
    Phi, out = tan.Phi, tan.out
    sp, mfp, cmdp, csp, lsp, trp, yp = tan.sp, tan.mfp, tan.cmdp, tan.csp, tan.lsp, tan.trp, tan.yp
    ew, ds, auxp = tan.work.ew, tan.ds, tan.auxp
    m = Phi.shape[1]
    nc = csp.shape[0]
    if is_set(geom[SG_MEASURED]):
        tan.info[TI_UNSUPPORTED] += 1
    elif builtin:
        _table_i_sample(s, C, geom, tan)
        return
    for j in range(m):
        eps = _column_step(Phi[:, j], tan, Phi.shape[0] - tan.pscale.shape[0])
        if eps == 0.0:
            for i in range(2 + nc):
                out[X_CMD + i, j] = 0.0
            continue
        e1, e2 = _difference_ends(eps, Phi[:, j], s, mi, P, tan)
        for side in range(2):
            e = e1 if side == 0 else e2
            _moved_state(e, Phi[:, j], s, mf, tan)
            _moved_commands(e, Phi[:, j], tan.cmd0, tan)
            for i in range(2):
                lsp[i] = tan.ls0[i]
            for i in range(nc):
                csp[i] = tan.cs0[i] + e * Phi[X_CS + i, j]
            _moved_parameters(e, Phi[:, j], P, tan)
            Pq = tan.Pp
            _moved_controller(e, Phi[:, j], C, params, tan)
            # (read as the run reads its state at a sample: the state as it is, its
            # derivative and outputs from an evaluation, which projects a copy)
            if builtin and not is_set(geom[SG_MEASURED]):
                read_encoders(sp, is_set(geom[SG_MOTOR_SIDE]), yp)
            else:
                evaluate_ws(sp, Pq, mi, mfp, cmdp, ds, auxp, ew, False, ew[3], True)
                true_readings(sp, ds, auxp, Pq[P_G], geom, yp)
            if builtin:
                bounding_step(yp, tan.Cp, lsp, cmdp, trp)
            else:
                rc = call_controller(ints[CB_ADDRESS], t, yp, tan.cpp, csp, cmdp, lsp)
                if rc != 0 or not (np.isfinite(cmdp[0]) and np.isfinite(cmdp[1])):
                    tan.info[TI_NONSMOOTH] += 1  # a copy the controller refused
            _central(out, X_CMD, j, cmdp, side, e1 - e2)
            _central(out, X_CS, j, csp, side, e1 - e2)
    for j in range(m):
        for i in range(2 + nc):
            Phi[X_CMD + i, j] = out[X_CMD + i, j]
