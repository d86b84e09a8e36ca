"""Integrator settings: the method (DOPRI5, ARK3, ARK4 or "auto") and its error control
(:class:`IntegratorSettings`), with each method's default tolerances."""

from __future__ import annotations

import math
from dataclasses import dataclass

from .._core.numerics.stepper import METHOD_ARK3, METHOD_ARK4, METHOD_DOPRI5

__all__ = ["IntegratorSettings", "DEFAULT_TOLERANCES", "AUTO_ARK_MIN_RTOL", "METHOD_CODES"]

#: the compiled run loop's code of each method by name
METHOD_CODES = {"dopri5": METHOD_DOPRI5, "ark3": METHOD_ARK3, "ark4": METHOD_ARK4}


#: default (rtol, atol) of each method when the settings leave them open
DEFAULT_TOLERANCES = {"dopri5": (1e-8, 1e-9), "ark3": (1e-5, 1e-6), "ark4": (1e-6, 1e-7)}
#: "auto" uses ARK3 for Model II only down to this rtol (a 3rd-order method is inefficient
#: at tighter tolerances, where the 5th-order DOPRI5 takes over)
AUTO_ARK_MIN_RTOL = 1e-7


@dataclass(frozen=True)
class IntegratorSettings:
    """Integrator and error control (adaptive steps with located events in every method).

    method : "auto" (default), "dopri5", "ark3" or "ark4".
        "dopri5": explicit Dormand-Prince 5(4), the reference (default rtol 1e-8 /
        atol 1e-9; the paper's Working Model runs used an adaptive Kutta-Merson integrator
        at 1e-10, and 1e-8 reproduces their gait metrics to better than 1e-4, see
        tests/_core/numerics). "ark3" / "ark4": additive Runge-Kutta 3(2) / 4(3) with the
        Model II belt dampers (and stiff motor damping) implicit (scoutsim/_core/numerics/ark.py),
        for the stiff Model II. "auto": Model II with ``rtol`` unset or >= 1e-7 -> "ark3"
        (default rtol 1e-5 / atol 1e-6, velocities 1e-5: about 10x faster than the
        reference, 10 s gait metrics within 3e-5 of the rtol 1e-10 reference,
        tests/simulation/test_simulate.py); every other case -> "dopri5".
    rtol, atol : relative / absolute local error tolerance (SI units of each state
        component); None = the method's default (:data:`DEFAULT_TOLERANCES`). The ARK
        methods apply ``atol`` to positions, angles and leg lengths and 10 x ``atol`` to
        the velocities (``ark.VELOCITY_ATOL_FACTOR``: a 0.1 s time scale between the two
        units).
    initial_step : first step guess [s].

    :meth:`resolve` gives the concrete settings a run uses (recorded in its provenance).
    """

    rtol: float | None = None
    atol: float | None = None
    initial_step: float = 1e-4
    method: str = "auto"

    def __post_init__(self):
        if self.method not in METHOD_CODES and self.method != "auto":
            raise ValueError(
                f"integrator.method = {self.method!r} is not allowed: must be one "
                f"of {sorted(METHOD_CODES) + ['auto']}"
            )
        for name in ("rtol", "atol", "initial_step"):
            v = getattr(self, name)
            if v is None and name != "initial_step":
                continue
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError(
                    f"integrator.{name} = {v!r} is not allowed: must be a finite number > 0"
                )
        if self.rtol is not None and self.rtol < 1e-14:
            raise ValueError(f"integrator.rtol = {self.rtol} is not allowed: must be >= 1e-14")

    def resolve(self, model: str = "II") -> IntegratorSettings:
        """The concrete method and tolerances for ``model``."""
        import dataclasses

        m = self.method
        if m == "auto":
            m = (
                "ark3"
                if model == "II" and (self.rtol is None or self.rtol >= AUTO_ARK_MIN_RTOL)
                else "dopri5"
            )
        elif m != "dopri5" and model != "II":
            m = "dopri5"  # the ARK splitting exists for Model II's belts only
        rt, at = DEFAULT_TOLERANCES[m]
        return dataclasses.replace(
            self,
            method=m,
            rtol=rt if self.rtol is None else self.rtol,
            atol=at if self.atol is None else self.atol,
        )
