"""Packing of RobotParameters into the compiled model's parameter array (the one place
where per-physical-leg values meet the model variant and its options; every leg quantity
is packed per virtual leg, back and front, whether the robot's legs differ or not)."""

from __future__ import annotations

import math

import numpy as np

from ...parameters import Environment, RobotParameters
from . import layout as L
from .flags import FLAG_OFF, FLAG_ON
from .hip_unit import hip_unit_code


def default_friction(robot: RobotParameters) -> float:
    """The default floor's Coulomb mu for ``robot`` (:meth:`Environment.friction_for`:
    DEFAULT_FRICTION_COEFFICIENT, or no slip for massless legs)."""
    return Environment().friction_for(robot)


def robot_array(
    robot: RobotParameters,
    model: str,
    *,
    friction_coefficient: float | None = None,
    passive_touchdown_angles=(0.0, 0.0),
    passive_touchdown_world: bool = True,
    pitch_limit: float = math.radians(60.0),
    strut_omega: float = 200.0,
    clamp_torso: bool = False,
    clamp_legs: bool = False,
    motor_circuit: str = "amplifier",
) -> np.ndarray:
    """Parameter array P for the compiled model.

    Parameters
    ----------
    robot : RobotParameters (SI, per physical leg).
    model : "ideal", "I", "II" or "passive" (no actuators).
    friction_coefficient : Coulomb coefficient mu of the toe; ``inf`` = no slip (a stance
        that loses normal force while the leg still pushes then slides frictionlessly).
        None (default): :func:`default_friction` of the robot.
    passive_touchdown_angles : (back, front) [rad], massless legs only: angle at which a
        massless leg is placed in flight.
    passive_touchdown_world : massless legs only: angles from the world vertical (True) or
        relative to the torso (False).
    pitch_limit : |theta| [rad] beyond which the run counts as a fall (default 60 deg).
    strut_omega : Baumgarte rate [rad/s] of the rigid-strut length constraint (docs/specification.md section 3).
    clamp_torso : bench rigs only (scoutsim.identification.rigs): hold the torso's x, y,
        theta fixed by three extra constraint rows of the KKT system (docs/identification.md).
    clamp_legs : bench rigs only: also hold both leg angles phi fixed relative to the torso
        (the stall rig); needs ``clamp_torso``.
    motor_circuit : "amplifier" (normal operation, docs/specification.md section 4), "open" (motor leads open:
        zero current) or "short" (leads shorted: i = -K_w w_m / R_A, back-EMF braking).
    """
    if friction_coefficient is None:
        friction_coefficient = default_friction(robot)
    if model not in L.MODEL_NAMES:
        raise ValueError(
            f"model = {model!r} is not allowed: must be one of {sorted(L.MODEL_NAMES)}"
        )
    if not (friction_coefficient >= 0.0):
        raise ValueError(
            f"friction_coefficient = {friction_coefficient} is not allowed: "
            "must be >= 0 (inf = no slip)"
        )
    if not (0.0 < pitch_limit < math.pi / 2):
        raise ValueError(
            f"pitch_limit = {math.degrees(pitch_limit)} deg is not allowed: must be in (0, 90) deg"
        )
    if motor_circuit not in L.CIRCUIT_NAMES:
        raise ValueError(
            f"motor_circuit = {motor_circuit!r} is not allowed: must be one of "
            f"{sorted(L.CIRCUIT_NAMES)}"
        )
    if clamp_legs and not clamp_torso:
        raise ValueError(
            "clamp_legs = True is not allowed without clamp_torso = True (the "
            "stall rig holds the torso and the legs)"
        )
    P = np.zeros(L.NP_)
    P[L.P_MT] = robot.torso_mass
    P[L.P_IT] = robot.torso_inertia
    P[L.P_L] = robot.half_hip_spacing
    P[L.P_COM_OFFSET] = robot.com_offset
    P[L.P_NP] = float(robot.legs_per_virtual_leg)
    P[L.P_G] = robot.gravity
    P[L.P_TORSO_LEN] = robot.torso_length
    P[L.P_TORSO_H] = robot.torso_height
    P[L.P_VB] = robot.battery_voltage
    P[L.P_RB] = robot.battery_resistance
    for leg in (L.BACK, L.FRONT):
        one = robot.leg(leg)
        for slot, value in (
            (L.P_ML, one.leg_mass),
            (L.P_IL, one.leg_inertia),
            (L.P_K, one.leg_stiffness),
            (L.P_C, one.leg_damping),
            (L.P_L0, one.leg_rest_length),
            (L.P_D, one.leg_com_distance),
            (L.P_N, one.gear_ratio),
            (L.P_ETA, one.efficiency),
            (L.P_TAU_IDLE, one.gearbox_idle_loss_torque),
            (L.P_C_LOAD, one.gearbox_load_loss_coefficient),
            (L.P_BACKLASH, one.belt_backlash),
            (L.P_LEG_FRIC, one.leg_friction_force),
            (L.P_LEG_FRIC_SIDE, one.leg_friction_side_load_coefficient),
            (L.P_LEG_C_ANGLE, one.leg_damping_angle_coefficient),
            (L.P_J1, one.drive_gear_inertia),
            (L.P_J2, one.driven_gear_inertia),
            (L.P_TAU_S, one.joint_stiction),
            (L.P_B_J, one.joint_damping),
            (L.P_KB, one.belt_stiffness),
            (L.P_CB, one.belt_damping),
            (L.P_KT, one.torque_constant),
            (L.P_KW, one.speed_constant),
            (L.P_RA, one.armature_resistance),
            (L.P_IMAX, one.current_limit),
        ):
            P[slot + leg] = value
    P[L.P_MODEL] = L.MODEL_NAMES[model]
    P[L.P_HIP_UNIT] = hip_unit_code(model, robot)
    no_slip = not math.isfinite(friction_coefficient)
    P[L.P_NO_SLIP] = FLAG_ON if no_slip else FLAG_OFF
    P[L.P_MU] = 0.0 if no_slip else friction_coefficient  # read only where toes can slip
    massless = all(
        m == 0.0 and i == 0.0
        for m, i in zip(robot.per_leg("leg_mass"), robot.per_leg("leg_inertia"))
    )
    P[L.P_MASSLESS] = FLAG_ON if massless else FLAG_OFF
    P[L.P_TD_WORLD] = FLAG_ON if passive_touchdown_world else FLAG_OFF
    P[L.P_TD_B] = passive_touchdown_angles[0]
    P[L.P_TD_F] = passive_touchdown_angles[1]
    P[L.P_THETA_LIM] = pitch_limit
    P[L.P_STRUT_OMEGA] = strut_omega
    P[L.P_CLAMP_TORSO] = FLAG_ON if clamp_torso else FLAG_OFF
    P[L.P_CLAMP_LEGS] = FLAG_ON if clamp_legs else FLAG_OFF
    P[L.P_CIRCUIT] = float(L.CIRCUIT_NAMES[motor_circuit])
    for leg in (L.BACK, L.FRONT):
        one = robot.leg(leg)
        if model == "II" and not (
            one.driven_gear_inertia + one.gear_ratio**2 * one.drive_gear_inertia > 0.0
        ):
            raise ValueError(
                f"robot.driven_gear_inertia / drive_gear_inertia = 0 ({L.LEG_NAMES[leg]} "
                "leg) is not allowed in Model II: the reflected gear inertia "
                "J_2 + N^2 J_1 must be > 0"
            )
    if massless and model != "passive":
        raise ValueError(
            "massless legs (leg_mass = leg_inertia = 0) carry no hip torque: use model='passive'"
        )
    if massless and math.isfinite(friction_coefficient):
        raise ValueError(
            "friction_coefficient: Coulomb slip is not defined for massless "
            "legs (a massless leg carries only axial force); use inf"
        )
    return P
