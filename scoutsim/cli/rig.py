"""``scoutsim rig``: run a virtual bench rig (free swing, flight steps or stall: the
simulator with the torso clamped) and write its log with sensor noise; the stall rig also
prints the belt deflection at maximum hip torque (the robot measured about 8 deg).

    scoutsim rig {free-swing,flight-steps,stall} [--motor {open,short}] [--toe-mass KG]
                 [--release BACK,FRONT] [--duration S] [--robot FILE] [--out DIR]
                 [--seed SEED] [--no-noise]
"""

from __future__ import annotations

import math

from ._common import UsageError, add_out_option, load_robot, out_dir, positive_float, usage_errors

NAME = "rig"


def register(sub, common) -> None:
    rg = sub.add_parser(
        NAME,
        help="run a virtual bench rig and write its log",
        description="Run a virtual bench rig (the same simulator with the torso clamped) and "
        "write its log (DIR/<rig>.csv.gz) with sensor noise; the stall rig also "
        "prints the belt deflection at maximum hip torque (the robot measured about "
        "8 deg).",
    )
    rg.add_argument("rig", choices=("free-swing", "flight-steps", "stall"))
    rg.add_argument(
        "--motor",
        choices=("open", "short"),
        default="open",
        help="free swing: motor leads open or shorted (default: open)",
    )
    rg.add_argument(
        "--toe-mass",
        type=positive_float,
        default=None,
        metavar="KG",
        help="free swing: mass at the toe [kg] (default: 1)",
    )
    rg.add_argument(
        "--release",
        default=None,
        metavar="BACK,FRONT",
        help="free swing: release angles [deg] (default: 60,-40)",
    )
    rg.add_argument(
        "--duration",
        type=positive_float,
        default=None,
        metavar="S",
        help="recorded time [s] (default: the rig's)",
    )
    rg.add_argument("--robot", metavar="FILE", help="TOML robot file (default: Scout II)")
    add_out_option(rg, "scoutsim_rig", note="")
    rg.add_argument("--seed", type=int, default=0, help="noise seed (default: 0)")
    rg.add_argument("--no-noise", action="store_true", help="write the noise-free signals")
    rg.set_defaults(func=execute)


def _release_angles(text: str) -> dict:
    """--release BACK,FRONT [deg] -> the FreeSwing release angles [rad]."""
    try:
        b, f = (math.radians(float(v)) for v in text.split(","))
    except ValueError:
        raise UsageError(
            f"--release {text!r} is not allowed: must be BACK,FRONT in degrees"
        ) from None
    return {"release_angle_back": b, "release_angle_front": f}


def _make_rig(args):
    from ..identification.rigs import FlightSteps, FreeSwing, Stall

    kw = {} if args.duration is None else {"duration": args.duration}
    with usage_errors():
        if args.rig == "free-swing":
            if args.toe_mass is not None:
                kw["toe_mass"] = args.toe_mass
            if args.release:
                kw |= _release_angles(args.release)
            return FreeSwing(motor=args.motor, **kw)
        if args.rig == "flight-steps":
            return FlightSteps(**kw)
        return Stall(**kw)


def execute(args) -> int:
    from ..identification.rigs import RigNoise, rig_log, run_rig, stall_deflection

    robot = load_robot(args.robot)
    out = out_dir(args.out)
    rig = _make_rig(args)
    if args.rig == "stall":
        d = stall_deflection(robot, rig)
        res = d["result"]
        lo, hi = d["static_band_deg"]
        print(
            f"stall rig: hip torque {d['torque_nm']:.2f} N m per physical leg (N eta K_T "
            f"i_max); belt deflection after {rig.duration:g} s: "
            f"{d['deflection_final_deg']:.3f} deg (static band of the motor stiction "
            f"{lo:.3f} .. {hi:.3f} deg; creep time constant c_b/k_b = "
            f"{d['creep_time_constant_s']:.3f} s); the robot measured about 8 deg "
            "(docs/identification.md)"
        )
    else:
        res = run_rig(rig, robot)
    log = rig_log(res, noise=None if args.no_noise else RigNoise(), seed=args.seed)
    path = log.save(out / f"{args.rig}.csv.gz")
    print(f"{args.rig} rig: {res.outcome}, {len(res.t)} samples; wrote {path}")
    return 0
