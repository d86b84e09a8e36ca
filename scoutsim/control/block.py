"""The control block: what the compiled run loop needs of the controller and the sensors.

One named tuple of arrays (:class:`ControlBlock`), built once per run by
:func:`scoutsim.control.dispatch.plan_controller` and carried from one call of the run loop
to the next, so a run cut into calls reads its sensors and runs its controller exactly as
one call would:

ints : int64 (``layout.NCB``)
    which controller runs (``CB_KIND``: ``layout.CTRL_*``), the address of a compiled
    controller function (``CB_ADDRESS``), the seed of the sensor noise (``CB_SEED``).
spec : (``layout.NSPEC``, ``layout.NSN``)
    each sensor slot's noise, bias, resolution and delay (:mod:`scoutsim._core.model.sensor_readings`).
geom : (``layout.NSG``)
    the sensors' geometry and flags.
hist : (delay + 1, ``layout.NSN``)
    the last readings, for delayed channels.
y : (``layout.NSN``)
    the readings of the current sample: what the controller sees.
last : (``layout.NS + layout.NAUX``)
    the model's evaluation that ended the last control period (derivative, outputs): what
    the IMU's accelerometer, the current sensors and the battery monitor read.
params, state : float64 arrays
    a compiled controller's own parameters and state (:class:`CompiledController`).
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from .._core.model import layout as L

__all__ = ["ControlBlock", "control_block"]

ControlBlock = namedtuple("ControlBlock", "ints spec geom hist y last params state")


def control_block(
    kind: int,
    *,
    address: int = 0,
    spec: np.ndarray | None = None,
    geom: np.ndarray | None = None,
    seed: int = 0,
    params: np.ndarray | None = None,
    state: np.ndarray | None = None,
) -> ControlBlock:
    """A fresh control block for one run (see the module docstring); ``spec`` and ``geom``
    default to ideal sensors with the lasers at the Scout II torso ends."""
    ints = np.zeros(L.NCB, dtype=np.int64)
    ints[L.CB_KIND] = kind
    ints[L.CB_ADDRESS] = address
    ints[L.CB_SEED] = seed
    spec = np.zeros((L.NSPEC, L.NSN)) if spec is None else np.ascontiguousarray(spec, float)
    if geom is None:
        geom = np.zeros(L.NSG)
        geom[L.SG_LASER_HALF_SPACING] = 0.35
    depth = int(spec[L.SPEC_DELAY].max()) + 1
    return ControlBlock(
        ints=ints,
        spec=spec,
        geom=np.ascontiguousarray(geom, float),
        hist=np.zeros((depth, L.NSN)),
        y=np.zeros(L.NSN),
        last=np.zeros(L.NS + L.NAUX),
        params=(
            np.zeros(1)
            if params is None or params.size == 0
            else np.ascontiguousarray(params, dtype=np.float64)
        ),
        state=(
            np.zeros(1)
            if state is None or state.size == 0
            else np.ascontiguousarray(state, dtype=np.float64)
        ),
    )
