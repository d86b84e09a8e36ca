"""The stride map of the controlled robot, for any controller whose state scoutsim can read
and set: its Poincaré section and one stride of the sampled closed loop.

**Section**: the first control sample after the plant's back-leg lift-off (an event every
bounding run has, located in continuous time by the integrator), taken before the
controller's command at that sample. The section coordinates ``z`` (:meth:`StrideMap.z_names`,
SI: m, rad, m/s, rad/s, N m) are the complete hybrid state there
(:class:`~scoutsim.state.HybridState`): the state without x (:data:`CONTROLLED_Z_NAMES`,
with the pinned toes' anchors relative to x), the controller's own state (a compiled
controller's state array, a Python controller's ``get_state()``) and, for a controller
other than the built-in Table I law, the hip torques held from the sample before (what its
motor-current and IMU readings see). The discrete modes (leg states, toe contact, motor
joints, slide directions) must recur.

The closed loop is a sampled-data system, so the map is smooth only piecewise: it jumps
where a perturbation moves the lift-off, or one of the controller's own switches, across a
sample boundary. :class:`Crossing` says how far the lift-off lies from the nearer boundary
(``margin_s``) and records the controller's leg states sample by sample, so that a
Jacobian by differences can tell a jump from a derivative.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..control.dispatch import check_state_access, plan_controller
from ..control.protocol import ControllerError, controller_name
from ..names import ContactMode, Leg
from ..parameters import DEFAULT_FRICTION_COEFFICIENT, RobotParameters
from ..simulation.engine import start_engine
from ..simulation.integrator import IntegratorSettings
from ..simulation.sensitivities import EXTENDED_ROWS
from ..state import HybridState, state_index, state_vector
from .poincare import MapError

__all__ = [
    "CONTROLLED_Z_NAMES",
    "Crossing",
    "StrideMap",
    "controlled_stride_map",
    "discrete_modes",
    "mode_signature",
    "section_state",
]

#: names of the plant's section coordinates (SI), the first ones of every stride map's z
CONTROLLED_Z_NAMES = (
    "y",
    "theta",
    "phi_back",
    "phi_front",
    "alpha_back",
    "alpha_front",
    "dx",
    "dy",
    "dtheta",
    "dphi_back",
    "dphi_front",
    "dalpha_back",
    "dalpha_front",
    "leg_length_back",
    "leg_length_front",
    "anchor_back_rel",
    "anchor_front_rel",
)
#: the components of z taken from the state vector (all but x), in z's order
_STATE_Z_NAMES = CONTROLLED_Z_NAMES[:-2]
#: the contact modes in which a toe is pinned at its anchor
_PINNED = (ContactMode.STICK, ContactMode.STRUT)
#: the event that defines the section: the back leg's lift-off as the plant has it (every
#: run has it) or as the built-in Table I law detects it (its own event, at a sample)
SECTION_EVENTS = {"plant": ("liftoff", Leg.BACK), "controller": ("controller_liftoff", Leg.BACK)}
#: how the sections are named in outputs
SECTION_LABELS = {
    "plant": "the first control sample after the back leg's lift-off (a plant event)",
    "controller": "the control sample after the Table I controller detects back-leg lift-off",
}


def mode_signature(hs: HybridState) -> dict:
    """The discrete part of a HybridState that must recur on a periodic orbit: its modes,
    with the slide direction of a toe that is not sliding (which means nothing) left out."""
    d = discrete_modes(hs)
    d["slide_directions"] = tuple(
        v if c == ContactMode.SLIDE else 0 for v, c in zip(hs.slide_directions, hs.contact_modes)
    )
    return d


def discrete_modes(hs: HybridState) -> dict:
    """The discrete part of a HybridState (its modes), as HybridState takes them."""
    return dict(
        leg_states=hs.leg_states,
        contact_modes=hs.contact_modes,
        motor_modes=hs.motor_modes,
        slide_directions=hs.slide_directions,
    )


@dataclass
class Crossing:
    """Where a run from a section state next crosses the section.

    start : the start (a HybridState) as the run took it, its dependent coordinates
        projected (None after a settling run or from the default start).
    state : the HybridState at the section sample.
    period_s : time from the start to that sample [s] (a whole number of control periods).
    samples : that number of control periods.
    event_s : time of the plant's last back-leg lift-off before it, from the start [s].
    margin_s : distance of that lift-off from the nearer sample boundary [s]: a
        perturbation that moves it by more moves it to another sample.
    leg_states : (samples + 1, 2) the controller's leg states at every sample of the
        stride: where the controller switched.
    plant_events : the plant's events of the stride, (kind, leg) in order: the sequence of
        contact and joint modes it went through.
    jacobian : with ``exact``, dz'/dz: the derivative of the section coordinates of
        ``state`` with respect to those of ``start``, carried with the run
        (:mod:`scoutsim._core.numerics.tangent`); else None.
    smoothness : with ``exact``, what the derivatives met: ``nonsmooth`` (resets where a
        perturbed copy ended in other modes than the run: the map is not differentiable
        there), ``transversality`` (the smallest |n.f| / (|n| |f|) of a located event),
        ``events`` (events differentiated); else None.
    """

    start: HybridState | None
    state: HybridState
    period_s: float
    samples: int
    event_s: float
    margin_s: float
    leg_states: np.ndarray
    plant_events: tuple = ()
    jacobian: np.ndarray | None = None
    smoothness: dict | None = None


class StrideMap:
    """The stride map of one robot, model, controller, floor and integrator.

    ``controller``: anything :func:`scoutsim.simulate` accepts whose own state scoutsim can
    read and set (the built-in Table I law, a
    :class:`~scoutsim.control.compiled.CompiledController`, a Python controller with
    ``get_state()`` / ``set_state(values)``, :mod:`scoutsim.control.protocol`); a fresh
    engine runs every stride. ``max_period``: the longest stride looked for [s].
    ``section``: "plant" (the first control sample after the back leg's lift-off, for any
    controller) or "controller" (the sample after the built-in Table I law detects it;
    the default for that law, whose map is then smooth wherever its own switches stay on
    their samples, as with its Model I orbit, whose lift-off crosses sample boundaries
    on the way to it).
    """

    def __init__(
        self,
        *,
        model: str = "II",
        friction_coefficient: float = DEFAULT_FRICTION_COEFFICIENT,
        robot=None,
        controller=None,
        integrator: IntegratorSettings | None = None,
        max_period: float = 0.6,
        section: str | None = None,
    ):
        self.model = model
        self.friction_coefficient = friction_coefficient
        self.robot = robot
        self.controller = controller
        self.integrator = integrator
        self.max_period = float(max_period)
        # samples of the last run of so many strides: the next goes there in one call
        self._expected: dict[int, int] = {}
        plan = plan_controller(controller, model, robot if robot is not None else RobotParameters())
        check_state_access(plan)  # strides restart from states that include it
        #: the controller is the built-in Table I law (no held torques in z)
        self.builtin = plan.kind == "builtin"
        #: the compiled loop runs the controller (the built-in law or a CompiledController):
        #: the map's Jacobian can be carried with the run
        self.compiled = plan.kind in ("builtin", "compiled")
        #: "plant" or "controller" (the built-in law's lift-off detection; its default)
        self.section = section or ("controller" if self.builtin else "plant")
        if self.section not in SECTION_LABELS or (
            self.section == "controller" and not self.builtin
        ):
            allowed = sorted(SECTION_LABELS) if self.builtin else ["plant"]
            raise ValueError(
                f"section = {section!r} is not allowed for this controller: must be one "
                f"of {allowed} (only the built-in Table I law logs its lift-off detection)"
            )
        self.section_label = SECTION_LABELS[self.section]

    def engine(self, start, duration: float):
        """An engine of this map's run from ``start`` (None: the model's default start), at
        most ``duration`` [s] long."""
        return start_engine(
            start,
            duration,
            robot=self.robot,
            model=self.model,
            controller=self.controller,
            friction_coefficient=self.friction_coefficient,
            integrator=self.integrator,
        )

    def crossing(
        self, start, *, settle_s: float = 0.0, strides: int = 1, exact: bool = False
    ) -> Crossing:
        """Run from ``start`` (a HybridState at a section sample, or None: the default
        start) for ``settle_s`` [s], then to the ``strides``-th section sample. MapError if
        the robot falls, the controller stops the run (non-finite torques, a compiled
        controller's status) or a stride takes longer than ``max_period``;
        ControllerError if a Python controller raises (its exception the cause).
        ``exact``: also the map's Jacobian dz'/dz, carried with the run (``start`` a
        HybridState, no settling; a controller the compiled loop runs: the built-in law
        or a CompiledController)."""
        if exact and (not isinstance(start, HybridState) or settle_s != 0.0):
            raise ValueError("exact: the Jacobian is of the map from a HybridState start")
        if exact and not self.compiled:
            raise ValueError(
                "exact: the Jacobian is carried through the compiled loop's controller (the "
                "built-in Table I law or a CompiledController); a Python controller's "
                "stride map is differentiated by differences (jacobian='fd')"
            )
        guess = self._expected.get(strides) if settle_s == 0.0 else None
        c = self._cross(start, settle_s, guess, strides, exact)
        if c is None:  # the lift-off came before the expected stride length: again
            c = self._cross(start, settle_s, None, strides, exact)
        assert c is not None, "a run sample by sample finds the crossing or raises"
        if settle_s == 0.0:
            self._expected[strides] = c.samples
        return c

    def _cross(
        self, start, settle_s: float, guess: int | None, strides: int, exact: bool = False
    ) -> Crossing | None:
        eng = self.engine(start, settle_s + strides * self.max_period)
        if exact:
            eng.carry_sensitivities(self._seed(start, eng.sensitivities.shape[0]))
        dt = float(eng.dt)
        k0 = int(round(settle_s / dt))
        if k0 > 0:
            eng.advance(k0)
            self._check(eng, "settling")
        nev0 = eng.nev
        t0 = k0 * dt
        k_end = k0 + int(round(strides * self.max_period / dt))
        # one call to just before the expected crossing (the last stride's length), then
        # sample by sample
        if guess is not None and guess > 3:
            eng.advance(k0 + guess - 2)
            self._check(eng, "a stride")
            if len(self._lifts(eng, nev0, t0)) >= strides:
                return None
        while True:
            te = self._lifts(eng, nev0, t0)
            if len(te) >= strides:
                break
            if eng.k >= k_end:
                raise MapError(
                    f"{len(te)} of {strides} back-leg lift-offs within "
                    f"{strides * self.max_period:g} s (the run was at t = "
                    f"{eng.k * dt - t0:.3f} s)"
                )
            eng.advance(eng.k + 1)
            self._check(eng, "a stride")
        n = eng.k - k0
        t_sec = n * dt
        # the plant's last back-leg lift-off before the section: its distance from a sample
        # boundary
        kind, leg = SECTION_EVENTS["plant"]
        tp = eng.event_times(kind, int(leg), since=nev0)
        t_ev = float(tp[-1]) - t0 if len(tp) else math.nan
        phase = (t_ev / dt) % 1.0
        first = eng.recorded_state(k0)
        return Crossing(
            start=(
                replace(start, state=first) if isinstance(start, HybridState) and k0 == 0 else None
            ),
            state=eng.hybrid_state(),
            period_s=t_sec,
            samples=n,
            event_s=t_ev,
            margin_s=dt * min(phase, 1.0 - phase),
            leg_states=eng.leg_state_record()[k0:],
            plant_events=eng.plant_events(nev0),
            jacobian=(self._end_map(eng) @ eng.sensitivities) if exact else None,
            smoothness=eng.smoothness() if exact else None,
        )

    # -- the Jacobian carried with the run ---------------------------------------------------
    def _seed(self, hs: HybridState, nx: int) -> np.ndarray:
        """dx/dz (nx rows) at the start :meth:`hs_of` makes: x is the run's extended state
        (rows :data:`~scoutsim.simulation.sensitivities.EXTENDED_ROWS`), its x coordinate 0, its
        anchors, controller state and (but for the built-in law) held torques those of z."""
        return self._coordinates(hs, nx).T

    def _end_map(self, eng) -> np.ndarray:
        """dz/dx at the engine's state now (:meth:`z_of` of its hybrid state): the anchors
        of pinned legs relative to x."""
        hs = eng.hybrid_state()
        out = self._coordinates(hs, eng.sensitivities.shape[0])
        nb = len(CONTROLLED_Z_NAMES)
        for leg in Leg:
            if hs.contact_modes[leg] in _PINNED:
                out[nb - 2 + leg, EXTENDED_ROWS["state"] + state_index("x")] = -1.0
            else:
                out[nb - 2 + leg, :] = 0.0
        return out

    def _coordinates(self, hs: HybridState, nx: int) -> np.ndarray:
        """The 0/1 matrix that picks each section coordinate of ``hs`` out of the extended
        state (nz x nx)."""
        nb = len(CONTROLLED_Z_NAMES)
        nc = len(hs.controller_state)
        rows = EXTENDED_ROWS
        out = np.zeros((len(self.z_of(hs)), nx))
        for i, name in enumerate(_STATE_Z_NAMES):
            out[i, rows["state"] + state_index(name)] = 1.0
        for leg in Leg:
            out[nb - 2 + leg, rows["anchors"] + leg] = 1.0
        for i in range(nc):
            out[nb + i, rows["controller_state"] + i] = 1.0
        if not self.builtin:
            for leg in Leg:
                out[nb + nc + leg, rows["commands"] + leg] = 1.0
        return out

    def _lifts(self, eng, nev0: int, t0: float) -> np.ndarray:
        kind, leg = SECTION_EVENTS[self.section]
        te = eng.event_times(kind, int(leg), since=nev0)
        return te[te > t0 + 1e-9] if self.section == "controller" else te[te > t0]

    @staticmethod
    def _check(eng, what: str) -> None:
        """MapError if the run of ``eng`` has stopped (the robot fell, the integration
        failed, the controller stopped it: no stride, a fact about the closed loop).
        A Python controller's own exception (a bug in its code, which a restart from a
        section state can reach where a run from the start does not) is raised as
        :class:`~scoutsim.control.protocol.ControllerError` with that exception as its
        cause, and a Ctrl-C that reached it as KeyboardInterrupt: neither says anything
        about the orbit."""
        bridge = eng.bridge
        if bridge is not None and bridge.interrupted:
            raise KeyboardInterrupt
        if eng.stopped and bridge is not None and bridge.failure is not None:
            sample, _, exc = bridge.failure
            if exc is not None:
                dt = float(eng.dt)
                raise ControllerError(
                    f"controller {controller_name(bridge.controller)}.command(t = "
                    f"{sample * dt:.10g} s, sensors) raised {type(exc).__name__}: {exc}; "
                    f"the stride map's run ({what}, t from its start at a section state) "
                    "stopped at that sample",
                    controller=bridge.controller,
                    t=sample * dt,
                    sample=sample,
                ) from exc
        if eng.stopped:
            raise MapError(
                f"the robot did not complete {what}: the run stopped ({eng.status_name}) "
                f"at t = {eng.t_now:.3f} s"
            )

    # -- section coordinates ---------------------------------------------------------------
    def z_names(self, hs: HybridState) -> tuple[str, ...]:
        """Names of the section coordinates of ``hs`` (see the module docstring)."""
        names = CONTROLLED_Z_NAMES + tuple(
            f"controller_state_{i}" for i in range(len(hs.controller_state))
        )
        if not self.builtin:
            names += ("held_torque_back", "held_torque_front")
        return names

    def z_of(self, hs: HybridState) -> np.ndarray:
        """The section coordinates of ``hs``: the state without x, the pinned toes' anchors
        relative to x (0 for a leg not pinned), the controller's state, the held torques."""
        s = np.asarray(hs.state)
        x = s[state_index("x")]
        rel = [
            (hs.toe_anchors[leg] - x) if hs.contact_modes[leg] in _PINNED else 0.0 for leg in Leg
        ]
        parts = [s[[state_index(n) for n in _STATE_Z_NAMES]], rel, hs.controller_state]
        if not self.builtin:
            parts.append(hs.held_torques)
        return np.concatenate([np.asarray(p, dtype=float) for p in parts])

    def hs_of(self, z, like: HybridState) -> HybridState:
        """The HybridState of section coordinates ``z`` at x = 0, with the discrete modes
        (and, for the built-in law, the held torques) of ``like``."""
        z = np.asarray(z, dtype=float)
        nb = len(CONTROLLED_Z_NAMES)
        nc = len(like.controller_state)
        s = state_vector(x=0.0, **dict(zip(_STATE_Z_NAMES, z)))
        held = like.held_torques if self.builtin else (z[nb + nc], z[nb + nc + 1])
        return HybridState(
            state=tuple(s),
            toe_anchors=(float(z[nb - 2]), float(z[nb - 1])),
            controller_state=tuple(z[nb : nb + nc]),
            held_torques=tuple(held),
            **discrete_modes(like),
        )


def section_state(result, section: str = "plant") -> HybridState:
    """The HybridState of ``result`` (a :class:`~scoutsim.SimulationResult`) at its section
    sample (``section``: "plant", the first sample after the back leg's lift-off, or
    "controller", the sample after the Table I law detects it) after its second-to-last
    back-leg lift-off: a Newton start on the section of :class:`StrideMap`. It carries no
    controller state and no held torques (a result does not record them): for a controller
    that keeps either, settle a stride or more from it
    (:func:`~scoutsim.analysis.controlled_orbit.controlled_fixed_point` does). MapError if
    the run has fewer than 3 back-leg lift-offs or did not complete."""
    dt = float(result.provenance["control_period_s"])
    kind, leg = SECTION_EVENTS[section]
    te = result.event_times(kind, leg.name.lower())
    if result.outcome != "completed" or len(te) < 3:
        raise MapError(
            f"no steady bounding to start from (outcome {result.outcome}, "
            f"{len(te)} back-leg lift-offs in {result.t[-1]:.3g} s)"
        )
    k = int(math.floor(te[-2] / dt + 1e-6)) + 1
    return result.hybrid_state(k)


def controlled_stride_map(hs, **settings):
    """One stride of the sampled closed loop from the HybridState ``hs`` taken at a section
    sample: ``(z_start, z_end, hs_end, period_s)``. ``settings``: the keywords of
    :class:`StrideMap` (model, friction_coefficient, robot, controller, integrator,
    max_period, section). MapError if the robot falls or no lift-off comes within
    ``max_period`` [s]."""
    m = StrideMap(**settings)
    c = m.crossing(hs)
    assert c.start is not None, "a crossing from a HybridState keeps its start"
    return m.z_of(c.start), m.z_of(c.state), c.state, c.period_s
