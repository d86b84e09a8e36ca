""":class:`RobotParameters`: the physical parameters of the planar Scout II model (paper
Tables II, III) and the quantities derived from them; every leg, hip-unit and motor quantity
may differ between the back and the front legs (:data:`PER_LEG_FIELDS`)."""

from __future__ import annotations

import copy
import dataclasses
from dataclasses import dataclass

from ..names import LEG_NAMES, leg_index
from .packaged import PACKAGED, packaged_defaults
from .parameter_error import ParameterError
from .schema import PER_LEG_FIELDS, ROBOT_SECTIONS, given_per_leg
from .validation import check_robot

# LEG_NAMES (the legs, in the order of a (back, front) pair) and leg_index live in
# scoutsim.names, the one home of the legs' names; PER_LEG_FIELDS (which fields may differ
# between the legs) in the schema; they stay importable from here.
__all__ = ["RobotParameters", "PER_LEG_FIELDS", "LEG_NAMES", "leg_index", "given_per_leg"]


def _per_leg_value(name: str, value):
    """A per-leg field's value as stored: a scalar, or a (back, front) tuple whose values
    differ (an equal pair is stored as its one value, so a robot given per leg with equal
    values is the same robot as one given by scalars)."""
    if given_per_leg(value):
        pair = tuple(value)
        if len(pair) != 2:
            raise ParameterError(
                f"robot.{name} = {list(pair)!r} is not allowed: give one value "
                "for both legs or a (back, front) pair",
                name,
            )
        back, front = (v.item() if hasattr(v, "item") else v for v in pair)
        return back if back == front and type(back) is type(front) else (back, front)
    return value


@dataclass(frozen=True)
@packaged_defaults(*ROBOT_SECTIONS)
class RobotParameters:
    """Physical parameters of the planar Scout II model (SI units).

    Every field of :data:`PER_LEG_FIELDS` (the leg bodies, telescopic legs, hip units and
    motors) takes one value for both legs or a (back, front) pair, e.g.
    ``leg_rest_length=(0.323, 0.30)``; a robot file writes ``value = [0.323, 0.30]``. An
    equal pair is stored as its one value. :meth:`leg` gives one leg's values (and derived
    quantities), :meth:`per_leg` a field's (back, front) pair; the derived quantities below
    (``gear_ratio``, ``stall_torque``, ...) need the legs to agree on their inputs and say
    so otherwise.

    Constructing one (also with :meth:`replace` or ``dataclasses.replace``) checks every
    value: a :class:`~scoutsim.parameters.ParameterError` names the field (and the leg), the
    value and its allowed range; a value far outside what a robot of this kind has warns
    (:class:`~scoutsim.parameters.ImplausibleParameterWarning`, once per value and process).

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
    com_offset : float
        Distance [m] of the torso's centre of mass ahead of the midpoint between the hips
        (assumed, default 0: midway, as in the paper): the back hip is hip_spacing / 2 +
        com_offset behind the COM, the front hip hip_spacing / 2 - com_offset ahead of it.
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
        Efficiencies in (0, 1]; eta = product (Table III: 0.68 x 0.96 = 65.28 %, the
        paper's constant efficiency).
    gearbox_idle_loss_torque : float
        tau_idle, torque-independent transmission loss at the leg side, per physical leg
        [N m] (assumed, default 0). Together with ``gearbox_load_loss_coefficient`` it makes
        the efficiency fall at low torque (paper Sec. IV.B; docs/model.md "Transmission
        losses"). Zero (with a zero coefficient) recovers the constant efficiency exactly.
    gearbox_load_loss_coefficient : float
        c_load, load-proportional loss tau_loss = tau_idle + c_load |tau_out| [-], in [0, 1)
        (assumed, default 0). The loss always opposes the transmitted power flow: a motor
        that drives the leg delivers that much less torque, and a leg that back-drives its
        motor must overcome it as well.
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

    torso_mass: float = PACKAGED
    torso_inertia: float = PACKAGED
    leg_mass: float = PACKAGED
    leg_inertia: float = PACKAGED
    leg_stiffness: float = PACKAGED
    leg_damping: float = PACKAGED
    hip_spacing: float = PACKAGED
    com_offset: float = PACKAGED
    leg_rest_length: float = PACKAGED
    leg_com_distance: float = PACKAGED
    legs_per_virtual_leg: int = PACKAGED
    gravity: float = PACKAGED
    torso_length: float = PACKAGED
    torso_height: float = PACKAGED
    planetary_ratio: float = PACKAGED
    sprocket_ratio: float = PACKAGED
    gearbox_efficiency: float = PACKAGED
    sprocket_efficiency: float = PACKAGED
    gearbox_idle_loss_torque: float = PACKAGED
    gearbox_load_loss_coefficient: float = PACKAGED
    drive_gear_inertia: float = PACKAGED
    driven_gear_inertia: float = PACKAGED
    joint_stiction: float = PACKAGED
    joint_damping: float = PACKAGED
    belt_stiffness: float = PACKAGED
    belt_damping: float = PACKAGED
    belt_backlash: float = PACKAGED
    leg_friction_force: float = PACKAGED
    leg_friction_side_load_coefficient: float = PACKAGED
    leg_damping_angle_coefficient: float = PACKAGED
    torque_constant: float = PACKAGED
    speed_constant: float = PACKAGED
    armature_resistance: float = PACKAGED
    current_limit: float = PACKAGED
    battery_voltage: float = PACKAGED
    battery_resistance: float = PACKAGED

    def __post_init__(self):
        for name in PER_LEG_FIELDS:
            value = getattr(self, name)
            stored = _per_leg_value(name, value)
            if stored is not value:
                object.__setattr__(self, name, stored)
        check_robot(self)

    # -- the legs --------------------------------------------------------------------------
    def per_leg(self, name: str) -> tuple:
        """The (back, front) values of field ``name`` (a field of :data:`PER_LEG_FIELDS`
        given as one value gives it twice)."""
        if name not in PER_LEG_FIELDS:
            raise ValueError(
                f"{name!r} is not a per-leg field; per-leg fields: {', '.join(PER_LEG_FIELDS)}"
            )
        value = getattr(self, name)
        return value if isinstance(value, tuple) else (value, value)

    @property
    def legs_differ(self) -> bool:
        """Whether any per-leg field has different back and front values."""
        return any(isinstance(getattr(self, n), tuple) for n in PER_LEG_FIELDS)

    def leg(self, leg) -> RobotParameters:
        """The robot with both legs set to leg ``leg``'s values ("back" / 0 or "front" / 1):
        one leg's quantities and everything derived from them
        (``robot.leg("front").stall_torque``)."""
        i = leg_index(leg)
        pairs = {
            n: getattr(self, n)[i] for n in PER_LEG_FIELDS if isinstance(getattr(self, n), tuple)
        }
        if not pairs:
            return self
        # one leg's values of a robot checked when it was made (leg by leg): a copy with
        # them, not a new construction (which would check, and warn of, them again)
        one = copy.copy(self)
        for name, value in pairs.items():
            object.__setattr__(one, name, value)
        return one

    def _same(self, derived: str, *names: str) -> tuple:
        """The values of ``names``, which must be the same for both legs for ``derived``."""
        for n in names:
            v = getattr(self, n)
            if isinstance(v, tuple):
                raise ValueError(
                    f"robot.{derived} is per leg here: {n} differs between the legs (back "
                    f"{v[0]:g}, front {v[1]:g}); ask one leg, robot.leg('back').{derived} "
                    f"or robot.leg('front').{derived}"
                )
        return tuple(getattr(self, n) for n in names)

    # -- derived quantities (docs/specification.md section 4) ------------------------------------------
    @property
    def gear_ratio(self) -> float:
        """Combined gear ratio N = planetary x sprocket [-] (docs/specification.md section 4: 102.18)."""
        planetary, sprocket = self._same("gear_ratio", "planetary_ratio", "sprocket_ratio")
        return planetary * sprocket

    @property
    def efficiency(self) -> float:
        """Constant transmission efficiency eta = gearbox x sprocket [-] (0.6528)."""
        gearbox, sprocket = self._same("efficiency", "gearbox_efficiency", "sprocket_efficiency")
        return gearbox * sprocket

    @property
    def half_hip_spacing(self) -> float:
        """L, half the distance between the hips [m] (the distance from the torso COM to each
        hip when ``com_offset`` is 0; :meth:`hip_offset`)."""
        return 0.5 * self.hip_spacing

    def hip_offset(self, leg) -> float:
        """Position [m] of leg ``leg``'s hip along the torso axis from the torso COM:
        -L - com_offset (back), L - com_offset (front); the compiled model's counterpart is
        ``scoutsim._core.model.kinematics.hip_offset``."""
        sign = (-1.0, 1.0)[leg_index(leg)]
        return sign * self.half_hip_spacing - self.com_offset

    @property
    def torque_per_amp(self) -> float:
        """Hip torque per ampere of motor current, N eta K_T [N m/A] (the compiled model's
        counterpart is ``scoutsim._core.model.actuator.torque_per_amp``)."""
        return (
            self.gear_ratio * self.efficiency * self._same("torque_per_amp", "torque_constant")[0]
        )

    @property
    def stall_torque(self) -> float:
        """Torque-speed line at zero speed, at one physical leg: N eta K_T V / R_A [N m]
        (tau_max of the paper's eq. (3), written at the leg)."""
        return (
            self.torque_per_amp
            * self.battery_voltage
            / self._same("stall_torque", "armature_resistance")[0]
        )

    @property
    def torque_speed_slope(self) -> float:
        """Torque lost per unit leg speed on the torque-speed line, at one physical leg:
        N^2 eta K_T K_w / R_A [N m s/rad] (minus the slope A of the paper's eq. (3), written
        at the leg)."""
        N = self.gear_ratio
        kt, kw, ra = self._same(
            "torque_speed_slope", "torque_constant", "speed_constant", "armature_resistance"
        )
        return N * N * self.efficiency * kt * kw / ra

    @property
    def no_load_speed(self) -> float:
        """Leg speed where the torque-speed line crosses zero torque, V / (K_w N) [rad/s]."""
        return self.battery_voltage / (
            self._same("no_load_speed", "speed_constant")[0] * self.gear_ratio
        )

    @property
    def max_leg_torque(self) -> float:
        """Current-limited torque at one physical leg, N eta K_T i_max [N m]."""
        return self.torque_per_amp * self._same("max_leg_torque", "current_limit")[0]

    @property
    def total_mass(self) -> float:
        """Torso plus all four physical legs [kg]."""
        back, front = self.per_leg("leg_mass")
        return self.torso_mass + self.legs_per_virtual_leg * (back + front)

    def replace(self, **changes) -> RobotParameters:
        """Return a copy with some fields changed (checked, as every construction is)."""
        return dataclasses.replace(self, **changes)
