"""A run as named columns with their SI units: the time series (:meth:`columns`, one
column per state, output and mode, and the cumulative energies [J]), the events and the
integrator steps; the tables a run is saved as (:meth:`tables`) and a pandas DataFrame.
A mixin of :class:`~scoutsim.result.simulation_result.SimulationResult`.
"""

from __future__ import annotations

import numpy as np

from .._core.model import layout as L
from .energy_accounts import ENERGY_COLUMNS
from .run_data import RunData

__all__ = ["ColumnViews", "COLUMN_UNITS", "column_unit"]

#: Unit of each :meth:`SimulationResult.columns` name, by prefix (first match wins):
#: (prefix, SI unit, exact match). Mode columns and the ``dynamics_solved`` flag (1: the
#: constrained dynamics solved, 0: singular) are codes without a unit.
COLUMN_UNITS = (
    ("t", "s", True),
    ("x", "m", True),
    ("y", "m", True),
    ("theta", "rad", True),
    ("phi_", "rad", False),
    ("alpha_", "rad", False),
    ("dx", "m/s", True),
    ("dy", "m/s", True),
    ("dtheta", "rad/s", True),
    ("dphi_", "rad/s", False),
    ("dalpha_", "rad/s", False),
    ("leg_length_", "m", False),
    ("ground_force_", "N", False),
    ("leg_axial_force_", "N", False),
    ("hip_torque_", "N m", False),
    ("motor_current_", "A", False),
    ("motor_speed_", "rad/s", False),
    ("belt_deflection_", "rad", False),
    ("stiction_holding_torque_", "N m", False),
    ("toe_x_", "m", False),
    ("toe_y_", "m", False),
    ("toe_velocity_x_", "m/s", False),
    ("strut_force_", "N", False),
    ("belt_torque_", "N m", False),
    ("battery_voltage", "V", True),
    ("energy", "J", True),
    ("cumulative_energy_", "J", False),
)


def column_unit(name: str) -> str | None:
    """Unit of a :meth:`SimulationResult.columns` name (None for mode codes and unknown
    names)."""
    for prefix, unit, exact in COLUMN_UNITS:
        if (name == prefix) if exact else name.startswith(prefix):
            return unit
    return None


class ColumnViews(RunData):
    """A run's arrays as named columns and tables."""

    def columns(self) -> dict:
        """All time series as named 1-D arrays (for CSV export / DataFrames); with the
        energy accounting also :attr:`energy_series`, one ``cumulative_energy_<flow>_<leg>``
        column per flow and ``cumulative_energy_battery_loss`` [J]."""
        cols = {"t": self.t}
        for i, n in enumerate(L.STATE_NAMES):
            cols[n] = self.state[:, i]
        for leg in range(2):
            for j, n in enumerate(L.AUX_LEG_NAMES):
                cols[f"{n}_{L.LEG_NAMES[leg]}"] = self.aux[:, leg * L.NAUX_LEG + j]
        cols["battery_voltage"] = self.aux[:, L.A_VBATT]
        cols["energy"] = self.aux[:, L.A_ENERGY]
        cols["dynamics_solved"] = self.aux[:, L.A_KKT_OK]
        for leg in range(2):
            for base, what in (
                (L.RM_LEG_STATE_B, "leg_state"),
                (L.RM_CONTACT_B, "contact_mode"),
                (L.RM_MOTOR_B, "motor_joint_mode"),
            ):
                cols[f"{what}_{L.LEG_NAMES[leg]}"] = self.modes[:, base + leg].astype(float)
        if self.energy_series is not None:
            for j, name in enumerate(ENERGY_COLUMNS):
                cols[name] = self.energy_series[:, j]
        return cols

    def event_columns(self) -> dict:
        """The events as named columns: time [s], kind (code and name), leg (0 back, 1
        front, -1 none), the kind's values v1-v3 (``layout`` "event record"), the
        transition's energies before / after [J] and violated invariants (bit mask), and,
        where recorded, the state just before (``<name>_before``) and after
        (``<name>_after``) the transition (``STATE_NAMES``, SI)."""
        ev = self.events
        kinds = ev[:, L.EVR_KIND].astype(np.int8)
        cols = {
            "t": ev[:, L.EVR_T],
            "kind": kinds,
            "kind_name": np.array([L.EVENT_KIND_NAMES.get(int(k), "?") for k in kinds], dtype=str),
            "leg": ev[:, L.EVR_LEG].astype(np.int8),
            "v1": ev[:, L.EVR_V1],
            "v2": ev[:, L.EVR_V2],
            "v3": ev[:, L.EVR_V3],
            "energy_before": ev[:, L.EVR_E_BEFORE],
            "energy_after": ev[:, L.EVR_E_AFTER],
            "violations": ev[:, L.EVR_VIOLATIONS].astype(np.int32),
        }
        if self.event_states is not None:
            for when, slot in (("before", L.EVS_BEFORE), ("after", L.EVS_AFTER)):
                for i, n in enumerate(L.STATE_NAMES):
                    cols[f"{n}_{when}"] = self.event_states[:, slot, i]
        return cols

    def step_columns(self) -> dict | None:
        """The integrator steps (if recorded) as named columns: time [s] and state at the
        end of each step, the plant modes during it."""
        if self.steps is None:
            return None
        st = self.steps
        cols = {"t": st[:, L.STP_T]}
        for i, n in enumerate(L.STATE_NAMES):
            cols[n] = st[:, L.STP_STATE + i]
        for leg, name in enumerate(L.LEG_NAMES):
            cols[f"contact_mode_{name}"] = st[:, L.STP_CONTACT_B + leg].astype(np.int8)
            cols[f"motor_joint_mode_{name}"] = st[:, L.STP_MOTOR_B + leg].astype(np.int8)
        return cols

    def tables(self) -> dict:
        """The run's tables as ``{name: (columns, units)}``: ``timeseries``, ``events`` and,
        if recorded, ``steps`` (what :meth:`save_tables` writes, and a streamed run writes
        piece by piece: :mod:`scoutsim.simulation.streaming`)."""
        series = self.columns()
        for n in series:
            if column_unit(n) is None:
                series[n] = series[n].astype(np.int8)
        out = {"timeseries": (series, {n: column_unit(n) for n in series})}
        ev = self.event_columns()
        ev_units: dict[str, str | None] = {"t": "s", "energy_before": "J", "energy_after": "J"}
        for n in ev:
            for when in ("_before", "_after"):
                if n.endswith(when) and not n.startswith("energy"):
                    ev_units[n] = column_unit(n[: -len(when)])
        out["events"] = (ev, ev_units)
        st = self.step_columns()
        if st is not None:
            out["steps"] = (st, {n: column_unit(n) for n in st})
        return out

    def to_dataframe(self):
        """All time series as a :class:`pandas.DataFrame` indexed by time ``t`` [s], one
        column per :meth:`columns` name (SI; mode columns as integer codes, see
        ``layout.LEG_STATE_NAMES`` / ``CONTACT_NAMES``); ``df.attrs["units"]`` maps each
        column to its unit. Needs pandas (``pip install pandas``)."""
        try:
            import pandas as pd
        except ImportError as exc:
            raise ImportError(
                "SimulationResult.to_dataframe needs pandas: pip install pandas "
                "(or pip install 'scoutsim[dataframe]')"
            ) from exc
        cols = self.columns()
        for n in cols:
            if column_unit(n) is None:
                cols[n] = cols[n].astype(np.int8)
        df = pd.DataFrame(cols).set_index("t")
        df.attrs["units"] = {n: column_unit(n) for n in cols}
        return df
