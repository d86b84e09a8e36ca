"""The time series of a run by name: torso position [m], pitch [rad], their rates, the
mechanical energy [J] and battery voltage [V]; per leg the angles [rad], rates [rad/s],
lengths [m], toe positions [m], forces [N], hip torques [N m], motor currents [A] and
speeds [rad/s], belt deflection [rad], controller leg states, plant contact modes and
motor-joint modes (codes of :mod:`scoutsim.names`); and the complete hybrid state at one
sample. A mixin of :class:`~scoutsim.result.simulation_result.SimulationResult`, which holds the
arrays (``state``, ``aux``, ``modes``; layout of :mod:`scoutsim._core.model.layout`).
"""

from __future__ import annotations

import numpy as np

from .._core.model import layout as L
from ..names import leg_index
from ..state import HybridState
from .run_data import RunData

__all__ = ["SeriesAccessors"]


class SeriesAccessors(RunData):
    """Named accessors of a run's time series (sampled at :attr:`t`)."""

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
    def vertical_speed(self):
        """Torso COM vertical velocity dy/dt [m/s]."""
        return self.state[:, L.NQ + L.IY]

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
        return self.state[:, L.IPHB + leg_index(leg)]

    def leg_rate(self, leg):
        """[rad/s]"""
        return self.state[:, L.NQ + L.IPHB + leg_index(leg)]

    def motor_angle(self, leg):
        """Driven-gear angle alpha relative to the torso [rad] (= phi outside Model II)."""
        return self.state[:, L.IALB + leg_index(leg)]

    def motor_angle_rate(self, leg):
        """Rate of the driven-gear angle alpha [rad/s] (= the leg rate outside Model II)."""
        return self.state[:, L.NQ + L.IALB + leg_index(leg)]

    def leg_length(self, leg):
        """[m]"""
        return self.state[:, L.IL_B + leg_index(leg)]

    def _aux(self, leg, slot):
        return self.aux[:, leg_index(leg) * L.NAUX_LEG + slot]

    def toe_position(self, leg):
        """(x, y) of the virtual leg's toe in the world [m]: the hip plus the leg along
        its angle (on the ground in stance)."""
        return self._aux(leg, L.A_TOE_X), self._aux(leg, L.A_TOE_Y)

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
        """Controller leg state per sample, codes of :class:`~scoutsim.names.LegState`:
        0 flight, 1 stance-retraction, 2 stance-brake."""
        return self.modes[:, L.RM_LEG_STATE_B + leg_index(leg)].astype(int)

    def contact_mode(self, leg):
        """Plant contact mode per sample, codes of :class:`~scoutsim.names.ContactMode`:
        0 flight, 1 stick, 2 slide, 3 strut."""
        return self.modes[:, L.RM_CONTACT_B + leg_index(leg)].astype(int)

    def motor_joint_mode(self, leg):
        """Model II motor-joint mode per sample, codes of
        :class:`~scoutsim.names.MotorJointMode`: -1 / +1 slipping in that direction,
        0 stuck (0 throughout in the other variants)."""
        return self.modes[:, L.RM_MOTOR_B + leg_index(leg)].astype(int)

    def hybrid_state(self, k: int):
        """The complete hybrid state at recorded sample ``k`` (continuous state, plant and
        controller modes, toe anchors) as a :class:`~scoutsim.state.HybridState`:
        ``simulate(..., initial_state=result.hybrid_state(k))`` continues this run from
        t[k] (its time restarts at 0), to the integration tolerance: the integrator's own
        state is not carried (see :class:`~scoutsim.state.HybridState`)."""
        n = len(self.t)
        if not (isinstance(k, (int, np.integer)) and -n <= k < n):
            raise ValueError(
                f"k = {k!r} is not allowed: must be an integer sample index in [{-n}, {n - 1}]"
            )
        m = self.modes[k].astype(int)
        aux = self.aux[k]
        return HybridState(
            state=self.state[k],
            leg_states=(m[L.RM_LEG_STATE_B], m[L.RM_LEG_STATE_F]),
            contact_modes=(m[L.RM_CONTACT_B], m[L.RM_CONTACT_F]),
            motor_modes=(m[L.RM_MOTOR_B], m[L.RM_MOTOR_F]),
            slide_directions=tuple(
                1 if aux[leg * L.NAUX_LEG + L.A_SLIP_V] >= 0.0 else -1 for leg in range(2)
            ),
            toe_anchors=tuple(float(aux[leg * L.NAUX_LEG + L.A_TOE_X]) for leg in range(2)),
        )
