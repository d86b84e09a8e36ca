"""Identifiability: each fitted parameter's value and confidence interval [SI], whether the
logs determine it (and why not), and the combination of parameters the clamped rigs
determine when they do not determine its parts.

A parameter counts as *identifiable* by the given logs when no flat direction involves it
(:mod:`scoutsim.identification.uncertainty`), its interval spans at most a factor
``max_interval_ratio`` (default 2, i.e. roughly +-35 %) and the fit did not end on the
search box's edge. Otherwise it is reported as not identifiable, with the reason; the
report also lists strongly correlated pairs (|rho| > 0.95) and the singular values and
directions of the scaled Jacobian (the combination of log-parameters the data do not
determine).
"""

from __future__ import annotations

import math

import numpy as np

from ..parameters import RobotParameters
from .fit_result import FittedParameter
from .parameter_vector import SearchBox
from .rigs import HIP_PARAMETERS
from .uncertainty import Optimum, Spread

__all__ = ["true_parameters", "fitted_parameters", "reflected_gear_inertia"]


def true_parameters(data: list) -> dict:
    """The true parameter values [SI] a virtual log states in its metadata
    (``true_parameters``; the last log that has them), else {}."""
    true = {}
    for d in data:
        tp = d.log.meta.get("true_parameters")
        if isinstance(tp, dict):
            true = tp
    return true


def fitted_parameters(
    sb: SearchBox, opt: Optimum, sd, base: RobotParameters, true: dict, max_interval_ratio: float
) -> dict:
    """name -> :class:`FittedParameter`: value exp(x), interval exp(x +- zq sd), and
    whether it is identifiable (finite interval spanning at most ``max_interval_ratio``,
    not at the search box's edge) or why not."""
    names, x, zq = sb.names, opt.x, opt.zq
    xlo, xhi = sb.xlo, sb.xhi
    fitted = {}
    for i, n in enumerate(names):
        half = zq * sd[i]
        lo = math.exp(x[i] - half) if math.isfinite(half) else 0.0
        hi = math.exp(x[i] + half) if math.isfinite(half) else math.inf
        at_edge = (x[i] - xlo[i] < 1e-3) or (xhi[i] - x[i] < 1e-3)
        ratio = hi / lo if lo > 0 else math.inf
        if not math.isfinite(ratio):
            ok, why = False, "not determined: flat or curved cost valley"
        elif at_edge and ratio > 1.0:
            ok, why = False, "fit ran to the search box's edge"
        elif ratio > max_interval_ratio:
            ok, why = False, f"interval spans a factor {ratio:.3g}"
        else:
            ok, why = True, ""
        fitted[n] = FittedParameter(
            name=n,
            unit=HIP_PARAMETERS[n],
            value=math.exp(x[i]),
            interval=(lo, hi),
            identifiable=ok,
            reason=why,
            log_sd=float(sd[i]),
            start=float(getattr(base, n)),
            bounds=(math.exp(xlo[i]), math.exp(xhi[i])),
            true=(float(true[n]) if n in true else None),
        )
    return fitted


def reflected_gear_inertia(
    sb: SearchBox, opt: Optimum, spr: Spread, base: RobotParameters, true: dict
) -> dict:
    """The combination the clamped rigs determine when both gear inertias are fitted: the
    reflected gear-train inertia J_2 + N^2 J_1 [kg m^2] (docs/specification.md section 5)
    with its interval, as {"reflected_gear_inertia": {...}}; {} if not both are fitted."""
    names, x, zq = sb.names, opt.x, opt.zq
    p = len(names)
    cov_det, flat, Vt, spans = spr.cov_det, spr.flat, spr.Vt, spr.spans
    combos = {}
    if "drive_gear_inertia" in names and "driven_gear_inertia" in names:
        i1, i2 = names.index("drive_gear_inertia"), names.index("driven_gear_inertia")
        n2 = base.gear_ratio**2
        j1, j2 = math.exp(x[i1]), math.exp(x[i2])
        jr = j2 + n2 * j1
        g = np.zeros(p)
        g[i1], g[i2] = n2 * j1 / jr, j2 / jr
        var = float(g @ cov_det @ g)
        half = zq * math.sqrt(max(var, 0.0))
        # undetermined if a flat direction, followed across the box, moves it beyond its
        # half-width (the same rule as for the parameters)
        # half-width (the same rule as for the parameters) - except the gear direction
        # itself, which the finite-difference stencil resolves only approximately
        for k in np.flatnonzero(flat):
            gv = abs(float(g @ Vt[k]))
            gear_dir = Vt[k, i1] ** 2 + Vt[k, i2] ** 2 > 0.5
            if gv > 0.2 * float(np.linalg.norm(g)) or (
                not gear_dir and gv * spans.get(int(k), 0.0) > half
            ):
                half = math.inf
        tr = None
        if "drive_gear_inertia" in true and "driven_gear_inertia" in true:
            tr = float(true["driven_gear_inertia"]) + n2 * float(true["drive_gear_inertia"])
        combos["reflected_gear_inertia"] = {
            "definition": "J_2 + N^2 J_1",
            "value": jr,
            "unit": "kg m^2",
            "interval": [
                jr * math.exp(-half),
                jr * math.exp(half) if math.isfinite(half) else None,
            ],
            "true": tr,
        }
    return combos
