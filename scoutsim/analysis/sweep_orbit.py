"""A sweep point's periodic orbit (``sweep(orbit=True)``, :mod:`scoutsim.analysis.sweep`; a
tuning's ``"stability"`` objective): the controlled orbit found by Newton from a steadily
bounding run's last strides, and the table columns that record it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: columns added by ``orbit=True``: the controlled orbit at the point (Newton from the run's
#: last strides, :func:`scoutsim.analysis.controlled_orbit.controlled_fixed_point`): its
#: period [s] and strides per period (a cycle of several strides), spectral radius of the
#: period's map and its k-th root, the contraction per stride (comparable between cycles
#: of different lengths), stability, residual (and the map's rounding noise where Newton
#: stopped above its tolerance within it, else NaN), and "ok" or why there is none
ORBIT_COLUMNS = (
    "orbit_period_s",
    "orbit_strides",
    "orbit_spectral_radius",
    "orbit_spectral_radius_per_stride",
    "orbit_stable",
    "orbit_residual",
    "orbit_residual_noise",
    "orbit_status",
)
#: integrator and tolerance of the per-point orbit (looser than the single-orbit default,
#: rtol 1e-11 / 1e-10: a sweep wants stability, not the 12th digit)
ORBIT_RTOL = 1e-9
ORBIT_TOL = 1e-7


def orbit_columns(result, robot, ctrl, task) -> dict:
    """The :data:`ORBIT_COLUMNS` of a steadily bounding run: its controlled orbit by Newton
    from its last strides (``task``: the run's ``model`` and ``friction_coefficient``).
    Where there is none, ``orbit_status`` says why; a controller's own exception in the
    search (a ControllerError with a cause) is raised: an error of the study, not a point
    without an orbit."""
    from ..control.dispatch import ControllerStateError
    from ..simulation.integrator import IntegratorSettings
    from .controlled_orbit import NewtonSettings, controlled_fixed_point
    from .poincare import MapError

    out: dict[str, Any] = {k: None for k in ORBIT_COLUMNS}
    try:
        o = controlled_fixed_point(
            result,
            model=task["model"],
            friction_coefficient=task["friction_coefficient"],
            robot=robot,
            controller=ctrl,
            newton=NewtonSettings(tol=ORBIT_TOL, max_iter=6),
            integrator=IntegratorSettings(rtol=ORBIT_RTOL, atol=ORBIT_RTOL / 10),
        )
        rho = float(np.max(np.abs(o.multipliers)))
        out.update(
            orbit_period_s=o.period,
            orbit_strides=o.strides,
            orbit_residual=o.residual,
            orbit_residual_noise=o.residual_noise,
            orbit_spectral_radius=rho,
            orbit_spectral_radius_per_stride=rho ** (1.0 / o.strides),
            orbit_stable=o.stable,
            orbit_status="ok",
        )
    except (MapError, ControllerStateError) as exc:
        # (a controller whose state scoutsim cannot read has no orbit here; the run's own
        # row stands)
        out["orbit_status"] = f"no orbit: {exc}"
    return out
