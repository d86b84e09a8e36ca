""":class:`RobotParameters`: the physical parameters of the planar Scout II model (paper
Tables II, III) and the quantities derived from them."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from .packaged import _packaged_defaults


@dataclass(frozen=True)
@_packaged_defaults("robot", "transmission", "motor")
class RobotParameters:
    """Physical parameters of the planar Scout II model (SI units).

    Attributes
    ----------
    torso_mass : float
        Torso mass m_torso [kg] (Table III).
    torso_inertia : float
        Torso pitch inertia about its COM [kg m^2] (Table III).
    leg_mass : float
        Mass of one physical leg body [kg] (Table III).
    leg_inertia : float
        Inertia of one physical leg about its own COM [kg m^2] (Table III).
    leg_stiffness : float
        Leg spring constant k, one physical leg [N/m] (Table III).
    leg_damping : float
        Leg damper constant c, one physical leg [N s/m] (Table III).
    hip_spacing : float
        Distance between front and back hips [m] (Table III); L = hip_spacing/2.
    leg_rest_length : float
        Leg rest length l0 = mechanical stop [m] (Table III).
    leg_com_distance : float
        Distance from hip to leg COM along the leg axis [m] (assumed l0/2).
    legs_per_virtual_leg : int
        Physical legs lumped in one virtual leg (2 for bounding).
    gravity : float
        Gravitational acceleration [m/s^2].
    torso_length, torso_height : float
        Torso box used for fall detection [m] (assumed).
    planetary_ratio, sprocket_ratio : float
        Gear ratios [-]; N = planetary_ratio * sprocket_ratio (Table III).
    gearbox_efficiency, sprocket_efficiency : float
        Efficiencies in (0, 1]; eta = product (Table III).
    gearbox_idle_loss_torque : float
        tau_idle, torque-independent transmission loss at the leg side, per physical leg
        [N m] (assumed, default 0). Together with ``gearbox_load_loss_coefficient`` it makes
        the efficiency fall at low torque (paper Sec. IV.B; docs/model.md "Transmission
        losses"). Zero (with a zero coefficient) recovers the constant efficiency exactly.
    gearbox_load_loss_coefficient : float
        c_load, load-proportional loss tau_loss = tau_idle + c_load |tau_out| [-], in [0, 1)
        (assumed, default 0).
    drive_gear_inertia : float
        J_1, drive (motor-side) gear inertia [kg m^2] (Table II).
    driven_gear_inertia : float
        J_2, driven gear inertia [kg m^2] (Table II).
    joint_stiction : float
        Breakaway (and kinetic Coulomb) friction torque at the motor joint [N m] (Table II).
    joint_damping : float
        Viscous damping at the motor joint [N m s/rad] (Table II, 6.2e-7 N m/(deg/s)).
    belt_stiffness : float
        k_b, lumped backlash/belt torsional spring [N m/rad] (Table II, 7 N m/deg).
    belt_damping : float
        c_b, lumped belt damper [N m s/rad] (Table II, 4 N m/(deg/s)).
    belt_backlash : float
        Total angular play of the hip unit [rad] (assumed, default 0: the paper lumps
        backlash into the belt spring). With play b the belt spring acts only beyond
        |alpha - phi| = b / 2: tau_spring = k_b (delta - sign(delta) b / 2) there, 0 inside
        (a dead zone); the belt damper acts throughout (docs/model.md, "Effects beyond the
        paper's models").
    leg_friction_force : float
        Coulomb friction of the telescopic leg's sliding joint [N], per physical leg
        (assumed, default 0), opposing the leg-length rate; regularised linearly over
        |dl/dt| < ``model.leg.LEG_FRICTION_SPEED`` (1 mm/s), so it holds a leg whose net
        spring force is below it almost still (stiction).
    leg_friction_side_load_coefficient : float
        Additional leg friction per unit side load of the sliding joint [-] (assumed,
        default 0): friction force += coefficient x |hip torque| / l, the bending load the
        hip torque puts on the leg's bushings (torque-dependent friction, paper Sec. IV.B).
    leg_damping_angle_coefficient : float
        a_phi [1/rad^2] (assumed, default 0): the leg damper is c (1 + a_phi phi^2), rising
        with the leg's angle phi from the torso normal (angle-dependent damping, paper
        Sec. IV.B).
    torque_constant : float
        Motor torque constant K_T [N m/A] (assumed).
    speed_constant : float
        Motor back-EMF constant K_w [V s/rad] (assumed).
    armature_resistance : float
        R_A [ohm] (assumed).
    current_limit : float
        Amplifier current limit i_max [A] (assumed).
    battery_voltage : float
        Battery (open-circuit) voltage; V_bar = 36 V by default [V] (paper Sec. II.A).
    battery_resistance : float
        Internal resistance shared by all motors [ohm]; 0 = ideal source (assumed).
    """

    torso_mass: float
    torso_inertia: float
    leg_mass: float
    leg_inertia: float
    leg_stiffness: float
    leg_damping: float
    hip_spacing: float
    leg_rest_length: float
    leg_com_distance: float
    legs_per_virtual_leg: int
    gravity: float
    torso_length: float
    torso_height: float
    planetary_ratio: float
    sprocket_ratio: float
    gearbox_efficiency: float
    sprocket_efficiency: float
    gearbox_idle_loss_torque: float
    gearbox_load_loss_coefficient: float
    drive_gear_inertia: float
    driven_gear_inertia: float
    joint_stiction: float
    joint_damping: float
    belt_stiffness: float
    belt_damping: float
    belt_backlash: float
    leg_friction_force: float
    leg_friction_side_load_coefficient: float
    leg_damping_angle_coefficient: float
    torque_constant: float
    speed_constant: float
    armature_resistance: float
    current_limit: float
    battery_voltage: float
    battery_resistance: float

    # -- derived quantities (docs/specification.md section 4) ------------------------------------------
    @property
    def gear_ratio(self) -> float:
        """Combined gear ratio N = planetary x sprocket [-] (docs/specification.md section 4: 102.18)."""
        return self.planetary_ratio * self.sprocket_ratio

    @property
    def efficiency(self) -> float:
        """Constant transmission efficiency eta = gearbox x sprocket [-] (0.6528)."""
        return self.gearbox_efficiency * self.sprocket_efficiency

    @property
    def half_hip_spacing(self) -> float:
        """L, distance from torso COM to each hip [m]."""
        return 0.5 * self.hip_spacing

    @property
    def torque_per_amp(self) -> float:
        """Hip torque per ampere of motor current, N eta K_T [N m/A] (the compiled model's
        counterpart is ``scoutsim.model.actuator.torque_per_amp``)."""
        return self.gear_ratio * self.efficiency * self.torque_constant

    @property
    def stall_torque(self) -> float:
        """Torque-speed line at zero speed, at one physical leg: N eta K_T V / R_A [N m]
        (tau_max of the paper's eq. (3), written at the leg)."""
        return self.torque_per_amp * self.battery_voltage / self.armature_resistance

    @property
    def torque_speed_slope(self) -> float:
        """Torque lost per unit leg speed on the torque-speed line, at one physical leg:
        N^2 eta K_T K_w / R_A [N m s/rad] (minus the slope A of the paper's eq. (3), written
        at the leg)."""
        N = self.gear_ratio
        return N * N * self.efficiency * self.torque_constant * self.speed_constant \
            / self.armature_resistance

    @property
    def no_load_speed(self) -> float:
        """Leg speed where the torque-speed line crosses zero torque, V / (K_w N) [rad/s]."""
        return self.battery_voltage / (self.speed_constant * self.gear_ratio)

    @property
    def max_leg_torque(self) -> float:
        """Current-limited torque at one physical leg, N eta K_T i_max [N m]."""
        return self.torque_per_amp * self.current_limit

    @property
    def total_mass(self) -> float:
        """Torso plus all four physical legs [kg]."""
        return self.torso_mass + 2 * self.legs_per_virtual_leg * self.leg_mass

    def replace(self, **changes) -> "RobotParameters":
        """Return a copy with some fields changed (validated by the loader functions)."""
        return dataclasses.replace(self, **changes)
