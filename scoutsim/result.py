"""The result of a simulation: time series, events, outcome, statistics and provenance.

Arrays are sampled at the controller's sample times (1 kHz by default; a run that falls
or fails ends with one extra off-grid sample at that moment). Events are located in
continuous time. Saved losslessly as a single ``.npz`` file (arrays bit-exact, metadata as
JSON).
"""

from __future__ import annotations

import dataclasses
import json
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .failure import diagnose_failure
from .model import layout as L
from .state import HybridState

_LEGS = {"back": 0, "front": 1, 0: 0, 1: 1}


#: Unit of each :meth:`SimulationResult.columns` name, by prefix (first match wins):
#: (prefix, SI unit, exact match). Mode columns and the ``dynamics_solved`` flag (1: the
#: constrained dynamics solved, 0: singular) are codes without a unit.
COLUMN_UNITS = (
    ("t", "s", True), ("x", "m", True), ("y", "m", True), ("theta", "rad", True),
    ("phi_", "rad", False), ("alpha_", "rad", False), ("dx", "m/s", True),
    ("dy", "m/s", True), ("dtheta", "rad/s", True), ("dphi_", "rad/s", False),
    ("dalpha_", "rad/s", False), ("leg_length_", "m", False), ("ground_force_", "N", False),
    ("leg_axial_force_", "N", False), ("hip_torque_", "N m", False),
    ("motor_current_", "A", False), ("motor_speed_", "rad/s", False),
    ("belt_deflection_", "rad", False), ("stiction_holding_torque_", "N m", False),
    ("toe_x_", "m", False), ("toe_y_", "m", False), ("toe_velocity_x_", "m/s", False),
    ("strut_force_", "N", False), ("belt_torque_", "N m", False),
    ("battery_voltage", "V", True), ("energy", "J", True),
    ("cumulative_energy_", "J", False),
)

#: destinations of the energy that sum several flows of ``layout.EN_LEG_NAMES`` (per
#: virtual leg), for :meth:`SimulationResult.cumulative_energy` and
#: :meth:`SimulationResult.power`: the transmission's losses (the paper's constant
#: efficiency, signed, and the optional load-dependent losses), the motor-joint friction,
#: and every friction and damper of the mechanism (motor joint, belt damper, leg damper
#: and sliding joint, sliding toes)
ENERGY_GROUPS = {
    "transmission": ("conversion", "gear_loss"),
    "joint_friction": ("joint_viscous", "joint_coulomb"),
    "friction": ("joint_viscous", "joint_coulomb", "belt_damper", "leg_damper",
                 "leg_friction", "toe_slide"),
}
#: destinations without a leg: the battery's internal loss, and the battery's whole output
#: (the electrical energy into both legs' motors plus that loss)
ENERGY_WHOLE_ROBOT = ("battery_loss", "battery")


#: names of the columns of :attr:`SimulationResult.energy_series` in the tables
ENERGY_COLUMNS = tuple(f"cumulative_energy_{f}_{leg}" for leg in L.LEG_NAMES
                       for f in L.EN_LEG_NAMES) + ("cumulative_energy_battery_loss",)


#: ``format`` of the metadata of a run's tables (:meth:`SimulationResult.save_tables`)
TABLES_FORMAT = "scoutsim.run/1"


def column_unit(name: str) -> str | None:
    """Unit of a :meth:`SimulationResult.columns` name (None for mode codes and unknown
    names)."""
    for prefix, unit, exact in COLUMN_UNITS:
        if (name == prefix) if exact else name.startswith(prefix):
            return unit
    return None


def _leg(leg) -> int:
    try:
        return _LEGS[leg]
    except KeyError:
        raise ValueError(f"leg = {leg!r} is not allowed: must be 'back' or 'front'") from None


@dataclass
class SimulationResult:
    """Everything one run produced.

    Attributes
    ----------
    t : (n,) sample times [s].
    state : (n, 16) states [x, y, theta, phi_b, phi_f, alpha_b, alpha_f, their rates,
        l_b, l_f] (SI; see ``scoutsim.model.layout.STATE_NAMES``).
    aux : (n, NAUX) outputs: ground forces, torques, currents, motor speeds, belt
        deflection, battery voltage, energy (``layout.A_*``).
    modes : (n, 6) int8: controller leg states (back, front), plant contact modes (back,
        front), motor-joint stiction modes (back, front); columns ``layout.RM_*``.
    events : (m, NEVREC) [t, kind, leg, v1, v2, v3, energy before / after, violations]
        (``layout.EVR_*``, kinds ``layout.EK_*``).
    outcome : "completed", "fell", "numerical_failure", "interrupted", "controller_error"
        (a user controller raised or returned bad torques: ``scoutsim.ControllerError``) or,
        for a run streamed to a disk that refused its tables, "write_failed" (:attr:`failure`
        says why a run failed numerically).
    t_end : time the run reached [s].
    stats : integrator statistics and contact diagnostics.
    provenance : parameters, model variant, tolerances, initial state, package version.
    event_states : (m, 2, 16) the exact state of each event record just before its
        transition and after its modes settled (``[:, layout.EVS_BEFORE]``,
        ``[:, layout.EVS_AFTER]``; controller records: the state at their sample), or
        None for results saved before it was recorded.
    steps : (k, NSTEPREC) every integrator step (time, state, plant modes; ``layout.STP_*``)
        if the run recorded them (``simulate(record_steps=True)``), else None.
    energy_flows : the whole run's energies [J] by name if it accounted for them
        (``simulate(energy=True)``), else None: per leg (``_back``, ``_front``) every power
        flow of ``layout.EN_LEG_NAMES`` integrated over the run, ``battery_loss``, the
        touchdown ``impacts``' losses and the mechanical energy at the first sample and at
        the end (``mechanical_start``, ``mechanical_end``); :meth:`energy_balance` reads
        them.
    energy_series : (n, NEN) the energy of every power flow (layout ``EN_*``: per leg the
        flows of ``layout.EN_LEG_NAMES``, then the battery's loss) accumulated from the
        start of the run to each sample [J], if the run accounted for its energy, else
        None. Read it with :meth:`cumulative_energy` and :meth:`power`. A window of a run
        (:meth:`window`, a streamed run's kept end) keeps the values since the run's start.
    """

    t: np.ndarray
    state: np.ndarray
    aux: np.ndarray
    modes: np.ndarray
    events: np.ndarray
    outcome: str
    t_end: float
    stats: dict
    provenance: dict
    event_states: np.ndarray | None = None
    steps: np.ndarray | None = None
    energy_flows: dict | None = None
    energy_series: np.ndarray | None = None
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    # -- torso -----------------------------------------------------------------------
    @property
    def x(self):
        """Torso COM forward position [m]."""
        return self.state[:, L.IX]

    @property
    def height(self):
        """Torso COM height y [m]."""
        return self.state[:, L.IY]

    @property
    def pitch(self):
        """Torso pitch theta [rad], nose up positive."""
        return self.state[:, L.ITH]

    @property
    def forward_speed(self):
        """Torso COM forward velocity [m/s]."""
        return self.state[:, L.NQ + L.IX]

    @property
    def pitch_rate(self):
        """[rad/s]"""
        return self.state[:, L.NQ + L.ITH]

    @property
    def energy(self):
        """Total mechanical energy (kinetic + gravity + leg and belt springs) [J]."""
        return self.aux[:, L.A_ENERGY]

    @property
    def battery_voltage(self):
        """[V]"""
        return self.aux[:, L.A_VBATT]

    # -- legs ------------------------------------------------------------------------
    def leg_angle(self, leg):
        """Leg angle phi relative to the torso [rad] (toe ahead of hip positive)."""
        return self.state[:, L.IPHB + _leg(leg)]

    def leg_rate(self, leg):
        """[rad/s]"""
        return self.state[:, L.NQ + L.IPHB + _leg(leg)]

    def motor_angle(self, leg):
        """Driven-gear angle alpha relative to the torso [rad] (= phi outside Model II)."""
        return self.state[:, L.IALB + _leg(leg)]

    def leg_length(self, leg):
        """[m]"""
        return self.state[:, L.IL_B + _leg(leg)]

    def _aux(self, leg, slot):
        return self.aux[:, _leg(leg) * L.NAUX_LEG + slot]

    def ground_force(self, leg):
        """(tangential, normal) ground force on the virtual leg's toe [N]."""
        return self._aux(leg, L.A_GT), self._aux(leg, L.A_GN)

    def hip_torque_commanded(self, leg):
        """Commanded hip torque per physical leg [N m]."""
        return self._aux(leg, L.A_TAU_CMD)

    def hip_torque_applied(self, leg):
        """Actuator torque delivered per physical leg, N eta K_T i less any transmission
        losses (docs/model.md) [N m]."""
        return self._aux(leg, L.A_TAU_APP)

    def motor_current(self, leg):
        """[A] per motor"""
        return self._aux(leg, L.A_CURRENT)

    def motor_speed(self, leg):
        """Motor shaft speed relative to the torso [rad/s]."""
        return self._aux(leg, L.A_OMEGA_M)

    def belt_deflection(self, leg):
        """alpha - phi [rad] (Model II; zero otherwise)."""
        return self._aux(leg, L.A_BELT)

    def leg_axial_force(self, leg):
        """Leg spring/damper force, compression positive [N] (virtual leg)."""
        return self._aux(leg, L.A_FAX)

    def leg_state(self, leg):
        """Controller leg state per sample: 0 flight, 1 stance-retraction, 2 stance-brake."""
        return self.modes[:, L.RM_LEG_STATE_B + _leg(leg)].astype(int)

    def contact_mode(self, leg):
        """Plant contact mode per sample: 0 flight, 1 stick, 2 slide, 3 strut."""
        return self.modes[:, L.RM_CONTACT_B + _leg(leg)].astype(int)

    def hybrid_state(self, k: int):
        """The complete hybrid state at recorded sample ``k`` (continuous state, plant and
        controller modes, toe anchors) as a :class:`~scoutsim.state.HybridState`:
        ``simulate(..., initial_state=result.hybrid_state(k))`` continues this run from
        t[k] (its time restarts at 0), to the integration tolerance: the integrator's own
        state is not carried (see :class:`~scoutsim.state.HybridState`)."""
        n = len(self.t)
        if not (isinstance(k, (int, np.integer)) and -n <= k < n):
            raise ValueError(f"k = {k!r} is not allowed: must be an integer sample index in "
                             f"[{-n}, {n - 1}]")
        m = self.modes[k].astype(int)
        aux = self.aux[k]
        return HybridState(
            state=self.state[k], leg_states=(m[L.RM_LEG_STATE_B], m[L.RM_LEG_STATE_F]),
            contact_modes=(m[L.RM_CONTACT_B], m[L.RM_CONTACT_F]),
            motor_modes=(m[L.RM_MOTOR_B], m[L.RM_MOTOR_F]),
            slide_directions=tuple(1 if aux[leg * L.NAUX_LEG + L.A_SLIP_V] >= 0.0 else -1
                                   for leg in range(2)),
            toe_anchors=tuple(float(aux[leg * L.NAUX_LEG + L.A_TOE_X]) for leg in range(2)))

    # -- energy ----------------------------------------------------------------------
    def _energy_columns(self, name: str, leg) -> list[int]:
        """Columns of :attr:`energy_series` that make up destination ``name`` of ``leg``
        (None: both legs)."""
        if self.energy_series is None:
            raise ValueError("this run did not account for its energy: run it with "
                             "simulate(..., energy=True) (scoutsim run does by default)")
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
                    f"{list(L.EN_LEG_NAMES) + list(ENERGY_GROUPS) + list(ENERGY_WHOLE_ROBOT)}")
        legs = (0, 1) if leg is None else (_leg(leg),)
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
        return self.energy_series[:, self._energy_columns(name, leg)].sum(axis=1)

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
            raise ValueError(f"electrical_power needs a run of Model I or II with its robot "
                             f"in the provenance (this one: model {model!r})")
        legs = (0, 1) if leg is None else (_leg(leg),)
        p = np.zeros(len(self.t))
        for lg in legs:
            i = self.motor_current(lg)
            w = self.motor_speed(lg)
            p += robot["legs_per_virtual_leg"] * i * (robot["armature_resistance"] * i
                                                      + robot["speed_constant"] * w)
        return p

    # -- events ----------------------------------------------------------------------
    def event_times(self, kind: str, leg=None) -> np.ndarray:
        """Times [s] of events of a kind ("touchdown", "liftoff", ...), optionally of one leg."""
        codes = {v: k for k, v in L.EVENT_KIND_NAMES.items()}
        if kind not in codes:
            raise ValueError(f"kind = {kind!r} is not allowed: must be one of {sorted(codes)}")
        m = self.events[:, 1] == codes[kind]
        if leg is not None:
            m &= self.events[:, 2] == _leg(leg)
        return self.events[m, 0]

    def event_table(self) -> list[dict]:
        """Events as a list of dicts (time, kind, leg, values)."""
        out = []
        for row in self.events:
            leg = int(row[2])
            out.append({"t": float(row[0]), "kind": L.EVENT_KIND_NAMES.get(int(row[1]), "?"),
                        "leg": L.LEG_NAMES[leg] if leg >= 0 else None,
                        "values": [float(v) for v in row[3:]]})
        return out

    def impacts(self):
        """Touchdown impacts: (t, leg, normal impulse [N s], tangential impulse [N s],
        kinetic energy lost [J]) as an array."""
        m = self.events[:, 1] == L.EK_TOUCHDOWN
        return self.events[m][:, [0, 2, 3, 4, 5]]

    # -- analysis (computed on demand) -----------------------------------------------------
    def gait(self, **kwargs):
        """Strides and gait metrics (:func:`scoutsim.analysis.gait.gait_metrics`)."""
        from .analysis.gait import gait_metrics
        key = ("gait", tuple(sorted(kwargs.items())))
        if key not in self._cache:
            self._cache[key] = gait_metrics(self, **kwargs)
        return self._cache[key]

    @property
    def strides(self):
        """Per-stride metrics (list of dicts) of all strides."""
        return self.gait().strides

    def summary(self) -> dict:
        """The run summary (outcome, steady-state gait metrics and what the gait costs:
        ``electrical_energy_j`` [J] over the run, ``cost_of_transport`` [-] over the steady
        strides, ...; None without the energy accounting,
        :meth:`~scoutsim.analysis.gait.GaitMetrics.energy_summary`), JSON-safe; a run that
        failed numerically also has ``"failure"``: :attr:`failure` as a dict (kind, time,
        what happened, parameters far from the Scout II defaults, advice); a run started
        standing (``simulate(initial_state="standing")``) also has ``"startup_duration_s"``:
        the time [s] from t = 0 to the start-up's hand-over to the bounding controller
        (None if it timed out)."""
        out = self.gait().summary(self)
        startup = (self.provenance or {}).get("startup")
        if startup is not None:
            # a start from standing: t = 0 to the hand-over to the bounding controller
            out["startup_duration_s"] = startup.get("handover_s")
        if self.failure is not None:
            out["failure"] = self.failure.to_dict()
        return out

    @property
    def failure(self):
        """Why the run failed numerically (:class:`~scoutsim.failure.FailureDiagnosis`:
        ``kind``, ``t``, ``what``, ``parameters`` far from the Scout II defaults,
        ``message()``), or None if it did not (outcome other than "numerical_failure")."""
        key = ("failure", self.outcome)
        if key not in self._cache:
            self._cache[key] = diagnose_failure(self)
        return self._cache[key]

    def window(self, t0: float, t1: float) -> "SimulationResult":
        """The samples (and their cumulative energies), events and steps with
        t0 <= t <= t1 [s], as views (all are in time order); outcome, end time, statistics,
        provenance and the run's energy totals stay the whole run's."""
        def rows(t):
            return slice(int(np.searchsorted(t, t0, side="left")),
                         int(np.searchsorted(t, t1, side="right")))
        k, j = rows(self.t), rows(self.events[:, L.EVR_T])
        return dataclasses.replace(
            self, t=self.t[k], state=self.state[k], aux=self.aux[k], modes=self.modes[k],
            events=self.events[j],
            event_states=None if self.event_states is None else self.event_states[j],
            steps=None if self.steps is None else self.steps[rows(self.steps[:, L.STP_T])],
            energy_series=None if self.energy_series is None else self.energy_series[k],
            _cache={})

    def energy_balance(self):
        """The run's work-energy balance (:class:`~scoutsim.analysis.energy.EnergyBalance`:
        every term [J], the input, the residual); needs a run made with
        ``simulate(energy=True)``."""
        from .analysis.energy import energy_balance
        return energy_balance(self)

    @property
    def fell(self) -> bool:
        return self.outcome == "fell"

    # -- persistence -----------------------------------------------------------------
    def save(self, path) -> Path:
        """Save losslessly to ``path`` (.npz)."""
        path = Path(path)
        meta = {"outcome": self.outcome, "t_end": self.t_end, "stats": self.stats,
                "provenance": self.provenance, "format": "scoutsim.result/1",
                "energy_flows": self.energy_flows}
        extra = {name: a for name, a in (("event_states", self.event_states),
                                         ("steps", self.steps),
                                         ("energy_series", self.energy_series))
                 if a is not None}
        np.savez_compressed(path, t=self.t, state=self.state, aux=self.aux, modes=self.modes,
                            events=self.events, meta=np.array(json.dumps(meta, allow_nan=True)),
                            **extra)
        return path if path.suffix == ".npz" else path.with_suffix(path.suffix + ".npz")

    @classmethod
    def load(cls, path, *, t_range: tuple[float, float] | None = None) -> "SimulationResult":
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
            what = "it is empty (0 bytes)" if size == 0 else \
                f"it is cut off or damaged ({size} bytes: {type(exc).__name__}: {exc})"
            raise ValueError(f"{path}: not a readable scoutsim result: {what}") from None

    @classmethod
    def _load_npz(cls, path: Path) -> "SimulationResult":
        with np.load(path, allow_pickle=False) as z:
            meta = json.loads(str(z["meta"]))
            if meta.get("format") != "scoutsim.result/1":
                raise ValueError(f"{path}: not a scoutsim result file")
            events = z["events"]
            if events.shape[1] < L.NEVREC:
                # saved before the transition audit columns existed: they are unknown
                pad = np.full((events.shape[0], L.NEVREC - events.shape[1]), np.nan)
                events = np.hstack([events, pad])
            return cls(t=z["t"], state=z["state"], aux=z["aux"], modes=z["modes"],
                       events=events, outcome=meta["outcome"], t_end=meta["t_end"],
                       stats=meta["stats"], provenance=meta["provenance"],
                       event_states=z["event_states"] if "event_states" in z.files else None,
                       steps=z["steps"] if "steps" in z.files else None,
                       energy_flows=meta.get("energy_flows"),
                       energy_series=(z["energy_series"] if "energy_series" in z.files
                                      else None))

    # -- tables (Parquet / compressed CSV: scoutsim.tables) ---------------------------
    def event_columns(self) -> dict:
        """The events as named columns: time [s], kind (code and name), leg (0 back, 1
        front, -1 none), the kind's values v1-v3 (``layout`` "event record"), the
        transition's energies before / after [J] and violated invariants (bit mask), and,
        where recorded, the state just before (``<name>_before``) and after
        (``<name>_after``) the transition (``STATE_NAMES``, SI)."""
        ev = self.events
        kinds = ev[:, L.EVR_KIND].astype(np.int8)
        cols = {"t": ev[:, L.EVR_T], "kind": kinds,
                "kind_name": np.array([L.EVENT_KIND_NAMES.get(int(k), "?") for k in kinds],
                                      dtype=str),
                "leg": ev[:, L.EVR_LEG].astype(np.int8),
                "v1": ev[:, L.EVR_V1], "v2": ev[:, L.EVR_V2], "v3": ev[:, L.EVR_V3],
                "energy_before": ev[:, L.EVR_E_BEFORE], "energy_after": ev[:, L.EVR_E_AFTER],
                "violations": ev[:, L.EVR_VIOLATIONS].astype(np.int32)}
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

    def save_tables(self, directory, *, fmt: str | None = None) -> list[Path]:
        """Write the run as tables into ``directory``: ``timeseries`` (every sample, every
        :meth:`columns` name, with the outcome, statistics and provenance as metadata),
        ``events`` (:meth:`event_columns`) and, if recorded, ``steps``
        (:meth:`step_columns`); Parquet if pyarrow is installed, else gzip-compressed CSV
        (``fmt``: "parquet" or "csv"). :meth:`load` reads them back bit for bit. Returns
        the paths written."""
        from .tables import default_format, write_table
        fmt = fmt or default_format()
        d = Path(directory)
        d.mkdir(parents=True, exist_ok=True)
        paths = []
        for name, (cols, units) in self.tables().items():
            meta = self.series_metadata() if name == "timeseries" else {"format": TABLES_FORMAT}
            paths.append(write_table(d / name, cols, units=units, metadata=meta, fmt=fmt))
        return paths

    def tables(self) -> dict:
        """The run's tables as ``{name: (columns, units)}``: ``timeseries``, ``events`` and,
        if recorded, ``steps`` (what :meth:`save_tables` writes, and a streamed run writes
        piece by piece: :mod:`scoutsim.streaming`)."""
        series = self.columns()
        for n in series:
            if column_unit(n) is None:
                series[n] = series[n].astype(np.int8)
        out = {"timeseries": (series, {n: column_unit(n) for n in series})}
        ev = self.event_columns()
        ev_units = {"t": "s", "energy_before": "J", "energy_after": "J"}
        for n in ev:
            for when in ("_before", "_after"):
                if n.endswith(when) and not n.startswith("energy"):
                    ev_units[n] = column_unit(n[:-len(when)])
        out["events"] = (ev, ev_units)
        st = self.step_columns()
        if st is not None:
            out["steps"] = (st, {n: column_unit(n) for n in st})
        return out

    def series_metadata(self) -> dict:
        """The metadata of the ``timeseries`` table: outcome, end time, statistics,
        provenance."""
        return {"format": TABLES_FORMAT, "outcome": self.outcome, "t_end": self.t_end,
                "stats": self.stats, "provenance": self.provenance,
                "event_states": self.event_states is not None,
                "energy_flows": self.energy_flows}

    @classmethod
    def _timeseries_table(cls, path: Path) -> Path:
        """The ``timeseries`` table of a saved run (its directory, or the table itself),
        after checking that the run's directory was written completely."""
        from .run_directory import check_run_directory
        from .tables import SUFFIXES, TableError
        check_run_directory(path if path.is_dir() else path.parent)
        if not path.is_dir():
            return path
        found = [path / f"timeseries{x}" for x in SUFFIXES.values()
                 if (path / f"timeseries{x}").exists()]
        if not found:
            raise TableError(f"{path}: no timeseries table "
                             f"({', '.join('timeseries' + x for x in SUFFIXES.values())})")
        return found[0]

    @classmethod
    def load_metadata(cls, path) -> dict:
        """The metadata of a run saved as tables (its directory or its ``timeseries``
        table) without reading its rows: outcome, end time ``t_end`` [s], statistics,
        provenance (a streamed run's: ``provenance["stream"]``)."""
        from .tables import TableError, read_metadata
        table = cls._timeseries_table(Path(path))
        meta = read_metadata(table)["metadata"]
        if meta.get("format") != TABLES_FORMAT:
            raise TableError(f"{table}: not the time series of a scoutsim run")
        return meta

    @classmethod
    def _load_tables(cls, path: Path, t_range=None) -> "SimulationResult":
        from .tables import SUFFIXES, TableError, read_table
        path = cls._timeseries_table(path)
        series, meta = read_table(path, t_range=t_range)
        if meta.get("format") != TABLES_FORMAT:
            raise TableError(f"{path}: not the time series of a scoutsim run")
        suffix = next(x for x in SUFFIXES.values() if path.name.lower().endswith(x))
        d = path.parent
        n = len(series["t"])
        state = np.column_stack([series[name] for name in L.STATE_NAMES]) if n else \
            np.zeros((0, L.NS))
        aux = np.zeros((n, L.NAUX))
        for leg in range(2):
            for j, name in enumerate(L.AUX_LEG_NAMES):
                aux[:, leg * L.NAUX_LEG + j] = series[f"{name}_{L.LEG_NAMES[leg]}"]
        aux[:, L.A_VBATT] = series["battery_voltage"]
        aux[:, L.A_ENERGY] = series["energy"]
        aux[:, L.A_KKT_OK] = series["dynamics_solved"]
        modes = np.zeros((n, L.NRM), dtype=np.int8)
        for leg in range(2):
            for base, what in ((L.RM_LEG_STATE_B, "leg_state"), (L.RM_CONTACT_B, "contact_mode"),
                               (L.RM_MOTOR_B, "motor_joint_mode")):
                modes[:, base + leg] = series[f"{what}_{L.LEG_NAMES[leg]}"]
        energy_series = None
        if ENERGY_COLUMNS[0] in series:
            energy_series = (np.column_stack([series[c] for c in ENERGY_COLUMNS]) if n else
                             np.zeros((0, L.NEN)))
        ev, _ = read_table(d / f"events{suffix}", t_range=t_range)
        m = len(ev["t"])
        events = np.zeros((m, L.NEVREC))
        for col, name in ((L.EVR_T, "t"), (L.EVR_KIND, "kind"), (L.EVR_LEG, "leg"),
                          (L.EVR_V1, "v1"), (L.EVR_V2, "v2"), (L.EVR_V3, "v3"),
                          (L.EVR_E_BEFORE, "energy_before"), (L.EVR_E_AFTER, "energy_after"),
                          (L.EVR_VIOLATIONS, "violations")):
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
        return cls(t=series["t"], state=state, aux=aux, modes=modes, events=events,
                   outcome=meta["outcome"], t_end=meta["t_end"], stats=meta["stats"],
                   provenance=meta["provenance"], event_states=event_states, steps=steps,
                   energy_flows=meta.get("energy_flows"), energy_series=energy_series)

    def to_dataframe(self):
        """All time series as a :class:`pandas.DataFrame` indexed by time ``t`` [s], one
        column per :meth:`columns` name (SI; mode columns as integer codes, see
        ``layout.LEG_STATE_NAMES`` / ``CONTACT_NAMES``); ``df.attrs["units"]`` maps each
        column to its unit. Needs pandas (``pip install pandas``)."""
        try:
            import pandas as pd
        except ImportError as exc:
            raise ImportError("SimulationResult.to_dataframe needs pandas: pip install pandas "
                              "(or pip install 'scoutsim[dataframe]')") from exc
        cols = self.columns()
        for n in cols:
            if column_unit(n) is None:
                cols[n] = cols[n].astype(np.int8)
        df = pd.DataFrame(cols).set_index("t")
        df.attrs["units"] = {n: column_unit(n) for n in cols}
        return df

    def plot(self, path=None, t_range=None):
        """Time histories of the run (pitch, height, leg angles and states, hip torques) as a
        Matplotlib figure, saved to ``path`` if given: a convenience for
        :func:`scoutsim.presentation.plots.plot_run`."""
        from .presentation.plots import plot_run
        return plot_run(self, path, t_range)

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
            for base, what in ((L.RM_LEG_STATE_B, "leg_state"), (L.RM_CONTACT_B, "contact_mode"),
                               (L.RM_MOTOR_B, "motor_joint_mode")):
                cols[f"{what}_{L.LEG_NAMES[leg]}"] = self.modes[:, base + leg].astype(float)
        if self.energy_series is not None:
            for j, name in enumerate(ENERGY_COLUMNS):
                cols[name] = self.energy_series[:, j]
        return cols
