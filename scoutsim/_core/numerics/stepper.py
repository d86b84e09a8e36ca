"""The integration method's step and continuous extension, chosen when the integrator is compiled.

The methods (``METHOD_*``): the explicit Dormand-Prince 5(4) pair
(:mod:`scoutsim._core.numerics.dopri5`), the reference, and the additive Runge-Kutta pairs
(:mod:`scoutsim._core.numerics.ark`) that treat the belt spring-dampers implicitly. The
integrator of one control period (:mod:`scoutsim._core.numerics.hybrid`) and its event
location (:mod:`scoutsim._core.numerics.event_location`) take a step and read its continuous
extension through :func:`do_step` and :func:`method_dense`. Compiled with Numba.
"""

from __future__ import annotations

from numba.extending import overload

from ..._numba.compile_steps import inline_only
from ..._numba.jit import kernel
from ..model.evaluate import evaluate_ws
from . import ark
from .dopri5 import dense, step

# integration methods (``run(..., method)``)
# (the user-level choice, e.g. ARK3 for Model II at the default tolerance, is made by
# ``simulation.IntegratorSettings.resolve``; run() itself maps AUTO to DOPRI5)
METHOD_AUTO = -1  # DOPRI5
METHOD_DOPRI5 = 0  # explicit Dormand-Prince 5(4): the reference
METHOD_ARK4 = 1  # additive RK 4(3), belt spring-dampers implicit (ark.py; Model II)
METHOD_ARK3 = 2  # additive RK 3(2) (ark.py, ARK3(2)4L[2]SA), same splitting


# --- the method, chosen when the integrator is compiled ---------------------------------
# ``method`` reaches the integrator as a compile-time constant (jit.SPECIALIZING_PARAMETERS,
# loop.run_entry). The two functions below are resolved from it while the caller is being
# compiled, so a run compiles only its own method's stepper and continuous extension
# (a Model II run at the default tolerance neither DOPRI5 nor ARK4: 10 % of the first run's
# compilation, docs/model.md "Compile time").


def method_step(method, s, h, P, mi, mf, cmd, work, eval_end, want_sf):
    """One step of ``method`` (a constant) on the step's ``work``
    (:class:`~scoutsim._core.numerics.work.StepWork`); compiled code only (:func:`_method_step`)."""
    raise NotImplementedError("method_step is resolved when a kernel is compiled")


@overload(method_step, prefer_literal=True, inline="always")
def _method_step(method, s, h, P, mi, mf, cmd, work, eval_end, want_sf):
    m = getattr(method, "literal_value", None)
    if m == METHOD_ARK4:

        def impl(method, s, h, P, mi, mf, cmd, work, eval_end, want_sf):
            return ark.step(s, h, P, mi, mf, cmd, work, eval_end, want_sf)

        return inline_only(impl)
    if m == METHOD_ARK3:

        def impl(method, s, h, P, mi, mf, cmd, work, eval_end, want_sf):
            return ark.step3(s, h, P, mi, mf, cmd, work, eval_end, want_sf)

        return inline_only(impl)
    if m == METHOD_DOPRI5:

        def impl(method, s, h, P, mi, mf, cmd, work, eval_end, want_sf):
            err, ok = step(s, h, P, mi, mf, cmd, work)
            return err, ok, 6

        return inline_only(impl)
    return None  # not a method constant: no implementation (a typing error names it)


def method_dense(method, s, y_new, h, K, th, out):
    """The continuous extension of ``method``'s last step (a constant) at the fraction
    ``th`` into ``out``; compiled code only (:func:`_method_dense`)."""
    raise NotImplementedError("method_dense is resolved when a kernel is compiled")


@overload(method_dense, prefer_literal=True, inline="always")
def _method_dense(method, s, y_new, h, K, th, out):
    m = getattr(method, "literal_value", None)
    if m == METHOD_ARK4 or m == METHOD_ARK3:

        def impl(method, s, y_new, h, K, th, out):
            ark.dense(s, y_new, h, K, th, out)

        return inline_only(impl)
    if m == METHOD_DOPRI5:

        def impl(method, s, y_new, h, K, th, out):
            dense(s, h, K, th, out)

        return inline_only(impl)
    return None


@kernel(inline="always")
def do_step(method, s, h, P, mi, mf, cmd, work, eval_end, want_sf=True):
    """One step of the selected method (a constant, :func:`method_step`) on the step's
    ``work`` (:class:`~scoutsim._core.numerics.work.StepWork`); returns (error_norm, ok,
    evaluations). ``want_sf``: the ARK methods also refresh the stiff factors at the
    step's end (SF1)."""
    return method_step(method, s, h, P, mi, mf, cmd, work, eval_end, want_sf)


@kernel(inline="always")
def eval_k0(method, s, P, mi, mf, cmd, K0, aux, ew, SF0):
    """f(s) into K0 (and, for the ARK method, the stiff factors into SF0)."""
    return evaluate_ws(s, P, mi, mf, cmd, K0, aux, ew, method >= METHOD_ARK4, SF0, True)
