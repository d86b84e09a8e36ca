"""Packing of RobotParameters into the compiled model's parameter array (the one place
where per-physical-leg values meet the model variant and its options)."""

from __future__ import annotations

import math

import numpy as np

from ..parameters import Environment, RobotParameters
from . import layout as L


def default_friction(robot: RobotParameters) -> float:
    """The default floor's Coulomb mu for ``robot`` (:meth:`Environment.friction_for`:
    DEFAULT_FRICTION_COEFFICIENT, or no slip for massless legs)."""
    return Environment().friction_for(robot)


def robot_array(robot: RobotParameters, model: str, *, friction_coefficient: float | None = None,
                passive_touchdown_angles=(0.0, 0.0), passive_touchdown_world: bool = True,
                pitch_limit: float = math.radians(60.0), strut_omega: float = 200.0,
                clamp_torso: bool = False, clamp_legs: bool = False,
                motor_circuit: str = "amplifier") -> np.ndarray:
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
        raise ValueError(f"model = {model!r} is not allowed: must be one of "
                         f"{sorted(L.MODEL_NAMES)}")
    if not (friction_coefficient >= 0.0):
        raise ValueError(f"friction_coefficient = {friction_coefficient} is not allowed: "
                         "must be >= 0 (inf = no slip)")
    if not (0.0 < pitch_limit < math.pi / 2):
        raise ValueError(f"pitch_limit = {math.degrees(pitch_limit)} deg is not allowed: "
                         "must be in (0, 90) deg")
    if motor_circuit not in L.CIRCUIT_NAMES:
        raise ValueError(f"motor_circuit = {motor_circuit!r} is not allowed: must be one of "
                         f"{sorted(L.CIRCUIT_NAMES)}")
    if clamp_legs and not clamp_torso:
        raise ValueError("clamp_legs = True is not allowed without clamp_torso = True (the "
                         "stall rig holds the torso and the legs)")
    P = np.zeros(L.NP_)
    P[L.P_MT] = robot.torso_mass
    P[L.P_IT] = robot.torso_inertia
    P[L.P_ML] = robot.leg_mass
    P[L.P_IL] = robot.leg_inertia
    P[L.P_K] = robot.leg_stiffness
    P[L.P_C] = robot.leg_damping
    P[L.P_L] = robot.half_hip_spacing
    P[L.P_L0] = robot.leg_rest_length
    P[L.P_D] = robot.leg_com_distance
    P[L.P_NP] = float(robot.legs_per_virtual_leg)
    P[L.P_G] = robot.gravity
    P[L.P_TORSO_LEN] = robot.torso_length
    P[L.P_TORSO_H] = robot.torso_height
    P[L.P_N] = robot.gear_ratio
    P[L.P_ETA] = robot.efficiency
    P[L.P_TAU_IDLE] = robot.gearbox_idle_loss_torque
    P[L.P_C_LOAD] = robot.gearbox_load_loss_coefficient
    P[L.P_BACKLASH] = robot.belt_backlash
    P[L.P_LEG_FRIC] = robot.leg_friction_force
    P[L.P_LEG_FRIC_SIDE] = robot.leg_friction_side_load_coefficient
    P[L.P_LEG_C_ANGLE] = robot.leg_damping_angle_coefficient
    P[L.P_J1] = robot.drive_gear_inertia
    P[L.P_J2] = robot.driven_gear_inertia
    P[L.P_TAU_S] = robot.joint_stiction
    P[L.P_B_J] = robot.joint_damping
    P[L.P_KB] = robot.belt_stiffness
    P[L.P_CB] = robot.belt_damping
    P[L.P_KT] = robot.torque_constant
    P[L.P_KW] = robot.speed_constant
    P[L.P_RA] = robot.armature_resistance
    P[L.P_IMAX] = robot.current_limit
    P[L.P_VB] = robot.battery_voltage
    P[L.P_RB] = robot.battery_resistance
    P[L.P_MODEL] = L.MODEL_NAMES[model]
    P[L.P_MU] = friction_coefficient if math.isfinite(friction_coefficient) else 1e308
    massless = robot.leg_mass == 0.0 and robot.leg_inertia == 0.0
    P[L.P_MASSLESS] = 1.0 if massless else 0.0
    P[L.P_TD_WORLD] = 1.0 if passive_touchdown_world else 0.0
    P[L.P_TD_B] = passive_touchdown_angles[0]
    P[L.P_TD_F] = passive_touchdown_angles[1]
    P[L.P_THETA_LIM] = pitch_limit
    P[L.P_STRUT_OMEGA] = strut_omega
    P[L.P_CLAMP_TORSO] = 1.0 if clamp_torso else 0.0
    P[L.P_CLAMP_LEGS] = 1.0 if clamp_legs else 0.0
    P[L.P_CIRCUIT] = float(L.CIRCUIT_NAMES[motor_circuit])
    if model == "II" and not (robot.driven_gear_inertia + robot.gear_ratio ** 2
                              * robot.drive_gear_inertia > 0.0):
        raise ValueError("robot.driven_gear_inertia / drive_gear_inertia = 0 is not allowed "
                         "in Model II: the reflected gear inertia J_2 + N^2 J_1 must be > 0")
    if massless and model != "passive":
        raise ValueError("massless legs (leg_mass = leg_inertia = 0) carry no hip torque: "
                         "use model='passive'")
    if massless and math.isfinite(friction_coefficient):
        raise ValueError("friction_coefficient: Coulomb slip is not defined for massless "
                         "legs (a massless leg carries only axial force); use inf")
    return P
