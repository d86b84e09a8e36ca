"""The fitted parameter vector: the hip-unit parameters are fitted as ``x = ln p`` (all are
positive and span decades), inside a search box in ln p (default: a factor 10 either side
of the starting robot's value [SI]; a fixed box for the transmission losses, which start at
0), and turned back into a robot by :func:`robot_with`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..parameters import RobotParameters
from .rigs import DEFAULT_PARAMS, HIP_PARAMETERS

__all__ = ["SearchBox", "default_bounds", "fitted_names", "search_box", "robot_with"]

#: Search box for parameters whose starting value is 0 (the transmission losses).
_ZERO_START_BOX = {
    "gearbox_idle_loss_torque": (1e-3, 2.0),
    "gearbox_load_loss_coefficient": (1e-3, 0.5),
}


class SearchBox(NamedTuple):
    """The fitted parameters and their search box in ln p."""

    names: list  # the fitted parameters, in the order of x
    box: list  # (ln lo, ln hi) of each
    xlo: np.ndarray  # (p,) lower ends, ln of SI values
    xhi: np.ndarray  # (p,) upper ends, ln of SI values


def default_bounds(name: str, value: float, factor: float = 10.0) -> tuple[float, float]:
    """Default search box of one parameter: (value/factor, value*factor), or a fixed box
    for the loss parameters that start at 0."""
    if value > 0:
        lo, hi = value / factor, value * factor
        if name == "gearbox_load_loss_coefficient":
            hi = min(hi, 0.9)
        return lo, hi
    if name in _ZERO_START_BOX:
        return _ZERO_START_BOX[name]
    raise ValueError(
        f"bounds[{name!r}]: the starting value is {value}; give a search box "
        "(lo, hi) with 0 < lo < hi"
    )


def fitted_names(params, data) -> list:
    """The names of the parameters to fit: ``params`` (default: the ``DEFAULT_PARAMS`` of
    the first log's rig), checked to be distinct keys of ``HIP_PARAMETERS``."""
    if params is None:
        params = DEFAULT_PARAMS[data[0].rig.name]
    names = list(params)
    for n in names:
        if n not in HIP_PARAMETERS:
            raise ValueError(
                f"params: {n!r} is not allowed: must be among {', '.join(HIP_PARAMETERS)}"
            )
    if len(set(names)) != len(names) or not names:
        raise ValueError(f"params = {names} is not allowed: need distinct names, at least one")
    return names


def search_box(names: list, base: RobotParameters, bounds: dict | None) -> SearchBox:
    """The search box of ``names`` in ln p: ``bounds`` {name: (lo, hi)} [SI] where given,
    else :func:`default_bounds` around the value of ``base``; checked 0 < lo < hi."""
    bounds = dict(bounds or {})
    box = []
    for n in names:
        lo, hi = bounds.get(n) or default_bounds(n, float(getattr(base, n)))
        if not (0.0 < lo < hi and math.isfinite(hi)):
            raise ValueError(f"bounds[{n!r}] = ({lo}, {hi}) is not allowed: need 0 < lo < hi")
        if n == "gearbox_load_loss_coefficient" and hi >= 1.0:
            raise ValueError(f"bounds[{n!r}]: hi = {hi} is not allowed: must be < 1")
        box.append((math.log(lo), math.log(hi)))
    xlo = np.array([b[0] for b in box])
    xhi = np.array([b[1] for b in box])
    return SearchBox(names, box, xlo, xhi)


def robot_with(base: RobotParameters, names, x) -> RobotParameters:
    """``base`` with the parameters ``names`` set to ``exp(x)`` [SI]."""
    return base.replace(**{n: float(math.exp(v)) for n, v in zip(names, x)})
