"""What the fit found: each fitted parameter (:class:`FittedParameter`: value, confidence
interval and search box in SI units, identifiable or why not) and the whole fit
(:class:`IdentificationResult`: correlations, singular values of the scaled Jacobian,
residual scale, the determined combinations), as a report, ``identified.json`` and fit
figures.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..parameters import RobotParameters
from .rig_data import simulate_log

__all__ = ["FittedParameter", "IdentificationResult"]


@dataclass
class FittedParameter:
    """One fitted parameter (SI)."""

    name: str
    unit: str
    value: float
    interval: tuple
    identifiable: bool
    reason: str
    log_sd: float
    start: float
    bounds: tuple
    true: float | None = None

    def to_dict(self) -> dict:
        def num(x):
            return None if (x is None or not math.isfinite(x)) else float(x)

        return {
            "value": float(self.value),
            "unit": self.unit,
            "interval": [num(self.interval[0]), num(self.interval[1])],
            "identifiable": bool(self.identifiable),
            "reason": self.reason,
            "log_sd": num(self.log_sd),
            "start": float(self.start),
            "search_box": [float(self.bounds[0]), float(self.bounds[1])],
            "true": num(self.true),
        }


@dataclass
class IdentificationResult:
    """What :func:`~scoutsim.identification.fit.identify` found (see
    :mod:`scoutsim.identification.fit`)."""

    parameters: dict
    confidence: float
    robot: RobotParameters
    start_robot: RobotParameters
    correlation: np.ndarray
    singular_values: np.ndarray
    singular_vectors: np.ndarray
    cost: float
    residual_scale: float
    channel_rms: dict
    n_residuals: int
    data: list = field(repr=False, default_factory=list)
    starts: list = field(default_factory=list)
    curvature_ratios: list = field(default_factory=list)
    flat: list = field(default_factory=list)
    combinations: dict = field(default_factory=dict)
    nfev: int = 0
    message: str = ""
    jacobian: str = "fd"
    jacobian_evaluations: int = 0
    jacobian_fallbacks: int = 0

    @property
    def names(self) -> list:
        return list(self.parameters)

    def to_dict(self) -> dict:
        return {
            "format": "scoutsim.identified/1",
            "logs": [d.log.path or d.log.name for d in self.data],
            "rigs": [d.rig.name for d in self.data],
            "confidence": self.confidence,
            "parameters": {k: p.to_dict() for k, p in self.parameters.items()},
            "correlation": {
                "names": self.names,
                "matrix": [
                    [None if not math.isfinite(v) else round(float(v), 6) for v in row]
                    for row in self.correlation
                ],
            },
            "singular_values": [float(v) for v in self.singular_values],
            "singular_vectors": [
                [round(float(v), 6) for v in col] for col in self.singular_vectors.T
            ],
            "curvature_ratios": [float(v) for v in self.curvature_ratios],
            "flat_directions": [bool(v) for v in self.flat],
            "combinations": self.combinations,
            "cost": self.cost,
            "residual_scale": self.residual_scale,
            "channel_rms_over_sigma": self.channel_rms,
            "n_residuals": self.n_residuals,
            "function_evaluations": self.nfev,
            "jacobian_method": self.jacobian,
            "jacobian_evaluations": self.jacobian_evaluations,
            "jacobian_fallbacks_to_differences": self.jacobian_fallbacks,
            "optimizer_message": self.message,
            "multistart": self.starts,
        }

    def report(self) -> str:
        """Plain-text table: fitted value, interval, identifiable flag (and truth if known)."""
        c = round(100 * self.confidence)
        has_true = any(p.true is not None for p in self.parameters.values())
        lines = [
            f"{'parameter':<30} {'unit':<10} "
            + (f"{'true':>11} " if has_true else "")
            + f"{'fitted':>11}  {str(c) + ' % interval':<27} identifiable"
        ]
        for p in self.parameters.values():
            lo, hi = p.interval
            iv = f"[{lo:.4g}, {hi:.4g}]" if math.isfinite(hi) else f"[{lo:.4g}, inf]"
            tr = (f"{p.true:>11.4g} " if p.true is not None else f"{'':>11} ") if has_true else ""
            lines.append(
                f"{p.name:<30} {p.unit:<10} {tr}{p.value:>11.4g}  {iv:<27} "
                + ("yes" if p.identifiable else f"NO ({p.reason})")
            )
        lines.append(
            f"residual scale s = {self.residual_scale:.3f} (1 = residuals as large as "
            f"the stated sensor noise); rms/sigma per channel: "
            + ", ".join(f"{k} {v:.3f}" for k, v in self.channel_rms.items())
        )
        pairs = []
        n = len(self.names)
        for i in range(n):
            for j in range(i + 1, n):
                r = self.correlation[i, j]
                if math.isfinite(r) and abs(r) > 0.95:
                    pairs.append(f"{self.names[i]} / {self.names[j]}: {r:+.3f}")
        if pairs:
            lines.append("strongly correlated (|rho| > 0.95): " + "; ".join(pairs))
        if len(self.singular_values):
            sv = self.singular_values
            lines.append(
                "singular values of the scaled Jacobian: "
                + ", ".join(f"{x:.3g}" for x in sv)
                + "; cost rise over the "
                "interval / linear prediction: "
                + ", ".join(f"{x:.2f}" for x in self.curvature_ratios)
            )
            for k in np.flatnonzero(self.flat):
                v = self.singular_vectors[:, k]
                idx = np.argsort(-np.abs(v))[:3]
                comb = " ".join(f"{v[i]:+.2f} ln {self.names[i]}" for i in idx if abs(v[i]) > 0.05)
                lines.append(f"flat direction (not determined by these logs): {comb}")
        for name, c in self.combinations.items():
            lo, hi = c["interval"]
            tr = f" (true {c['true']:.5g})" if c.get("true") is not None else ""
            if hi is None:
                lines.append(
                    f"combination {name} = {c['definition']}: {c['value']:.5g} "
                    f"{c['unit']}, not determined either{tr}"
                )
            else:
                lines.append(
                    f"determined combination {name} = {c['definition']}: "
                    f"{c['value']:.5g} {c['unit']}, interval [{lo:.5g}, {hi:.5g}]{tr}"
                )
        return "\n".join(lines)

    def save(self, out_dir, figures: bool = True) -> Path:
        """Write ``identified.json`` (and fit figures ``fit_<n>.png``) into ``out_dir``."""
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        path = out / "identified.json"
        path.write_text(json.dumps(self.to_dict(), indent=2))
        if figures:
            self.plot(out)
        return path

    def plot(self, out_dir) -> list:
        """One figure per log, ``out_dir/fit_<n>.png``: logged vs fitted (and starting)
        encoder angle and current, residuals; a convenience for
        :func:`scoutsim.presentation.identification_plots.plot_fit` (needs Matplotlib).
        Returns the paths written."""
        from ..presentation.identification_plots import plot_fit

        files = []
        for i, d in enumerate(self.data):
            fit_a, fit_c, _ = simulate_log(d, self.robot)
            start_a, _, _ = simulate_log(d, self.start_robot)
            f = Path(out_dir) / f"fit_{i + 1}.png"
            plot_fit(d, fit_a, fit_c, start_a, f)
            files.append(f)
        return files
