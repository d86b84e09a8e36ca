"""The derivatives of a run's recorded signals with respect to robot fields, sample by
sample: the derivatives of the state carried with the run
(:meth:`~scoutsim.simulation.engine.HybridEngine.carry_sensitivities`), read after every
control sample, and those of the motor currents along them (docs/explanation/derivatives.md).
Its user: the hip-unit identification's exact Jacobian (docs/identification.md).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._core.model import layout as L
from .._core.model.derivative.currents import current_derivatives
from .._core.numerics.tangent_work import X_CMD, X_MF, X_S
from ..parameters.robot_fields import robot_value, robot_with_value
from .parameter_rows import packing_derivatives

__all__ = ["SampleDerivatives"]

#: relative step of the central differences of the packing (a field's derivative of the
#: packed arrays, :func:`~scoutsim.simulation.parameter_rows.packing_derivatives`)
DIFFERENCE_STEP = 1e-6


@dataclass
class SampleDerivatives:
    """The derivatives of a run's recorded driven-gear angles and motor currents with
    respect to robot fields, carried with the run, sample by sample (the bench runs of the
    identification fill one: ``run_bench(..., derivatives=...)``).

    fields : names of float fields of RobotParameters (a leg's ``<field>.back``, ...).
    angle : (n samples, 2 legs, fields) d alpha / d field [rad per the field's SI unit];
        None before the run.
    current : (n, 2, fields) d i / d field [A per the field's SI unit]: the current's
        derivative along each carried column at the sample, in closed form (the
        amplifier's branch, the motor speed's and the battery voltage's tangents).
    smoothness : the run's :meth:`~scoutsim.simulation.engine.HybridEngine.smoothness`;
        ``smoothness["nonsmooth"] > 0``: a reset where a perturbed copy took another branch
        (the run is not differentiable there: the derivatives are not those of the run).
    """

    fields: tuple
    angle: np.ndarray | None = None
    current: np.ndarray | None = None
    smoothness: dict = field(default_factory=dict)
    _angle: list = field(default_factory=list, repr=False)
    _current: list = field(default_factory=list, repr=False)
    _dP: np.ndarray | None = field(default=None, repr=False)
    _pending: tuple | None = field(default=None, repr=False)

    def start(self, eng, robot, engine) -> None:
        """Carry the fields' columns on ``eng`` (``engine(robot)`` makes the run's engine
        for another robot: the fields' derivatives of the packed arrays are its central
        differences) and record sample 0."""
        dP, dC, dcp = packing_derivatives(
            self.fields,
            lambda name: robot_value(robot, name),
            lambda name, value: engine(robot_with_value(robot, name, value))[0],
            DIFFERENCE_STEP,
        )
        n = len(self.fields)
        nx = eng.sensitivities.shape[0]
        seed = np.zeros((nx + n, n))
        seed[nx:, :] = np.eye(n)
        eng.carry_sensitivities(seed, (dP, dC, dcp))
        self._dP = dP
        self._angle, self._current, self._pending = [], [], None
        self.record(eng)

    def record(self, eng) -> None:
        """Called at sample 0 and after every advance by one sample: the record of sample k
        is written when the run goes on from k, with the command the controller sets at k
        (held until k + 1), so sample k's derivatives are complete once the engine is at
        k + 1: its state's from then, its command's now."""
        pending = self._pending
        if pending is not None and eng.k == pending[0] + 1:
            _, s, mi, mf, phi = pending
            self._angle.append(phi[[X_S + L.IALB, X_S + L.IALF], :].copy())
            self._current.append(
                self._current_derivative(
                    s, mi, mf, eng.cmd, eng.P, phi, eng.sensitivities[X_CMD : X_CMD + 2]
                )
            )
        Phi = eng.sensitivities
        self._pending = (
            eng.k,
            eng.s.copy(),
            eng.mi.copy(),
            eng.mf.copy(),
            Phi[:X_CMD].copy(),
        )

    def finish(self, eng) -> None:
        """The recorded samples as arrays, and the run's smoothness."""
        self.angle = np.array(self._angle)
        self.current = np.array(self._current)
        self.smoothness = eng.smoothness()

    def _current_derivative(self, s, mi, mf, cmd, P, phi, dcmd) -> np.ndarray:
        """(2, fields): the motor currents' derivative at state ``s`` (modes ``mi``,
        anchors ``mf``) under the commands ``cmd`` and parameters ``P``, along each
        column (the state's and anchors' rows ``phi``, the commands' ``dcmd``), in closed
        form (:func:`~scoutsim._core.model.derivative.currents.current_derivatives`)."""
        assert self._dP is not None, "start() comes first"
        return current_derivatives(
            s,
            P,
            mi,
            mf,
            np.ascontiguousarray(cmd, dtype=float),
            (
                np.ascontiguousarray(phi[X_S:X_MF]),
                np.ascontiguousarray(phi[X_MF:X_CMD]),
                np.ascontiguousarray(dcmd),
            ),
            self._dP,
        )
