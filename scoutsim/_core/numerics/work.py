"""Named bundles of the integrators' arrays (compiled code receives them as named tuples).

``StepWork``: what one integrator step works on: the stage derivatives ``K`` (7 x NS), the
step's end ``y_new`` and its outputs ``aux_new``, a stage buffer ``tmp``, the evaluation
workspace ``ew`` (:func:`~scoutsim._core.numerics.dopri5.eval_workspace`), the ARK methods' stiff
factors at the step's start and end ``SF0``, ``SF1`` and their scratch ``Z``, the error
tolerances ``rtol``, ``atol``, and the step's work-energy accounting ``energy``
(``StepEnergy``).

``StepEnergy``: what the work-energy accounting of a step works on
(:mod:`~scoutsim._core.numerics.step_energy`; every array empty when the run does not
account): ``quad`` the method's quadrature sum_j b_j P(Y_j) of the power flows [W] over
the step being taken, ``p_start`` the power flows at the step's start (from the evaluation
that gave K[0]), ``p_end`` at its end (from the evaluation of y_new), and the scratch
``p`` (a stage's power flows); layout ``EN_*``.

``EventWork``: what locating events works on: which event functions are ``armed``, their
values at the step's start ``e_old`` and end ``e_new``, and the probe buffers ``ybuf``
(a state), ``aux_tmp`` (its outputs) and ``e_tmp`` (its event values).

``Plant``: the hybrid state and what drives it: the state ``s``, the parameters ``P``, the
integer and float modes ``mi``, ``mf`` and the held commands ``cmd``.

``EventLog``: the event records ``ev`` (``layout.NEVBUF`` columns) and the integrator
statistics ``stats`` (``numerics.stats``).
"""

from __future__ import annotations

from collections import namedtuple

StepWork = namedtuple("StepWork", "K y_new aux_new tmp ew SF0 SF1 Z rtol atol energy")
StepEnergy = namedtuple("StepEnergy", "quad p_start p_end p")
EventWork = namedtuple("EventWork", "armed e_old e_new ybuf aux_tmp e_tmp")
Plant = namedtuple("Plant", "s P mi mf cmd")
EventLog = namedtuple("EventLog", "ev stats")
