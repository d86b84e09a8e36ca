"""How robust the start-up from standing is: each of its parameters, and the robot's
motor torque, varied by -10 % and +10 % one at a time, and the floor changed, in ideal,
Model I and Model II (docs/model.md "Standing start").

A run counts as bounding when it completes ``DURATION`` s with steady bounding
(``summary["steady_bounding"]``) and at least ``MIN_STEADY`` steady strides. Prints one
row per variation: per model, yes/no, the start-up's duration [s] and the mean speed.

    python tools/startup_robustness.py [--duration S]
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this tree's scoutsim

import scoutsim  # noqa: E402
from scoutsim import ControllerParameters, RobotParameters, StartupParameters  # noqa: E402

MODELS = ("ideal", "I", "II")
DURATION = 10.0
MIN_STEADY = 7


def variations():
    """(name, robot, start-up parameters, floor friction) of every case."""
    robot = RobotParameters()
    ctrl = ControllerParameters()
    base = StartupParameters()
    yield "default", robot, base, None
    for f in (0.9, 1.1):
        tag = f"{(f - 1) * 100:+.0f} %"
        yield (
            f"stand_duration {tag}",
            robot,
            base.replace(stand_duration=base.stand_duration * f),
            None,
        )
        yield (
            f"step_angle_back {tag}",
            robot,
            base.replace(step_angle_back=ctrl.touchdown_angle_back * f),
            None,
        )
        yield f"step_kp {tag}", robot, base.replace(step_kp=ctrl.brake_kp_back * f), None
        yield f"step_kd {tag}", robot, base.replace(step_kd=ctrl.brake_kd_back * f), None
        yield (
            f"front_pushoff_angle {tag}",
            robot,
            base.replace(front_pushoff_angle=base.front_pushoff_angle * f),
            None,
        )
        # the hip torque the motor gives (Models I, II): its current limit
        yield (
            f"current_limit {tag}",
            robot.replace(current_limit=robot.current_limit * f),
            base,
            None,
        )
    yield "no front push", robot, base.replace(front_pushoff_angle=None), None
    for f in (0.9, 1.1):
        yield (
            f"no front push, current_limit {(f - 1) * 100:+.0f} %",
            robot.replace(current_limit=robot.current_limit * f),
            base.replace(front_pushoff_angle=None),
            None,
        )
    yield "floor mu = 0.8", robot, base, 0.8
    yield "floor mu = 1.5", robot, base, 1.5
    yield "floor no slip", robot, base, math.inf


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=DURATION)
    args = ap.parse_args(argv)
    print(f"{'variation':32s} " + " ".join(f"{m:>22s}" for m in MODELS))
    for name, robot, startup, mu in variations():
        cells = []
        for model in MODELS:
            r = scoutsim.simulate(
                robot,
                None,
                "standing",
                args.duration,
                model=model,
                startup=startup,
                friction_coefficient=mu,
            )
            s = r.summary()
            ok = (
                s["outcome"] == "completed"
                and s["steady_bounding"]
                and s["n_steady_strides"] >= MIN_STEADY
            )
            su = s.get("startup_duration_s")
            sp = s.get("mean_speed_m_s")
            cells.append(
                f"{'yes' if ok else 'NO':>3s} "
                f"{'-' if su is None else f'{su:.3f} s':>8s} "
                f"{'-' if sp is None else f'{sp:.2f} m/s':>9s}"
            )
        print(f"{name:32s} " + " ".join(f"{c:>22s}" for c in cells), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
