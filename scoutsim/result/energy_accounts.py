"""The energy accounting of a run by name: the energy [J] that went to each destination
(a power flow of ``layout.EN_LEG_NAMES``, a group of them, the battery) from the start of
the run to each sample, the mean power [W] over each control period, the electrical power
into the motors [W], and the work-energy balance (docs/model.md "Work-energy balance"). A
mixin of :class:`~scoutsim.result.simulation_result.SimulationResult`, which holds ``energy_series`` and
``energy_flows`` (runs made with ``simulate(energy=True)``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .._core.model import layout as L
from ..names import leg_index
from ..parameters import RobotParameters
from .run_data import RunData

__all__ = ["EnergyAccessors", "ENERGY_GROUPS", "ENERGY_WHOLE_ROBOT", "ENERGY_COLUMNS"]

#: destinations of the energy that sum several flows of ``layout.EN_LEG_NAMES`` (per
#: virtual leg), for :meth:`SimulationResult.cumulative_energy` and
#: :meth:`SimulationResult.power`: the transmission's losses (the paper's constant
#: efficiency, signed, and the optional load-dependent losses), the motor-joint friction,
#: and every friction and damper of the mechanism (motor joint, belt damper, leg damper
#: and sliding joint, sliding toes)
ENERGY_GROUPS = {
    "transmission": ("conversion", "gear_loss"),
    "joint_friction": ("joint_viscous", "joint_coulomb"),
    "friction": (
        "joint_viscous",
        "joint_coulomb",
        "belt_damper",
        "leg_damper",
        "leg_friction",
        "toe_slide",
    ),
}
#: destinations without a leg: the battery's internal loss, and the battery's whole output
#: (the electrical energy into both legs' motors plus that loss)
ENERGY_WHOLE_ROBOT = ("battery_loss", "battery")


#: names of the columns of :attr:`SimulationResult.energy_series` in the tables
ENERGY_COLUMNS = tuple(
    f"cumulative_energy_{f}_{leg}" for leg in L.LEG_NAMES for f in L.EN_LEG_NAMES
) + ("cumulative_energy_battery_loss",)


class EnergyAccessors(RunData):
    """Named accessors of a run's energy accounting."""

    if TYPE_CHECKING:  # the time series' accessors (series.py), for the type checker

        def motor_current(self, leg) -> np.ndarray: ...
        def motor_speed(self, leg) -> np.ndarray: ...

    def _energy_columns(self, name: str, leg) -> list[int]:
        """Columns of :attr:`energy_series` that make up destination ``name`` of ``leg``
        (None: both legs)."""
        if self.energy_series is None:
            raise ValueError(
                "this run did not account for its energy: run it with "
                "simulate(..., energy=True) (scoutsim run does by default)"
            )
        if name in ENERGY_WHOLE_ROBOT:
            if leg is not None:
                raise ValueError(f"{name!r} is the whole robot's: leg must be None")
            if name == "battery_loss":
                return [L.EN_BATTERY_LOSS]
            return [L.EN_BATTERY_LOSS] + self._energy_columns("electrical", None)
        flows = ENERGY_GROUPS.get(name, (name,))
        for f in flows:
            if f not in L.EN_LEG_NAMES:
                raise ValueError(
                    f"name = {name!r} is not allowed: must be one of "
                    f"{list(L.EN_LEG_NAMES) + list(ENERGY_GROUPS) + list(ENERGY_WHOLE_ROBOT)}"
                )
        legs = (0, 1) if leg is None else (leg_index(leg),)
        return [lg * L.NEN_LEG + L.EN_LEG_NAMES.index(f) for lg in legs for f in flows]

    def cumulative_energy(self, name: str, leg=None) -> np.ndarray:
        """The energy [J] that went to destination ``name`` from the start of the run to
        each sample (docs/model.md "Work-energy balance"; needs ``simulate(energy=True)``).

        Parameters
        ----------
        name : a flow of ``layout.EN_LEG_NAMES`` ("electrical": into the motor terminals,
            "copper", "conversion", "gear_loss", "hip_work", "joint_viscous",
            "joint_coulomb", "belt_damper", "leg_damper", "leg_friction", "toe_slide",
            "constraint"), a group of :data:`ENERGY_GROUPS` ("transmission",
            "joint_friction", "friction": every friction and damper of the mechanism), or
            the whole robot's "battery_loss" (R_b I_b^2) or "battery" (the battery's
            output: electrical energy of both legs plus its loss).
        leg : "back", "front" or None (both virtual legs, each of its motors counted).

        Returns
        -------
        (n,) array [J], aligned with :attr:`t`. The touchdown impacts' losses are not in
        it (they happen at instants: :meth:`impacts`).
        """
        columns = self._energy_columns(name, leg)  # (raises if the run has no accounting)
        assert self.energy_series is not None
        # column by column, so that each sample's sum is the same however many samples
        # are summed at once (a run taken in pieces: result.stride_record)
        out = self.energy_series[:, columns[0]].copy()
        for c in columns[1:]:
            out += self.energy_series[:, c]
        return out

    def power(self, name: str, leg=None) -> np.ndarray:
        """Mean power [W] into destination ``name`` (as :meth:`cumulative_energy`) over
        each control period: element k is (E(t[k+1]) - E(t[k])) / (t[k+1] - t[k]), the
        period that starts at sample k (its command held); the last element is NaN. Its
        sum times the period is the energy exactly (no quadrature error: the energy is
        integrated on every integrator step)."""
        e = self.cumulative_energy(name, leg)
        out = np.full(len(e), np.nan)
        if len(e) > 1:
            out[:-1] = np.diff(e) / np.diff(self.t)
        return out

    def electrical_power(self, leg=None) -> np.ndarray:
        """Electrical power into the motor terminals at each sample [W], from the recorded
        current i and motor speed w_m of every motor: n_p i (R_A i + K_w w_m) per virtual
        leg (n_p motors; docs/specification.md section 4), summed over both legs if ``leg``
        is None. Instantaneous (just after the sample's command), and available without
        the energy accounting; Model I and II only (the ideal actuator and the passive
        model have no electrical side: ValueError)."""
        model = (self.provenance or {}).get("model")
        robot = (self.provenance or {}).get("robot")
        if model not in ("I", "II") or not robot:
            raise ValueError(
                f"electrical_power needs a run of Model I or II with its robot "
                f"in the provenance (this one: model {model!r})"
            )
        legs = (0, 1) if leg is None else (leg_index(leg),)
        p = np.zeros(len(self.t))
        for lg in legs:
            i = self.motor_current(lg)
            w = self.motor_speed(lg)
            motor = RobotParameters(**robot).leg(lg)
            p += (
                robot["legs_per_virtual_leg"]
                * i
                * (motor.armature_resistance * i + motor.speed_constant * w)
            )
        return p

    def energy_balance(self):
        """The run's work-energy balance (:class:`~scoutsim.analysis.energy.EnergyBalance`:
        every term [J], the input, the residual); needs a run made with
        ``simulate(energy=True)``."""
        from ..analysis.energy import energy_balance

        return energy_balance(self)
