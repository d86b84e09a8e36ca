"""Why a run failed numerically: :func:`diagnose_failure` reads a result whose outcome is
"numerical_failure" and says what stopped it and what to look at.

The compiled run loop ends a run as a numerical failure for several reasons: the
constrained equations of motion could not be solved (a singular or ill-conditioned
system), an event could not be applied, or the integrator could not continue (no step met
the tolerance down to the smallest step size, a step produced non-finite values, or one
control period needed more steps or events than allowed). The first kind points at the
model (its parameters or its state), the last at the integrator or at forces that change
faster than any step can follow. The result keeps what tells them apart: the last sample's
"dynamics solved" flag, the transition records (energies and violated invariants), the
state, forces and energy of every sample and the integrator statistics; and its provenance
holds the parameters, which are compared with the Scout II defaults.

    r = scoutsim.simulate(...)
    if r.failure is not None:
        print(r.failure.message())

Classification, first match wins:

* ``"singular_dynamics"``: the last sample's dynamics did not solve, or the last
  transition was stamped "constrained dynamics singular";
* ``"non_finite"``: a state, force or energy value is NaN or infinite;
* ``"energy"``: the mechanical energy rose to more than :data:`ENERGY_GROWTH` times its
  starting value (at least 1 J), far more than the motors add in a run: some state or
  force became absurd;
* ``"integrator"``: none of these: the values stayed finite and plausible and the
  integrator stopped.

Independently, the parameters farther than a factor :data:`FAR_FACTOR` from their
Scout II default are listed (for a default of 0: above :data:`FAR_FACTOR` times a Scout II
reference scale of the same dimension). The advice names them if there are any, else the
integrator tolerance.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .._core.model import layout as L
from .._core.model.flags import flag_is_set
from ..parameters import (
    UNITS,
    ControllerParameters,
    RobotParameters,
    field_dimension,
    parameter_table,
)

__all__ = ["FailureDiagnosis", "diagnose_failure", "far_parameters", "FAR_FACTOR", "ENERGY_GROWTH"]

#: A parameter counts as far from its Scout II default beyond this factor either way.
FAR_FACTOR = 100.0
#: Energy above this multiple of the starting energy (at least 1 J) counts as blown up
#: (the default 10 s Model II run holds 92-112 J of mechanical energy throughout).
ENERGY_GROWTH = 1.0e3
#: rtol at or below which a stalled integrator is advised to loosen the tolerance (the
#: error estimate of a step is then dominated by round-off, ~1e-16 of each state value).
TIGHT_RTOL = 1e-12

KINDS = ("singular_dynamics", "non_finite", "energy", "integrator")


@dataclass(frozen=True)
class FarParameter:
    """A parameter of a run far from its Scout II default (SI values)."""

    name: str  #: "section.field", as in the parameter files (e.g. robot.torso_mass)
    value: float
    default: float
    unit: str  #: SI unit ("" for dimensionless)
    reference: float | None = None  #: scale it was compared with when the default is 0

    def text(self) -> str:
        u = f" {self.unit}" if self.unit else ""
        if self.reference is not None:
            return (
                f"{self.name} = {self.value:.4g}{u} (default 0; more than {FAR_FACTOR:g} "
                f"x the reference {self.reference:.4g}{u})"
            )
        return f"{self.name} = {self.value:.4g}{u} (default {self.default:.4g}{u})"

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class FailureDiagnosis:
    """What stopped a run that failed numerically, and what to check.

    Attributes
    ----------
    kind : str
        "singular_dynamics", "non_finite", "energy" or "integrator" (module docstring).
    t : float
        Time the run reached [s].
    what : str
        What happened, in one sentence (facts read from the result).
    parameters : tuple of FarParameter
        Parameters farther than :data:`FAR_FACTOR` from their Scout II defaults.
    rtol : float or None
        Relative tolerance of the run's integrator (None if not recorded).
    """

    kind: str
    t: float
    what: str
    parameters: tuple = ()
    rtol: float | None = None

    @property
    def suspects_parameters(self) -> bool:
        """True if some parameters are far from the Scout II defaults."""
        return bool(self.parameters)

    def advice(self, cli: bool = False) -> str:
        """What to check or change; ``cli``: name the ``scoutsim`` options, else the
        Python API."""
        rtol = "--rtol" if cli else "IntegratorSettings(rtol=...)"
        if self.parameters:
            far = "; ".join(p.text() for p in self.parameters)
            text = (
                f"parameters far from the Scout II defaults (factor > {FAR_FACTOR:g}): "
                f"{far}; check them"
            )
            if self.kind == "integrator":
                text += f" (if they are intended, a different {rtol} may get through)"
            return text
        if self.kind == "integrator":
            if self.rtol is not None and self.rtol <= TIGHT_RTOL:
                return (
                    f"no parameter is far from its Scout II default; at rtol = "
                    f"{self.rtol:g} round-off can keep every step's error above the "
                    f"tolerance: try a larger {rtol}"
                )
            method = "" if cli else " or another IntegratorSettings(method=...)"
            return f"no parameter is far from its Scout II default; try a smaller {rtol}{method}"
        return (
            f"no parameter is far from its Scout II default; check the initial state "
            f"and the combination of parameters, or try a smaller {rtol}"
        )

    def message(self, cli: bool = False) -> str:
        """The whole diagnosis: what happened, then the advice."""
        return f"{self.what}; {self.advice(cli)}"

    def to_dict(self) -> dict:
        """JSON-safe dict (for the run summary)."""
        return {
            "kind": self.kind,
            "t_s": float(self.t),
            "what": self.what,
            "parameters": [p.to_dict() for p in self.parameters],
            "advice": self.advice(),
            "message": self.message(),
        }


@lru_cache(maxsize=1)
def _sections() -> dict:
    return {row["name"]: row["section"] for row in parameter_table()}


def _si_unit(name: str) -> str:
    dimension = field_dimension(name)
    assert dimension is not None, f"{name} is a parameter with a unit"
    unit = next(iter(UNITS[dimension]))
    return "" if unit in ("1", "bool") else unit


def _reference_scales() -> dict:
    """Scout II scale of each dimension, for parameters whose default is 0."""
    r = RobotParameters()
    weight = r.total_mass * r.gravity
    return {
        "force": weight,
        "torque": r.max_leg_torque,
        "resistance": r.armature_resistance,
        "dimensionless": 1.0,
        "per squared angle": 1.0,
    }


def far_parameters(robot: dict | None, controller: dict | None = None) -> tuple:
    """Parameters farther than :data:`FAR_FACTOR` from their Scout II defaults.

    Parameters
    ----------
    robot, controller : dict or None
        Field name -> SI value (as in a result's provenance, ``dataclasses.asdict``).

    Returns
    -------
    tuple of FarParameter
        In field order. A value of 0 is never far (it switches an effect off); angles are
        not compared (their range is bounded). For a default of 0 the value is compared
        with a Scout II scale of its dimension (weight for forces, the current-limited leg
        torque for torques, the armature resistance for resistances, 1 otherwise).
    """
    scales = _reference_scales()
    out = []
    for values, cls in ((robot, RobotParameters), (controller, ControllerParameters)):
        if not values:
            continue
        default = cls()
        for f in dataclasses.fields(cls):
            v, d = values.get(f.name), getattr(default, f.name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or isinstance(d, bool):
                continue
            dim = field_dimension(f.name)
            if v == 0 or dim == "angle":
                continue
            label = f"{_sections()[f.name]}.{f.name}"
            if not math.isfinite(v):
                out.append(FarParameter(label, float(v), float(d), _si_unit(f.name)))
            elif d != 0:
                ratio = abs(v / d)
                if ratio > FAR_FACTOR or ratio < 1.0 / FAR_FACTOR:
                    out.append(FarParameter(label, float(v), float(d), _si_unit(f.name)))
            elif dim in scales and abs(v) > FAR_FACTOR * scales[dim]:
                out.append(FarParameter(label, float(v), 0.0, _si_unit(f.name), scales[dim]))
    return tuple(out)


def _event_name(row) -> str:
    kind = L.EVENT_KIND_NAMES.get(int(row[L.EVR_KIND]), "event")
    leg = int(row[L.EVR_LEG])
    return f"{kind} of the {L.LEG_NAMES[leg]} leg" if 0 <= leg < 2 else kind


def diagnose_failure(result) -> FailureDiagnosis | None:
    """The :class:`FailureDiagnosis` of a :class:`~scoutsim.result.simulation_result.SimulationResult`, or
    None if its outcome is not "numerical_failure"."""
    if result.outcome != "numerical_failure":
        return None
    prov = result.provenance or {}
    integ = prov.get("integrator") or {}
    rtol = integ.get("rtol")
    far = far_parameters(prov.get("robot"), prov.get("controller"))
    t_end = float(result.t_end)
    state = np.asarray(result.state)
    aux = np.asarray(result.aux)
    events = np.asarray(result.events)

    def make(kind, what):
        return FailureDiagnosis(kind, t_end, what, far, rtol)

    # 1. the equations of motion could not be solved (at the last sample, or in the
    # transition the run ended in)
    singular = []
    if events.ndim == 2 and events.shape[1] > L.EVR_VIOLATIONS and len(events):
        v = events[:, L.EVR_VIOLATIONS]
        last = (events[:, L.EVR_T] >= t_end) & np.isfinite(v)
        singular = [row for row in events[last] if int(row[L.EVR_VIOLATIONS]) & L.V_SINGULAR]
    if (len(aux) and not flag_is_set(aux[-1, L.A_KKT_OK])) or singular:
        where = f" (at the {_event_name(singular[-1])})" if singular else ""
        return make(
            "singular_dynamics",
            f"at t = {t_end:.6g} s the constrained equations of motion could not be "
            f"solved{where}: the system is singular or too ill-conditioned to solve",
        )
    # 2. non-finite values
    if len(state):
        bad = ~(np.all(np.isfinite(state), axis=1) & np.all(np.isfinite(aux), axis=1))
        if bad.any():
            k = int(np.argmax(bad))
            cols = result.columns()
            names = [n for n, c in cols.items() if n != "t" and not np.isfinite(c[k])]
            shown = ", ".join(names[:6]) + (f" and {len(names) - 6} more" if len(names) > 6 else "")
            return make(
                "non_finite",
                f"at t = {float(result.t[k]):.6g} s these values are not finite: {shown}",
            )
    # 3. the energy blew up
    energy = aux[:, L.A_ENERGY] if len(aux) else np.zeros(0)
    if len(energy):
        e0 = float(energy[0])
        k = int(np.argmax(np.abs(energy)))
        if abs(energy[k]) > ENERGY_GROWTH * max(abs(e0), 1.0):
            return make(
                "energy",
                f"the mechanical energy rose from {e0:.4g} J to "
                f"{float(energy[k]):.4g} J by t = {float(result.t[k]):.6g} s",
            )
    # 4. the integrator stopped with finite, plausible values
    stats = result.stats or {}
    steps = float(stats.get("steps", float("nan")))
    rejected = float(stats.get("rejected_steps", float("nan")))
    hmin = float(stats.get("min_step_s", float("nan")))
    method = integ.get("method", "?")
    from .._core.numerics.hybrid import MAX_EVENTS_PER_PERIOD, MAX_STEPS_PER_PERIOD

    detail = (
        f"smallest accepted step {hmin:.3g} s" if math.isfinite(hmin) else "no step was accepted"
    )
    if math.isfinite(steps) and math.isfinite(rejected):
        detail += f", {rejected:.0f} of {steps + rejected:.0f} steps rejected"
    tol = "".join(
        f", {k} {integ[k]:g}" for k in ("rtol", "atol") if isinstance(integ.get(k), (int, float))
    )
    return make(
        "integrator",
        f"at t = {t_end:.6g} s the integrator ({method}{tol}) could not go on: no step "
        f"met the tolerance down to the smallest step size, a step gave non-finite "
        f"values, or a control period needed more than {MAX_STEPS_PER_PERIOD} steps "
        f"or {MAX_EVENTS_PER_PERIOD} events ({detail}); the state, forces and energy "
        f"stayed finite",
    )
