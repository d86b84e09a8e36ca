"""The compiled run loop: the controller's samples and the plant's integration between them.

A run is a sequence of control periods (sample k at t = k dt). At each sample the sensors
are read (:func:`sense`, :mod:`scoutsim._core.model.sensor_readings`), the controller (the compiled
Table I law of :mod:`scoutsim.control.bounding`, or a controller function called through
its address, :mod:`scoutsim.control.compiled`) updates the held commands, the plant's
modes are settled and the sample is recorded; then :func:`scoutsim._core.numerics.hybrid.advance` integrates the plant with
located events to the next sample. This module composes the controller and the plant;
the integrator (:mod:`scoutsim._core.numerics`) knows neither the controller nor the run.
"""

from __future__ import annotations

from collections import namedtuple
from collections.abc import Callable

import numpy as np

from .._numba.jit import allocating, kernel
from ..control.bounding import bounding_step
from ..control.compiled import call_controller
from .model.evaluate import evaluate_ws
from .model.flags import FLAG_OFF, FLAG_ON, is_set
from .model.hip_unit import is_geared
from .model.kinematics import project_state
from .model.layout import (
    A_ENERGY,
    A_KKT_OK,
    CB_ADDRESS,
    CB_KIND,
    CB_SEED,
    CB_STATUS,
    CTRL_BUILTIN,
    CTRL_HELD,
    EK_CTRL_LIFTOFF,
    EK_CTRL_SWEEP,
    EK_CTRL_TOUCHDOWN,
    MI_CONTACT_B,
    MI_MOTOR_B,
    NAUX,
    NEV,
    NIMP,
    NMI,
    NQ,
    NS,
    P_G,
    RM_CONTACT_B,
    RM_LEG_STATE_B,
    RM_MOTOR_B,
    SG_MEASURED,
    SG_MOTOR_SIDE,
    ST_CONTROLLER_ERROR,
    ST_NUMERICAL_FAILURE,
    ST_RUNNING,
    TR_LIFTOFF,
    TR_SWEEP,
    TR_TOUCHDOWN,
)
from .model.rigid_body import state_energy_ws
from .model.sensor_readings import measure, read_encoders, true_readings
from .numerics import ark, tangent_call
from .numerics.dopri5 import eval_workspace
from .numerics.events import log_event, mode_violations, stamp_states, stamp_transition
from .numerics.hybrid import HW_EVAL_KEPT, HW_STIFF_VALID, STEP_HEADROOM, AdvanceScratch, advance
from .numerics.stats import S_NFEV
from .numerics.stepper import METHOD_ARK4, METHOD_AUTO, METHOD_DOPRI5
from .numerics.tangent_work import carrying
from .numerics.transitions import settle_ws
from .numerics.work import EventLog, EventWork, StepEnergy, StepWork

__all__ = [
    "run",
    "run_entry",
    "effective_method",
    "record_sample",
    "sense",
    "readings_at",
    "Control",
    "Span",
    "Records",
    "Carry",
]


@kernel
def sense(k, s, P, mi, mf, cmd, kept, cb, ew, s_tmp):
    """Read the sensors at control sample ``k`` into ``cb.y`` (control block,
    :mod:`scoutsim.control.block`): the true readings at the state ``s`` and, if ``kept``,
    the evaluation that ended the last period (``cb.last``), else a fresh one under the
    held command ``cmd`` (the run's first sample; workspace ``ew``, a projected copy of the
    state in ``s_tmp``); then the measurement model if any channel has one."""
    if not kept:
        for i in range(NS):
            s_tmp[i] = s[i]
        project_state(s_tmp, P, mi, mf)
        evaluate_ws(s_tmp, P, mi, mf, cmd, cb.last[:NS], cb.last[NS:], ew, False, ew[3], True)
    true_readings(s, cb.last[:NS], cb.last[NS:], P[P_G], cb.geom, cb.y)
    if is_set(cb.geom[SG_MEASURED]):
        measure(k, cb.spec, cb.ints[CB_SEED], cb.hist, cb.y)


@allocating
def readings_at(k, s, P, mi, mf, cmd, kept, cb):
    """The sensor readings of control sample ``k`` at the state ``s`` (into ``cb.y``),
    before a run (k = 0: what a controller's ``reset`` sees) or between two calls of
    :func:`run`: what the loop reads at the start of its next call
    (the same numbers: the noise is a function of the sample, the delay buffer's row of
    sample ``k`` is written with the same values). ``kept``: the run's last evaluation
    (``cb.last``) is at ``s``, as after a call that ended running (``hwork[HW_EVAL_KEPT]``);
    else a fresh one under ``cmd``."""
    sense(k, s, P, mi, mf, cmd, kept, cb, eval_workspace(), np.zeros(NS))


@kernel
def record_sample(t, s, aux, ls, mi, out_t, out_s, out_aux, out_ls, n_out, energy, out_energy):
    """Append one row (time, state, outputs, leg states and modes) to the time series, and
    the energy accumulator ``energy`` (layout ``EN_*``, [J] since the run's start) to
    ``out_energy`` unless that is empty (no accounting)."""
    out_t[n_out] = t
    if out_energy.shape[0] > 0:
        for i in range(energy.shape[0]):
            out_energy[n_out, i] = energy[i]
    for i in range(NS):
        out_s[n_out, i] = s[i]
    for i in range(NAUX):
        out_aux[n_out, i] = aux[i]
    for leg in range(2):
        out_ls[n_out, RM_LEG_STATE_B + leg] = ls[leg]
        out_ls[n_out, RM_CONTACT_B + leg] = mi[MI_CONTACT_B + leg]
        out_ls[n_out, RM_MOTOR_B + leg] = mi[MI_MOTOR_B + leg]
    return n_out + 1


#: what drives the plant: the compiled Table I law's parameters ``C``, the leg states
#: ``ls`` and the control block ``cb`` (:mod:`scoutsim.control.block`)
Control = namedtuple("Control", "C ls cb")
#: the samples a call runs, k_start .. k_stop - 1 (the run's last sample ``k_last``), the
#: control period ``dt`` [s] and the integrator's tolerances
Span = namedtuple("Span", "k_start k_stop k_last dt rtol atol")
#: where the run is recorded: the time series (``out_t``, ``out_s``, ``out_aux``,
#: ``out_ls``), the event records and statistics (``ev``, ``stats``), the integrator
#: steps (``steps``, ``stepc``) and the energy accounting (``energy``, ``out_energy``)
Records = namedtuple("Records", "out_t out_s out_aux out_ls ev stats steps stepc energy out_energy")
#: what a run carries from one call to the next: ``hwork`` (step-size guess and flags),
#: which event functions are ``armed``, the ARK stiff factors ``sfwork``, the evaluation
#: workspace ``ew`` and the sensitivities ``tangent``
#: (:data:`~scoutsim._core.numerics.tangent_work.TangentPack`; no columns: none)
Carry = namedtuple("Carry", "hwork armed sfwork ew tangent")


@allocating
def run(plant, control, span, records, carry, n_out, nev, method):
    """Run control periods span.k_start .. span.k_stop-1 (sample k at t = k dt).

    ``plant`` (:class:`~scoutsim._core.numerics.work.Plant`: state ``s``, parameters ``P``, modes
    ``mi``, ``mf``, held commands ``cmd``), ``control`` (:data:`Control`: ``C``, ``ls``,
    ``cb``), ``span`` (:data:`Span`), ``records`` (:data:`Records`) and ``carry``
    (:data:`Carry`) name the arrays below; ``n_out`` rows of the time series and ``nev``
    event records are in use.

    At each sample: the sensors are read into ``cb.y`` (:func:`sense`) and the controller
    of the control block ``cb`` (:mod:`scoutsim.control.block`: the compiled Table I law
    with parameters ``C``, a controller function called through its address, or none:
    ``cmd`` held as the caller set it) updates the held commands, the modes are settled, the sample is
    recorded, then the plant is integrated to the next sample. ``method``: METHOD_DOPRI5 or
    METHOD_ARK3 / METHOD_ARK4 (Model II only), a compile-time constant: call the
    specialization :func:`run_entry` returns. ``hwork``:
    [step-size guess, 1 if ``sfwork`` (NS, 2 NSTIFF) holds the ARK stiff factors of the
    last step], both carried between calls so that a run cut into calls (chunks, a Python
    controller) integrates exactly as one call would. ``ew`` (:func:`eval_workspace`) is
    the evaluation workspace, kept across calls too: while hwork[HW_EVAL_KEPT] = 1 it holds
    the last evaluation at ``s`` (K[0]), so a new command is applied to it with
    :func:`evaluate_command_change` instead of a fresh evaluation. ``ev`` (``NEVBUF``
    columns) receives the event records with the state before / after each transition;
    ``steps`` / ``stepc`` every integrator step if ``stepc[1]`` (see
    :func:`~scoutsim._core.numerics.events.record_step`): the call returns at a sample before
    ``steps`` has fewer than ``STEP_HEADROOM`` free rows (as before ``ev`` fills up).
    ``energy`` (layout ``EN_*``) accumulates the energy of every power flow over the
    integrator's steps (:mod:`~scoutsim._core.numerics.step_energy`); an empty
    array switches the accounting off. ``out_energy`` (rows as ``out_t``, ``NEN`` columns;
    empty (0, NEN) without the accounting) receives ``energy`` at every recorded sample:
    the cumulative energy of every flow [J]. Returns (k, n_out, nev, status, t)."""
    rtol, atol = span.rtol, span.atol
    ev, stats, steps, stepc, energy = (
        records.ev,
        records.stats,
        records.steps,
        records.stepc,
        records.energy,
    )
    armed, sfwork, ew = carry.armed, carry.sfwork, carry.ew
    K = np.zeros((7, NS))
    y_new = np.zeros(NS)
    tmp = np.zeros(NS)
    aux = np.zeros(NAUX)
    aux_new = np.zeros(NAUX)
    e_old = np.zeros(NEV)
    e_new = np.zeros(NEV)
    ybuf = np.zeros(NS)
    imp = np.zeros(NIMP)
    ds = np.zeros(NS)
    s_prev = np.zeros(NS)
    tr = np.zeros(2, dtype=np.int64)
    ew_s = eval_workspace()
    s_tmp = np.zeros(NS)
    SF0 = sfwork  # ARK stiff factors, kept across calls (hwork[HW_STIFF_VALID] = 1: valid)
    SF1 = np.zeros((NS, 2 * ark.NSTIFF))
    Z = np.zeros((ark.Z_ROWS, ark.Z_COLS))
    nen = energy.shape[0]  # (0: no accounting)
    step_energy = StepEnergy(np.zeros(nen), np.zeros(nen), np.zeros(nen), np.zeros(nen))
    sc = AdvanceScratch(
        np.empty(NEV),
        np.zeros(NEV, dtype=np.bool_),
        np.zeros(NMI, dtype=np.int64),
        np.empty(NS),
        steps,
        stepc,
        energy,
        imp,
        carry.tangent,
    )
    work = StepWork(K, y_new, aux_new, tmp, ew, SF0, SF1, Z, rtol, atol, step_energy)
    evw = EventWork(armed, e_old, e_new, ybuf, np.empty(NAUX), np.empty(NEV))
    log = EventLog(ev, stats)
    periods = PeriodScratch(aux, ds, s_prev, tr, ew_s, s_tmp, np.empty((NQ, NQ)), log)
    return run_periods(
        plant, control, span, records, carry, n_out, nev, method, work, evw, sc, periods
    )


#: :func:`run_periods`' own arrays: the outputs ``aux`` at the state, a derivative ``ds``
#: for the final evaluation, the state before a sample's settling ``s_prev``, the
#: controller's transitions ``tr``, the sensors' evaluation workspace ``ew_s`` and state
#: copy ``s_tmp``, a mass-matrix scratch ``M`` (the energy before a mode change) and the
#: event log ``log`` (``EventLog``)
PeriodScratch = namedtuple("PeriodScratch", "aux ds s_prev tr ew_s s_tmp M log")


@kernel
def run_periods(plant, control, span, records, carry, n_out, nev, method, work, evw, sc, periods):
    """The control periods of :func:`run` on the arrays it made: ``work`` (``StepWork``),
    ``evw`` (``EventWork``), ``sc`` (:data:`AdvanceScratch`) and ``periods``
    (:data:`PeriodScratch`, with the event log). A kernel (no reference counting): the loop passes
    its arrays to the integrator and the model at every sample, and with reference counting
    each of them was an atomic increment and decrement per call (perf, 10 s of Model II:
    6 % of the compiled time). Returns what :func:`run` returns."""
    s, P, mi, mf, cmd = plant
    C, ls, cb = control
    k_start, k_stop, k_last, dt = span.k_start, span.k_stop, span.k_last, span.dt
    out_t, out_s, out_aux, out_ls, ev, stats, steps, stepc, energy, out_energy = records
    hwork, ew = carry.hwork, carry.ew
    K = work.K
    aux, ds, s_prev, tr, ew_s, s_tmp, M_e, log = periods
    tan = carry.tangent
    kind = cb.ints[CB_KIND]
    sf_ok = is_set(hwork[HW_STIFF_VALID])  # SF0 holds stiff factors from an earlier step
    t = k_start * dt
    k = k_start
    while k < k_stop:
        t = k * dt
        # (read under every kind, the held commands too: a caller that sets them, a
        # learning environment's policy, sees the readings and their delays sample by sample)
        if kind == CTRL_BUILTIN and not is_set(cb.geom[SG_MEASURED]):
            # the Table I law reads only the hip encoders and leg lengths; with ideal
            # sensors nothing else is needed here (readings_at reads every channel)
            read_encoders(s, is_set(cb.geom[SG_MOTOR_SIDE]), cb.y)
        else:
            sense(k, s, P, mi, mf, cmd, is_set(hwork[HW_EVAL_KEPT]), cb, ew_s, s_tmp)
        if carrying(tan):
            tangent_call.keep(cmd, cb.state, ls, tan)
        if kind == CTRL_BUILTIN:
            bounding_step(cb.y, C, ls, cmd, tr)
            nevc = nev
            for leg in range(2):
                if tr[leg] & TR_TOUCHDOWN:
                    nev = log_event(ev, nev, t, EK_CTRL_TOUCHDOWN, leg, 0.0, 0.0, 0.0)
                if tr[leg] & TR_SWEEP:
                    nev = log_event(ev, nev, t, EK_CTRL_SWEEP, leg, 0.0, 0.0, 0.0)
                if tr[leg] & TR_LIFTOFF:
                    nev = log_event(ev, nev, t, EK_CTRL_LIFTOFF, leg, 0.0, 0.0, 0.0)
            if nev > nevc:
                stamp_states(ev, nevc, nev, s, s)
        elif kind != CTRL_HELD:
            rc = call_controller(cb.ints[CB_ADDRESS], t, cb.y, cb.params, cb.state, cmd, ls)
            if rc != 0 or not (np.isfinite(cmd[0]) and np.isfinite(cmd[1])):
                # the sample is not recorded: the run's data end at the sample before
                cb.ints[CB_STATUS] = rc
                return k, n_out, nev, ST_CONTROLLER_ERROR, t
        if carrying(tan) and kind != CTRL_HELD:
            tangent_call.sample(t, s, P, mi, mf, kind == CTRL_BUILTIN, C, cb, tan)
        nev0 = nev
        for i in range(NS):
            s_prev[i] = s[i]
        if carrying(tan):
            tangent_call.snapshot(s, mi, mf, K[0], tan)
        nev = settle_ws(t, s, P, mi, mf, cmd, K[0], aux, log, nev, ew, is_set(hwork[HW_EVAL_KEPT]))
        hwork[HW_EVAL_KEPT] = FLAG_OFF
        stats[S_NFEV] += 1
        if carrying(tan):
            tangent_call.reset(-1, t, mi, K[0], P, cmd, tan)
        if nev > nev0:
            # the new command changed a mode (a joint breaks away, a toe starts to slide):
            # audit it like an event (rare: the energy before is computed only here)
            stamp_transition(
                ev,
                nev0,
                nev,
                state_energy_ws(s_prev, P, M_e),
                aux[A_ENERGY],
                mode_violations(s, K[0], aux, P, mi),
                s_prev,
                s,
            )
        # record the sample
        n_out = record_sample(
            t, s, aux, ls, mi, out_t, out_s, out_aux, out_ls, n_out, energy, out_energy
        )
        if not is_set(aux[A_KKT_OK]):
            return k, n_out, nev, ST_NUMERICAL_FAILURE, t
        if k >= k_last:
            k += 1
            break
        t_next = (k + 1) * dt
        t, nev, status = advance(
            t,
            t_next,
            plant,
            hwork,
            aux,
            log,
            nev,
            method,
            work,
            evw,
            sc,
            sf_ok or method == METHOD_DOPRI5,
        )
        sf_ok = True
        hwork[HW_STIFF_VALID] = FLAG_ON
        # K[0], aux and ew now hold the evaluation at s (the end of the last step, or the
        # state after an event), with the command of the period just ended
        hwork[HW_EVAL_KEPT] = FLAG_ON if status == ST_RUNNING else FLAG_OFF
        if status == ST_RUNNING:  # what the sensors of the next sample read
            for i in range(NS):
                cb.last[i] = K[0, i]
            for i in range(NAUX):
                cb.last[NS + i] = aux[i]
        if status != ST_RUNNING:
            # record the final state (fall or failure) off the grid
            evaluate_ws(s, P, mi, mf, cmd, ds, aux, ew, False, ew[3], True)
            n_out = record_sample(
                t, s, aux, ls, mi, out_t, out_s, out_aux, out_ls, n_out, energy, out_energy
            )
            return k + 1, n_out, nev, status, t
        k += 1
        if nev > ev.shape[0] - 64:
            break
        if stepc[1] != 0 and stepc[0] > steps.shape[0] - STEP_HEADROOM:
            break
    return k, n_out, nev, ST_RUNNING, t


#: compiled entry points of :func:`run`, by (method, argument types) and by (method,
#: argument fingerprints)
_ENTRIES: dict[tuple, object] = {}

_compute_fingerprint: Callable[..., bytes] | None
try:  # Numba's key of its type cache (private; None where missing: typed instead)
    from numba._dispatcher import compute_fingerprint as _compute_fingerprint
except ImportError:
    _compute_fingerprint = None


def effective_method(method: int, hip_unit: int) -> int:
    """The method :func:`run` integrates with for the hip unit ``hip_unit`` (``P_HIP_UNIT``):
    the ARK methods split off the belt of a geared unit (Model II), so they exist for
    those only; DOPRI5 otherwise and for METHOD_AUTO."""
    if method == METHOD_AUTO or (method >= METHOD_ARK4 and not is_geared(hip_unit)):
        return METHOD_DOPRI5
    return method


def run_entry(method: int, args: tuple):
    """The compiled :func:`run` for one integration method, called with ``args`` (every
    argument of :func:`run` but ``method``): compiled (or loaded from the cache) for the
    method as a constant, so a run compiles and loads only its own method's integrator.

    The entry is looked up by the arguments' fingerprints (Numba's own key of its type
    cache, computed in C: for an array its dtype, dimensions, layout and writability); the
    arguments are typed (``numba.typeof``, about 0.2 ms for these bundles) only when a
    fingerprint is new. ``compute_fingerprint`` is private to Numba: where it is missing
    (another release), every call is looked up by its typed arguments instead (the same
    entries, 0.2 ms more a call)."""
    key = None
    if _compute_fingerprint is not None:
        try:
            key = (method, tuple(_compute_fingerprint(a) for a in args))
        except (TypeError, ValueError, NotImplementedError):  # a value Numba has no key for
            key = None
    entry = _ENTRIES.get(key) if key is not None else None
    if entry is None:
        from numba import typeof
        from numba.core import types

        argtypes = tuple(typeof(a) for a in args)
        typed_key = (method, argtypes)
        entry = _ENTRIES.get(typed_key)
        if entry is None:
            entry = _ENTRIES[typed_key] = run.compile(argtypes + (types.literal(method),))
        if key is not None:
            _ENTRIES[key] = entry
    return entry
