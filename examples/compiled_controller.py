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
line, a brake at the sweep limit (the structure of the paper's Table I controller, eqs.
2-5), and a pitch-rate term on the touchdown angles (gain ``K_PITCH_RATE``, 0 by default)
to play with. Its parameter array has named slots; every quantity that may differ between
the legs (set-points, gains, the leg rest length, the motor constants of a robot whose
legs differ) has two, back then front (``params[NAME + leg]``), so it runs any robot.
With the gain at 0 it is the Table I law, and the script checks that it reproduces the
built-in controller's run bit for bit.

Run it (after ``pip install -e .`` in the repository):

    python examples/compiled_controller.py [--robot FILE] [--duration 10] [--model II]
                                           [--pitch-rate-gain 0.0] [--quick]

``--robot FILE`` is a robot file as ``scoutsim run --robot`` reads it (its
``[controller]`` section sets the Table I parameters of both controllers, its
``[sensors]`` section what both read); ``--quick``
runs 4 s instead of 10 s (seconds in all). It prints the compile time, each run's outcome,
gait, speed and distance, and whether the two runs agree.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

import scoutsim
from scoutsim.control import CompiledController
from scoutsim.control import sensors as S
from scoutsim.names import LEG_NAMES, LegState

# --- the controller's parameter array, by name ------------------------------------------
# a per-leg quantity takes two slots, back then front: params[NAME + leg]
PER_LEG = len(LEG_NAMES)
TD = 0  # touchdown angles [rad]
SWEEP = TD + PER_LEG  # sweep limits [rad]
KP_FLIGHT = SWEEP + PER_LEG  # flight servo gains [N m/rad]
KD_FLIGHT = KP_FLIGHT + PER_LEG  # ... [N m s/rad]
KP_BRAKE = KD_FLIGHT + PER_LEG  # brake servo gains [N m/rad]
KD_BRAKE = KP_BRAKE + PER_LEG  # ... [N m s/rad]
REST_LENGTH = KD_BRAKE + PER_LEG  # leg rest length l0 [m]
STALL_TORQUE = REST_LENGTH + PER_LEG  # the motor's torque-speed line at the leg,
SLOPE = STALL_TORQUE + PER_LEG  # tau = -stall + slope rate [N m], [N m s/rad]
TORQUE_LIMIT = SLOPE + PER_LEG  # the amplifier's current limit at the leg [N m]
# one value for both legs
TD_COMPRESSION = TORQUE_LIMIT + PER_LEG  # leg compression that means touchdown [m]
LO_COMPRESSION = TD_COMPRESSION + 1  # ... below which the leg has lifted off [m]
K_PITCH_RATE = LO_COMPRESSION + 1  # touchdown angle correction [rad per rad/s]
N_PARAMS = K_PITCH_RATE + 1

FLIGHT, RETRACTION, BRAKE = int(LegState.FLIGHT), int(LegState.RETRACTION), int(LegState.BRAKE)
QUICK_DURATION = 4.0  # simulated time [s] of --quick


def bound_with_pitch_rate(t, y, params, state, torque, leg_states):
    """Hip torques [N m] for the readings ``y`` (see the module docstring)."""
    for leg in range(2):
        angle = y[S.HIP_ANGLE + leg]
        rate = y[S.HIP_RATE + leg]
        compression = params[REST_LENGTH + leg] - y[S.LEG_LENGTH + leg]
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
            torque[leg] = (
                params[KP_FLIGHT + leg] * (target - angle) - params[KD_FLIGHT + leg] * rate
            )
        elif st == RETRACTION:
            tau = -params[STALL_TORQUE + leg] + params[SLOPE + leg] * rate
            torque[leg] = min(0.0, max(tau, -params[TORQUE_LIMIT + leg]))
        else:
            torque[leg] = (
                params[KP_BRAKE + leg] * (params[SWEEP + leg] - angle)
                - params[KD_BRAKE + leg] * rate
            )
    return 0


def controller_params(
    robot: scoutsim.RobotParameters | None = None,
    table: scoutsim.ControllerParameters | None = None,
    pitch_rate_gain: float = 0.0,
) -> np.ndarray:
    """The parameter array (slots above) for ``robot`` (default Scout II) and the Table I
    parameters ``table`` (default Table I): each leg's set-points and gains, and each leg's
    rest length and motor constants (eqs. 2-4 of the paper, ``robot.leg(leg)``)."""
    robot = robot or scoutsim.RobotParameters()
    table = table or scoutsim.ControllerParameters()
    p = np.zeros(N_PARAMS)
    for leg, name in enumerate(LEG_NAMES):
        one = robot.leg(leg)
        p[TD + leg] = getattr(table, f"touchdown_angle_{name}")
        p[SWEEP + leg] = getattr(table, f"sweep_limit_{name}")
        p[KP_FLIGHT + leg] = getattr(table, f"flight_kp_{name}")
        p[KD_FLIGHT + leg] = getattr(table, f"flight_kd_{name}")
        p[KP_BRAKE + leg] = getattr(table, f"brake_kp_{name}")
        p[KD_BRAKE + leg] = getattr(table, f"brake_kd_{name}")
        p[REST_LENGTH + leg] = one.leg_rest_length
        p[STALL_TORQUE + leg] = one.stall_torque
        p[SLOPE + leg] = -one.torque_speed_slope
        p[TORQUE_LIMIT + leg] = one.max_leg_torque
    p[TD_COMPRESSION] = table.touchdown_compression
    p[LO_COMPRESSION] = table.liftoff_compression
    p[K_PITCH_RATE] = pitch_rate_gain
    return p


def make_controller(
    robot: scoutsim.RobotParameters | None = None,
    pitch_rate_gain: float = 0.0,
    table: scoutsim.ControllerParameters | None = None,
) -> CompiledController:
    """The example controller on ``robot`` (default Scout II, legs alike or not), with the
    set-points and gains of ``table`` (default Table I) and the robot's motor constants."""
    return CompiledController(
        bound_with_pitch_rate,
        params=controller_params(robot, table, pitch_rate_gain),
        name="bound_with_pitch_rate",
    )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--robot",
        metavar="FILE",
        help="TOML robot file, as `scoutsim run --robot` (default: Scout II)",
    )
    ap.add_argument(
        "--duration",
        type=float,
        default=None,
        help="simulated time [s] (default 10, 4 with --quick)",
    )
    ap.add_argument("--model", default="II", choices=["ideal", "I", "II"])
    ap.add_argument(
        "--pitch-rate-gain",
        type=float,
        default=0.0,
        help="touchdown angle correction [deg per deg/s]",
    )
    ap.add_argument("--quick", action="store_true", help="a short run (seconds in all)")
    args = ap.parse_args(argv)
    duration = (
        args.duration if args.duration is not None else QUICK_DURATION if args.quick else 10.0
    )
    robot, table = scoutsim.load_parameters(args.robot)
    sensors = scoutsim.load_sensors(args.robot, robot)  # the file's [sensors], else ideal
    scoutsim.simulation.simulator.warm_up()
    ctrl = make_controller(robot, args.pitch_rate_gain, table)  # deg/deg-s = rad/rad-s
    print(f"compiled the controller in {ctrl.compile_time_s:.2f} s")
    runs = {}
    for name, c in (("built-in Table I", table), ("this example", ctrl)):
        t0 = time.perf_counter()
        r = scoutsim.simulate(robot, c, duration=duration, model=args.model, sensors=sensors)
        wall = time.perf_counter() - t0
        runs[name] = r
        s = r.summary()
        speed = s.get("mean_speed_m_s")
        print(
            f"{name:18s} {r.outcome:10s} {wall * 1e3:7.1f} ms ({r.t_end / wall:5.0f}x real "
            f"time), {s.get('n_steady_strides', 0)} steady strides, mean speed "
            f"{'n/a' if speed is None or math.isnan(speed) else f'{speed:.3f} m/s'}, "
            f"{r.x[-1] - r.x[0]:.4f} m in {r.t_end:.2f} s"
        )
    a, b = runs.values()
    same = a.outcome == b.outcome and np.array_equal(a.t, b.t) and np.array_equal(a.state, b.state)
    print(
        f"the two runs agree bit for bit: {'yes' if same else 'no'}"
        + ("" if args.pitch_rate_gain == 0.0 else " (expected: the pitch-rate gain is not 0)")
    )


if __name__ == "__main__":
    main()
