"""The work-energy accounting of a step: the energy of every power flow over it.

The energy of every power flow P (:mod:`scoutsim._core.model.power_flows`) over a step of
the integrator of one control period (:mod:`scoutsim._core.numerics.hybrid`) is the
method's own quadrature of the power at its stages,

    E = h sum_j b_j P(Y_j),

with the weights b_j of the step's solution y_new = y + h sum_j b_j K_j. That is the method
applied to the energies as further components of the state, z' = P(y) (which never feed
back): they are integrated with the order and the error control of the motion itself, and
at no further evaluation of the right-hand side. P(Y_j) is read from the evaluation that
gave the stage derivative K_j, held in the evaluation workspace (the state as it projected
it, the forces, currents and multipliers as they acted: :func:`add_stage`), P(Y_0) = P(y)
from the evaluation that gave K[0] (the step's start, with the period's held command and
the step's modes: ``StepEnergy.p_start``). The sum is kept in the step's scratch (``StepEnergy.quad``) and
added to the run's energies only when the step is taken (:func:`take_step`): a rejected
step, and a step redone to an event's instant, count once. The motion is the same bit for
bit with and without the accounting: it only reads the evaluations and writes its own
arrays. Compiled with Numba.
"""

from __future__ import annotations

from ..._numba.jit import kernel
from ..model.power_flows import power_flows


@kernel(inline="always")
def accounting(en):
    """True if the run accounts for the energy (``en``: the step's
    :class:`~scoutsim._core.numerics.work.StepEnergy`, empty arrays otherwise)."""
    return en.quad.shape[0] > 0


@kernel
def power_at(ds, P, mi, ew, out):
    """The power flows into ``out`` at the evaluation held in the workspace ``ew``, with
    derivative ``ds`` (a kernel of its own: called at a step's end and a period's start,
    it is compiled once; the stages' :func:`add_stage` has the flows inlined)."""
    power_flows(ds, P, mi, ew[0], ew[1], out)


@kernel(inline="always")
def begin_step(b0, en):
    """Start the quadrature of a step: ``en.quad`` = b_0 P(y), the first stage being the
    step's start."""
    for i in range(en.quad.shape[0]):
        en.quad[i] = b0 * en.p_start[i]


@kernel(inline="always")
def add_stage(b, ds, P, mi, ew, en):
    """Add b P(Y) to ``en.quad``: the power flows of the stage just evaluated on the
    workspace ``ew`` (without its outputs: they are not needed), with derivative ``ds``."""
    power_flows(ds, P, mi, ew[0], ew[1], en.p)
    for i in range(en.quad.shape[0]):
        en.quad[i] += b * en.p[i]


@kernel(inline="always")
def take_step(h, en, energy):
    """The step of size ``h`` whose quadrature ``en.quad`` holds is taken: add its energy
    h sum_j b_j P(Y_j) to the run's ``energy`` (layout ``EN_*``, [J]); its end's power
    flows become the next step's start."""
    for i in range(energy.shape[0]):
        energy[i] += h * en.quad[i]
        en.p_start[i] = en.p_end[i]
