"""Saving and loading a run, losslessly: one ``.npz`` file (arrays bit-exact, metadata as
JSON), or a directory of tables (``timeseries``, ``events``, ``steps``: Parquet or
gzip-compressed CSV through :mod:`scoutsim.io.tables`, with units and metadata), read back bit
for bit, optionally only a time window [s]. A mixin of
:class:`~scoutsim.result.simulation_result.SimulationResult`.
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path
from typing import TYPE_CHECKING, Any, Self

import numpy as np

from .._core.model import layout as L
from .energy_accounts import ENERGY_COLUMNS
from .run_data import RunData

__all__ = ["ResultFiles", "TABLES_FORMAT"]

#: ``format`` of the metadata of a run's tables (:meth:`SimulationResult.save_tables`)
TABLES_FORMAT = "scoutsim.run/1"


class ResultFiles(RunData):
    """Saving and loading a run (``.npz`` or tables)."""

    if TYPE_CHECKING:  # the class's own window and the column views' tables, for the checker

        def window(self, t0: float, t1: float) -> Self: ...
        def tables(self) -> dict: ...

    def save(self, path) -> Path:
        """Save losslessly to ``path`` (.npz)."""
        path = Path(path)
        meta = {
            "outcome": self.outcome,
            "t_end": self.t_end,
            "stats": self.stats,
            "provenance": self.provenance,
            "format": "scoutsim.result/1",
            "energy_flows": self.energy_flows,
        }
        extra: dict[str, Any] = {
            name: a
            for name, a in (
                ("event_states", self.event_states),
                ("steps", self.steps),
                ("energy_series", self.energy_series),
            )
            if a is not None
        }
        np.savez_compressed(
            path,
            t=self.t,
            state=self.state,
            aux=self.aux,
            modes=self.modes,
            events=self.events,
            meta=np.array(json.dumps(meta, allow_nan=True)),
            **extra,
        )
        return path if path.suffix == ".npz" else path.with_suffix(path.suffix + ".npz")

    @classmethod
    def load(cls, path, *, t_range: tuple[float, float] | None = None) -> Self:
        """Load a result written by :meth:`save` (``.npz``) or by :meth:`save_tables` or a
        streamed run (the directory, or its ``timeseries`` table), bit for bit.

        ``t_range`` = (t0, t1) [s]: only the samples, events and steps in that window (from
        Parquet tables only the row groups that hold them are read: a window of a long
        streamed run needs the memory of the window); outcome, end time, statistics and
        provenance stay the whole run's."""
        path = Path(path)
        if path.is_dir() or not path.name.lower().endswith(".npz"):
            return cls._load_tables(path, t_range)
        try:
            r = cls._load_npz(path)
            return r if t_range is None else r.window(*t_range)
        except (EOFError, zipfile.BadZipFile, KeyError, json.JSONDecodeError) as exc:
            size = path.stat().st_size
            what = (
                "it is empty (0 bytes)"
                if size == 0
                else f"it is cut off or damaged ({size} bytes: {type(exc).__name__}: {exc})"
            )
            raise ValueError(f"{path}: not a readable scoutsim result: {what}") from None

    @classmethod
    def _load_npz(cls, path: Path) -> Self:
        with np.load(path, allow_pickle=False) as z:
            meta = json.loads(str(z["meta"]))
            if meta.get("format") != "scoutsim.result/1":
                raise ValueError(f"{path}: not a scoutsim result file")
            events = z["events"]
            if events.shape[1] < L.NEVREC:
                # saved before the transition audit columns existed: they are unknown
                pad = np.full((events.shape[0], L.NEVREC - events.shape[1]), np.nan)
                events = np.hstack([events, pad])
            return cls(
                t=z["t"],
                state=z["state"],
                aux=z["aux"],
                modes=z["modes"],
                events=events,
                outcome=meta["outcome"],
                t_end=meta["t_end"],
                stats=meta["stats"],
                provenance=meta["provenance"],
                event_states=z["event_states"] if "event_states" in z.files else None,
                steps=z["steps"] if "steps" in z.files else None,
                energy_flows=meta.get("energy_flows"),
                energy_series=(z["energy_series"] if "energy_series" in z.files else None),
            )

    def save_tables(self, directory, *, fmt: str | None = None) -> list[Path]:
        """Write the run as tables into ``directory``: ``timeseries`` (every sample, every
        :meth:`columns` name, with the outcome, statistics and provenance as metadata),
        ``events`` (:meth:`event_columns`) and, if recorded, ``steps``
        (:meth:`step_columns`); Parquet if pyarrow is installed, else gzip-compressed CSV
        (``fmt``: "parquet" or "csv"). :meth:`load` reads them back bit for bit. Returns
        the paths written."""
        from ..io.tables import default_format, write_table

        fmt = fmt or default_format()
        d = Path(directory)
        d.mkdir(parents=True, exist_ok=True)
        paths = []
        for name, (cols, units) in self.tables().items():
            meta = self.series_metadata() if name == "timeseries" else {"format": TABLES_FORMAT}
            paths.append(write_table(d / name, cols, units=units, metadata=meta, fmt=fmt))
        return paths

    def series_metadata(self) -> dict:
        """The metadata of the ``timeseries`` table: outcome, end time, statistics,
        provenance."""
        return {
            "format": TABLES_FORMAT,
            "outcome": self.outcome,
            "t_end": self.t_end,
            "stats": self.stats,
            "provenance": self.provenance,
            "event_states": self.event_states is not None,
            "energy_flows": self.energy_flows,
        }

    @classmethod
    def _timeseries_table(cls, path: Path) -> Path:
        """The ``timeseries`` table of a saved run (its directory, or the table itself),
        after checking that the run's directory was written completely."""
        from ..io.run_directory import check_run_directory
        from ..io.tables import SUFFIXES, TableError

        check_run_directory(path if path.is_dir() else path.parent)
        if not path.is_dir():
            return path
        found = [
            path / f"timeseries{x}" for x in SUFFIXES.values() if (path / f"timeseries{x}").exists()
        ]
        if not found:
            raise TableError(
                f"{path}: no timeseries table "
                f"({', '.join('timeseries' + x for x in SUFFIXES.values())})"
            )
        return found[0]

    @classmethod
    def load_metadata(cls, path) -> dict:
        """The metadata of a run saved as tables (its directory or its ``timeseries``
        table) without reading its rows: outcome, end time ``t_end`` [s], statistics,
        provenance (a streamed run's: ``provenance["stream"]``)."""
        from ..io.tables import TableError, read_metadata

        table = cls._timeseries_table(Path(path))
        meta = read_metadata(table)["metadata"]
        if meta.get("format") != TABLES_FORMAT:
            raise TableError(f"{table}: not the time series of a scoutsim run")
        return meta

    @classmethod
    def _load_tables(cls, path: Path, t_range=None) -> Self:
        from ..io.tables import SUFFIXES, TableError, read_table

        path = cls._timeseries_table(path)
        series, meta = read_table(path, t_range=t_range)
        if meta.get("format") != TABLES_FORMAT:
            raise TableError(f"{path}: not the time series of a scoutsim run")
        suffix = next(x for x in SUFFIXES.values() if path.name.lower().endswith(x))
        d = path.parent
        n = len(series["t"])
        state = (
            np.column_stack([series[name] for name in L.STATE_NAMES]) if n else np.zeros((0, L.NS))
        )
        aux = np.zeros((n, L.NAUX))
        for leg in range(2):
            for j, name in enumerate(L.AUX_LEG_NAMES):
                aux[:, leg * L.NAUX_LEG + j] = series[f"{name}_{L.LEG_NAMES[leg]}"]
        aux[:, L.A_VBATT] = series["battery_voltage"]
        aux[:, L.A_ENERGY] = series["energy"]
        aux[:, L.A_KKT_OK] = series["dynamics_solved"]
        modes = np.zeros((n, L.NRM), dtype=np.int8)
        for leg in range(2):
            for base, what in (
                (L.RM_LEG_STATE_B, "leg_state"),
                (L.RM_CONTACT_B, "contact_mode"),
                (L.RM_MOTOR_B, "motor_joint_mode"),
            ):
                modes[:, base + leg] = series[f"{what}_{L.LEG_NAMES[leg]}"]
        energy_series = None
        if ENERGY_COLUMNS[0] in series:
            energy_series = (
                np.column_stack([series[c] for c in ENERGY_COLUMNS]) if n else np.zeros((0, L.NEN))
            )
        ev, _ = read_table(d / f"events{suffix}", t_range=t_range)
        m = len(ev["t"])
        events = np.zeros((m, L.NEVREC))
        for col, name in (
            (L.EVR_T, "t"),
            (L.EVR_KIND, "kind"),
            (L.EVR_LEG, "leg"),
            (L.EVR_V1, "v1"),
            (L.EVR_V2, "v2"),
            (L.EVR_V3, "v3"),
            (L.EVR_E_BEFORE, "energy_before"),
            (L.EVR_E_AFTER, "energy_after"),
            (L.EVR_VIOLATIONS, "violations"),
        ):
            events[:, col] = ev[name]
        event_states = None
        if meta.get("event_states"):
            event_states = np.zeros((m, 2, L.NS))
            for when, slot in (("before", L.EVS_BEFORE), ("after", L.EVS_AFTER)):
                for i, name in enumerate(L.STATE_NAMES):
                    event_states[:, slot, i] = ev[f"{name}_{when}"]
        steps = None
        if (d / f"steps{suffix}").exists():
            st, _ = read_table(d / f"steps{suffix}", t_range=t_range)
            steps = np.zeros((len(st["t"]), L.NSTEPREC))
            steps[:, L.STP_T] = st["t"]
            for i, name in enumerate(L.STATE_NAMES):
                steps[:, L.STP_STATE + i] = st[name]
            for leg, name in enumerate(L.LEG_NAMES):
                steps[:, L.STP_CONTACT_B + leg] = st[f"contact_mode_{name}"]
                steps[:, L.STP_MOTOR_B + leg] = st[f"motor_joint_mode_{name}"]
        return cls(
            t=series["t"],
            state=state,
            aux=aux,
            modes=modes,
            events=events,
            outcome=meta["outcome"],
            t_end=meta["t_end"],
            stats=meta["stats"],
            provenance=meta["provenance"],
            event_states=event_states,
            steps=steps,
            energy_flows=meta.get("energy_flows"),
            energy_series=energy_series,
        )
