"""The weighted residuals of the fit: for every log, the simulated minus the logged
motor-encoder angle of every leg that moves, divided by the angle noise [rad / rad], and,
where the rig drives current, the motor current likewise [A / A]::

    r = [(alpha_sim(t_k; p) - alpha_log(t_k)) / sigma_angle,  (i_sim - i_log) / sigma_i]

and, after the fit, the rms of each channel in units of its stated noise.
"""

from __future__ import annotations

import numpy as np
from scipy import optimize

from ..parameters import RobotParameters
from ..simulation.integrator import IntegratorSettings
from ..simulation.sample_derivatives import SampleDerivatives
from ..validation.log_format import LogError
from .parameter_vector import robot_with
from .rig_data import simulate_log

__all__ = ["Residuals", "residual_count", "channel_rms"]


def residual_count(data: list, p: int) -> int:
    """Number of residuals of the logs ``data``; LogError if they are not more than the
    ``p`` fitted parameters."""
    nres = sum(d.n_residuals for d in data)
    if nres <= p:
        raise LogError(
            f"{data[0].log.path or data[0].name}: only {nres} residuals for {p} parameters",
            data[0].log.path,
        )
    return nres


class Residuals:
    """r(x): the weighted residuals of every log with the fitted parameters at ``x`` (ln p)
    and the others of ``base``; a non-finite residual counts as 1e6. ``nfev`` counts the
    evaluations (each replays every rig)."""

    def __init__(
        self,
        data: list,
        base: RobotParameters,
        names: list,
        integrator: IntegratorSettings | None,
        diff_step: float = 1e-3,
    ):
        self.data = data
        self.base = base
        self.names = names
        self.integrator = integrator
        self.diff_step = diff_step
        self.nfev = 0
        self.njev = 0
        self.nfd = 0

    def __call__(self, x):
        self.nfev += 1
        rb = robot_with(self.base, self.names, x)
        out = []
        for d in self.data:
            a, c, _ = simulate_log(d, rb, self.integrator)
            simulated, logged = (a, c), (d.angle, d.current)
            for signal, leg, noise in _channels(d):
                out.append((simulated[signal][:, leg] - logged[signal][:, leg]) / noise)
        r = np.concatenate(out)
        r[~np.isfinite(r)] = 1e6
        return r

    def jacobian(self, x) -> np.ndarray:
        """dr/dx at ``x`` (x = ln p), from the derivatives of each replay carried with it
        (:class:`~scoutsim.simulation.sample_derivatives.SampleDerivatives`): the angles' and
        currents' derivatives with respect to the fitted fields, times p (the chain rule
        to ln p), over each channel's noise. Where a replay is not differentiable (a reset
        whose perturbed copies took another branch) or failed early, forward differences
        of r with ``diff_step`` (the fit's) instead, for the whole matrix. ``njev`` counts
        the calls, ``nfd`` those that fell back."""
        self.njev += 1
        rb = robot_with(self.base, self.names, x)
        p = np.exp(np.asarray(x, dtype=float))
        blocks = []
        for d in self.data:
            der = SampleDerivatives(tuple(self.names))
            a, _, _ = simulate_log(d, rb, self.integrator, derivatives=der)
            n = d.angle.shape[0]
            if (
                der.smoothness.get("nonsmooth", 0) > 0
                or a.shape[0] < n
                or der.angle is None
                or der.angle.shape[0] < n
            ):
                self.nfd += 1
                return self._differences(x)
            assert der.current is not None, "a finished run has both"
            derivative = (der.angle, der.current)
            for signal, leg, noise in _channels(d):
                blocks.append(derivative[signal][:n, leg, :] * p / noise)
        J = np.vstack(blocks)
        if not np.all(np.isfinite(J)):
            self.nfd += 1
            return self._differences(x)
        return J

    def _differences(self, x) -> np.ndarray:
        """dr/dx by forward differences, steps ``diff_step`` max(1, |x_i|) (those of
        ``scipy.optimize.least_squares``'s "2-point")."""
        x = np.asarray(x, dtype=float)
        return optimize.approx_fprime(x, self, self.diff_step * np.maximum(1.0, np.abs(x)))


def _channels(d) -> list:
    """The channels of log ``d`` in the order of its residuals: (signal, leg, noise), signal
    0 the encoder angle [rad], 1 the motor current [A] (where the fit uses it)."""
    out = [(0, leg, d.sigma_angle) for leg in d.legs]
    if d.current is not None:
        out += [(1, leg, d.sigma_current) for leg in d.legs]
    return out


def channel_rms(r: np.ndarray, data: list) -> dict:
    """RMS of each log's angle (and current) residuals ``r`` in units of the stated noise
    [-], by channel name."""
    rms = {}
    o = 0
    for j, d in enumerate(data):
        n = d.angle.shape[0] * len(d.legs)
        ra = r[o : o + n]
        o += n
        rms[f"log {j + 1} ({d.rig.name}) angle"] = float(np.sqrt(np.mean(ra * ra)))
        if d.current is not None:
            rc = r[o : o + n]
            o += n
            rms[f"log {j + 1} ({d.rig.name}) current"] = float(np.sqrt(np.mean(rc * rc)))
    return rms
