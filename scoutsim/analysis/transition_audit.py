"""Transition audit: energy accounting and mode consistency at every plant transition.

Every discontinuity of the hybrid model (touchdown impact, lift-off, slide / stick, strut,
motor-joint stick / slip, the massless passive touchdown, a mode change caused by a new
command) is a *transition*. The compiled run loop records, for each one, the total
mechanical energy just before it and after the modes have settled, and a bit mask of the
mode invariants that the state violates afterwards (:class:`scoutsim.names.Violation`: a
pinned toe the ground pulls, a stuck joint beyond breakaway, a joint slipping against its
motion, ...). This module reads those records (``result.event_log()``) and checks the two
laws every transition must obey:

* **energy**: mechanical energy may only drop, and only by a logged loss with a physical
  cause: the kinetic energy a touchdown impact or a jam dissipates (logged with its impulse). Every
  other transition leaves the energy unchanged (forces change, the state does not jump);
* **consistency**: after the transition the modes agree with the velocities and forces.

    audit = scoutsim.analysis.transition_audit.audit_transitions(result)
    audit.ok, audit.problems(), audit.n_transitions, audit.total_logged_loss_J

The records cost nothing extra in a run (the energies are evaluated anyway); the audit is
meant for tests and for users who change the model.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..names import EVENT_KIND_NAMES, VIOLATION_NAMES, EventKind
from .energy import EnergyBalance

#: default tolerance of the energy balance of one transition, relative to the larger of the
#: energies before and after it and 1 J (Scout II holds about 80 J of mechanical energy)
ENERGY_REL_TOL = 1e-9
#: tolerance of the whole run's work-energy balance (runs made with ``energy=True``),
#: relative to its input, in units of the integrator's rtol: the residual is integration
#: error (measured over 10 s of bounding: 20-35 rtol for DOPRI5 at 1e-8 and ARK3 at 1e-5)
BALANCE_RTOL_FACTOR = 100.0


@dataclass(frozen=True)
class Transition:
    """One plant transition: the event records it logged and its audit."""

    t: float  #: time [s]
    kinds: tuple  #: names of the event records it logged, in order
    legs: tuple  #: leg of each record (0 back, 1 front, -1 none)
    energy_before_J: float
    energy_after_J: float
    logged_loss_J: float  #: kinetic energy the touchdown impacts of this transition lost
    violations: int  #: bit mask of scoutsim.names.Violation

    @property
    def unexplained_loss_J(self) -> float:
        """Energy lost beyond the logged losses [J] (negative: energy gained)."""
        return (self.energy_before_J - self.energy_after_J) - self.logged_loss_J

    def violation_names(self) -> list:
        return [name for bit, name in VIOLATION_NAMES.items() if self.violations & bit]


@dataclass(frozen=True)
class TransitionAudit:
    transitions: tuple
    rel_tol: float = ENERGY_REL_TOL
    #: the run's work-energy balance (:class:`~scoutsim.analysis.energy.EnergyBalance`) if
    #: it accounted for its energy (``simulate(energy=True)``), else None
    balance: EnergyBalance | None = None
    #: tolerance of the balance's relative residual
    balance_tol: float = 1e-6

    @property
    def n_transitions(self) -> int:
        return len(self.transitions)

    @property
    def total_logged_loss_J(self) -> float:
        return float(sum(tr.logged_loss_J for tr in self.transitions))

    @property
    def total_energy_drop_J(self) -> float:
        """Sum over transitions of the energy before minus after [J]."""
        return float(sum(tr.energy_before_J - tr.energy_after_J for tr in self.transitions))

    def problems(self) -> list:
        """One line per transition that breaks energy accounting or mode consistency."""
        out = []
        for tr in self.transitions:
            what = "+".join(tr.kinds)
            if not (np.isfinite(tr.energy_before_J) and np.isfinite(tr.energy_after_J)):
                out.append(f"t = {tr.t:.9f} s {what}: energy not finite")
                continue
            scale = max(abs(tr.energy_before_J), abs(tr.energy_after_J), 1.0)
            if abs(tr.unexplained_loss_J) > self.rel_tol * scale:
                out.append(
                    f"t = {tr.t:.9f} s {what}: energy {tr.energy_before_J:.9f} -> "
                    f"{tr.energy_after_J:.9f} J, logged loss {tr.logged_loss_J:.3e} J, "
                    f"unexplained {tr.unexplained_loss_J:+.3e} J"
                )
            if tr.logged_loss_J < -self.rel_tol * scale:
                out.append(
                    f"t = {tr.t:.9f} s {what}: an impact gained energy ({-tr.logged_loss_J:.3e} J)"
                )
            if tr.violations:
                out.append(f"t = {tr.t:.9f} s {what}: " + ", ".join(tr.violation_names()))
        b = self.balance
        if b is not None and not abs(b.relative_residual) <= self.balance_tol:
            out.append(
                f"work-energy balance: residual {b.residual_J:+.3e} J = "
                f"{b.relative_residual:+.1e} of the input ({b.input_J:.3f} J), beyond "
                f"{self.balance_tol:.0e}"
            )
        return out

    @property
    def ok(self) -> bool:
        return not self.problems()


def audit_transitions(result, rel_tol: float = ENERGY_REL_TOL) -> TransitionAudit:
    """The transition audit of a :class:`~scoutsim.result.simulation_result.SimulationResult`.

    ``rel_tol``: energy balance tolerance of one transition, relative to its energy scale.
    A run made with ``simulate(energy=True)`` is also audited as a whole: its work-energy
    balance (``audit.balance``) must close to ``BALANCE_RTOL_FACTOR`` times the integrator's
    rtol of the input (at least 1e-6). Results saved before the audit existed carry no
    audit columns: ValueError."""
    log = result.event_log()
    t, kind, leg, v3 = log["t"], log["kind"], log["leg"], log["v3"]
    e_before, e_after, violations = log["energy_before"], log["energy_after"], log["violations"]
    out: list[dict[str, Any]] = []
    cur: dict[str, Any] | None = None
    for i in range(len(t)):
        eb, ea = e_before[i], e_after[i]
        if np.isnan(eb):
            cur = None  # a controller record: not a plant transition
            continue
        key = (t[i], eb, ea if not np.isnan(ea) else None)
        if cur is None or cur["key"] != key:
            cur = {"key": key, "rows": []}
            out.append(cur)
        cur["rows"].append(i)
    trs = []
    for g in out:
        rows = g["rows"]
        loss = sum(v3[i] for i in rows if kind[i] in (EventKind.TOUCHDOWN, EventKind.JAM))
        bits = 0
        for i in rows:
            bits |= int(violations[i])
        trs.append(
            Transition(
                t=float(t[rows[0]]),
                kinds=tuple(EVENT_KIND_NAMES.get(int(kind[i]), "?") for i in rows),
                legs=tuple(int(leg[i]) for i in rows),
                energy_before_J=float(e_before[rows[0]]),
                energy_after_J=float(e_after[rows[0]]),
                logged_loss_J=float(loss),
                violations=bits,
            )
        )
    balance = None
    balance_tol = 1e-6
    if getattr(result, "energy_flows", None) is not None:
        from .energy import energy_balance

        balance = energy_balance(result)
        rtol = (result.provenance.get("integrator") or {}).get("rtol") or 1e-8
        balance_tol = max(1e-6, BALANCE_RTOL_FACTOR * rtol)
    return TransitionAudit(tuple(trs), rel_tol, balance, balance_tol)
