"""Writing your own controller so that it runs compiled, at the built-in controller's speed.

A controller for scoutsim is a function of the sensor readings. Written as a plain Python
object (``command(t, sensors)``) it is called from the simulator's compiled loop at every
control sample, which costs a few microseconds each; written as a Numba-compilable
function and wrapped in :class:`scoutsim.CompiledController`, it runs inside the compiled
loop through a function pointer, as fast as the built-in Table I controller. Editing it
compiles only the function (about half a second), never the simulator.

The function's signature is fixed::

    command(t, y, params, state, torque, leg_states) -> int

``y`` holds the readings by slot (``scoutsim.control.sensors``: ``HIP_ANGLE``,
``HIP_RATE``, ``LEG_LENGTH``, ``PITCH``, ``PITCH_RATE``, ``ACCELERATION``,
``LASER_RANGE``, ``MOTOR_CURRENT``, ``BATTERY``; back then front for the legs; SI units),
``params`` and ``state`` are your own float arrays (the state starts from a copy of the
initial state at every run), ``torque`` receives the hip torques per physical leg [N m]
(back, front), ``leg_states`` the leg states to log. Return 0 to go on.

This example is a bounding controller written from scratch in that form: per leg, a
flight servo to a touchdown angle, stance-retraction at the motor's full torque-speed
line, a brake at the sweep limit (the structure of the paper's Table I controller), and a
pitch-rate term on the touchdown angles (gain ``K_PITCH_RATE``, 0 by default) to play
with. Run it:

    python examples/compiled_controller.py [--duration 10] [--pitch-rate-gain 0.0]

It prints the compile time, the run's gait and its speed next to the built-in controller's.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

import scoutsim
from scoutsim.control import CompiledController
from scoutsim.control import sensors as S

# --- the controller's parameter array, by name --------------------------------------
TD = 0            # touchdown angles [rad], back, front (TD + 1)
SWEEP = 2         # sweep limits [rad], back, front
KP_FLIGHT = 4     # flight servo gains [N m/rad], [N m s/rad]
KD_FLIGHT = 5
KP_BRAKE = 6      # brake servo gains
KD_BRAKE = 7
TD_COMPRESSION = 8    # leg compression that means touchdown [m]
LO_COMPRESSION = 9    # ... below which the leg has lifted off [m]
REST_LENGTH = 10      # leg rest length l0 [m]
STALL_TORQUE = 11     # the motor's torque-speed line at the leg: tau = -stall + slope rate
SLOPE = 12
TORQUE_LIMIT = 13     # the amplifier's current limit, as a leg torque [N m]
K_PITCH_RATE = 14     # touchdown angle correction per pitch rate [rad per rad/s]
N_PARAMS = 15

FLIGHT, RETRACTION, BRAKE = 0, 1, 2


def bound_with_pitch_rate(t, y, params, state, torque, leg_states):
    """Hip torques [N m] for the readings ``y`` (see the module docstring)."""
    for leg in range(2):
        angle = y[S.HIP_ANGLE + leg]
        rate = y[S.HIP_RATE + leg]
        compression = params[REST_LENGTH] - y[S.LEG_LENGTH + leg]
        st = leg_states[leg]
        if st == FLIGHT and compression > params[TD_COMPRESSION]:
            st = RETRACTION
        elif st != FLIGHT and compression < params[LO_COMPRESSION]:
            st = FLIGHT
        if st == RETRACTION and angle < params[SWEEP + leg]:
            st = BRAKE
        leg_states[leg] = st
        if st == FLIGHT:
            target = params[TD + leg] + params[K_PITCH_RATE] * y[S.PITCH_RATE]
            torque[leg] = params[KP_FLIGHT] * (target - angle) - params[KD_FLIGHT] * rate
        elif st == RETRACTION:
            tau = -params[STALL_TORQUE] + params[SLOPE] * rate
            torque[leg] = min(0.0, max(tau, -params[TORQUE_LIMIT]))
        else:
            torque[leg] = (params[KP_BRAKE] * (params[SWEEP + leg] - angle)
                           - params[KD_BRAKE] * rate)
    return 0


def make_controller(robot: scoutsim.RobotParameters | None = None,
                    pitch_rate_gain: float = 0.0) -> CompiledController:
    """The example controller on ``robot`` (default Scout II), with the Table I set-points
    and gains and the robot's motor constants (eqs. 2-4 of the paper)."""
    robot = robot or scoutsim.RobotParameters()
    table = scoutsim.ControllerParameters()
    p = np.zeros(N_PARAMS)
    p[TD:TD + 2] = table.touchdown_angle_back, table.touchdown_angle_front
    p[SWEEP:SWEEP + 2] = table.sweep_limit_back, table.sweep_limit_front
    p[KP_FLIGHT], p[KD_FLIGHT] = table.flight_kp_back, table.flight_kd_back
    p[KP_BRAKE], p[KD_BRAKE] = table.brake_kp_back, table.brake_kd_back
    p[TD_COMPRESSION] = table.touchdown_compression
    p[LO_COMPRESSION] = table.liftoff_compression
    p[REST_LENGTH] = robot.leg_rest_length
    p[STALL_TORQUE] = robot.stall_torque
    p[SLOPE] = -robot.torque_speed_slope
    p[TORQUE_LIMIT] = robot.max_leg_torque
    p[K_PITCH_RATE] = pitch_rate_gain
    return CompiledController(bound_with_pitch_rate, params=p, name="bound_with_pitch_rate")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--duration", type=float, default=10.0, help="simulated time [s]")
    ap.add_argument("--model", default="II", choices=["ideal", "I", "II"])
    ap.add_argument("--pitch-rate-gain", type=float, default=0.0,
                    help="touchdown angle correction [deg per deg/s]")
    args = ap.parse_args(argv)
    scoutsim.simulation.warm_up()
    ctrl = make_controller(pitch_rate_gain=args.pitch_rate_gain)   # deg/deg-s = rad/rad-s
    print(f"compiled the controller in {ctrl.compile_time_s:.2f} s")
    for name, c in (("built-in Table I", None), ("this example", ctrl)):
        t0 = time.perf_counter()
        r = scoutsim.simulate(controller=c, duration=args.duration, model=args.model)
        wall = time.perf_counter() - t0
        s = r.summary()
        speed = s.get("mean_speed_m_s")
        print(f"{name:18s} {r.outcome:10s} {wall * 1e3:7.1f} ms ({r.t_end / wall:5.0f}x real "
              f"time), {s.get('n_steady_strides', 0)} steady strides, mean speed "
              f"{'n/a' if speed is None or math.isnan(speed) else f'{speed:.3f} m/s'}")


if __name__ == "__main__":
    main()
