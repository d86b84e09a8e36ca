"""``scoutsim continue``: a family of periodic gaits along one parameter, its stability
along the branch and where it bifurcates (docs/orbits.md, "Families of gaits").

    scoutsim continue --vary NAME=LO:HI --out DIR [--passive --speed V --apex-height H]
                      [--points N] [--model {ideal,I,II}] [--friction MU] [--duration S]
                      [--controller C] [--robot FILE] [--json]

With --passive the conservative model's family in the apex pitch rate (NAME
``pitch_rate_deg``), by pseudo-arclength continuation with exact Jacobians; otherwise the
controlled robot's orbit followed through N values of a robot, controller or floor
parameter. Writes ``family.csv``, ``family.parquet`` and ``family.png`` into DIR.

Exit code 1 if no orbit is found at any value.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

from ._common import (
    UsageError,
    add_controller_option,
    add_no_progress_option,
    controller_choice,
    dumps,
    load_parameters,
    make_controller,
    progress_messages,
)
from ._given import refuse_given
from ._orbit_options import (
    CONTROLLED_ONLY,
    PASSIVE_ONLY,
    add_controlled_orbit_options,
    add_passive_apex_options,
)

NAME = "continue"
#: the passive family's parameter
PITCH_RATE = "pitch_rate_deg"


def _points(text: str) -> int:
    n = int(text)
    if n < 2:
        raise ValueError(f"{n}: give at least 2 points")
    return n


def register(sub, common) -> None:
    p = sub.add_parser(
        NAME,
        help="a family of periodic gaits along one parameter, its stability and bifurcations",
        description="Follow a periodic gait as one parameter varies and write the branch "
        "table (family.csv, family.parquet: the parameter, touchdown angles from the world "
        "vertical, period, strides, mean speed, spectral radius per stride, stable, "
        "bifurcation, the largest multipliers, status) and its figure (family.png). "
        "--passive: the conservative model's family in the apex pitch rate "
        "(pitch_rate_deg), pseudo-arclength continuation with exact Jacobians; folds, "
        "branch points, period doublings and torus bifurcations located along it. "
        "Otherwise: the controlled robot's orbit at --points values of a robot.<field>, "
        "controller.<field> (a _deg suffix on an angle takes degrees) or "
        "friction_coefficient, each found after the robot settled from its neighbour "
        "(the attracting gait; docs/orbits.md).",
    )
    p.add_argument(
        "--vary",
        required=True,
        metavar="NAME=LO:HI",
        help="the parameter and its range, in the unit the name gives",
    )
    p.add_argument("--out", required=True, metavar="DIR", help="directory for the outputs")
    p.add_argument(
        "--passive",
        action="store_true",
        help="the passive conservative model (massless legs), varying pitch_rate_deg",
    )
    add_passive_apex_options(p)
    p.add_argument(
        "--points",
        type=_points,
        default=13,
        metavar="N",
        help="controlled: values from LO to HI, evenly spaced (default: 13)",
    )
    add_controlled_orbit_options(p, "simulated time to the first orbit's Newton start")
    p.add_argument(
        "--robot",
        metavar="FILE",
        help="TOML robot/controller file with the layout of scoutsim/data/scout2.toml "
        "(--passive: its massless-leg configuration); unset entries keep the defaults",
    )
    add_controller_option(p)
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    add_no_progress_option(p)
    p.set_defaults(func=execute)


def _vary(text: str) -> tuple[str, float, float]:
    name, sep, rng = text.partition("=")
    lo, sep2, hi = rng.partition(":")
    try:
        a, b = float(lo), float(hi)
    except ValueError:
        a = b = math.nan
    if not (sep and sep2 and name.strip() and math.isfinite(a) and math.isfinite(b)):
        raise UsageError(f"--vary {text!r}: give NAME=LO:HI with finite numbers")
    if not b > a:
        raise UsageError(f"--vary {text!r}: HI must exceed LO")
    return name.strip(), a, b


def _axis(name: str) -> str:
    """The family figure's parameter axis: the name with its unit."""
    if name == PITCH_RATE:
        return f"{name} [deg/s]"
    if name == "friction_coefficient":
        return f"{name} [-]"
    from ..analysis.sweep_points import axis_label

    return axis_label(name)[1]


def execute(args) -> int:
    import numpy as np

    from ..analysis.poincare import MapError
    from ..control.dispatch import ControllerStateError
    from ..presentation.family_plots import plot_family

    name, lo, hi = _vary(args.vary)
    robot, cparams = load_parameters(args.robot)
    say = progress_messages(args, NAME)
    if args.passive:
        if name != PITCH_RATE:
            raise UsageError(
                f"--vary {name!r} is not allowed with --passive: the passive family varies "
                f"{PITCH_RATE} (the apex pitch rate, deg/s)"
            )
        if args.controller != "table-i":
            raise UsageError("--controller is not allowed with --passive")
        refuse_given(
            args,
            CONTROLLED_ONLY,
            "with --passive (the passive family is followed by pseudo-arclength from its "
            "apex state, with no controller, floor or settling run)",
        )
        from ..analysis.passive_family import passive_family

        try:
            fam = passive_family(
                args.speed,
                args.apex_height,
                (math.radians(lo), math.radians(hi)),
                robot=robot,
                progress=say,
            )
        except MapError as exc:
            print(f"scoutsim {NAME}: {exc}", file=sys.stderr)
            return 1
        title = (
            f"passive family, apex speed {args.speed:g} m/s, height {args.apex_height:g} m "
            f"(pseudo-arclength; energy multiplier left out)"
        )
    else:
        refuse_given(args, PASSIVE_ONLY, "without --passive (the passive model's apex state)")
        from ..analysis.controlled_family import controlled_family

        law, cparams = controller_choice(args.controller, cparams)
        controller = make_controller(law, cparams, robot)
        try:
            fam = controlled_family(
                name,
                np.linspace(lo, hi, args.points),
                model=args.model,
                friction_coefficient=args.friction,
                robot=robot,
                controller=controller,
                settle_duration=args.duration,
                progress=say,
            )
        except ControllerStateError as exc:
            raise UsageError(
                f"--controller {args.controller}: {exc}; scoutsim continue restarts strides "
                "from section states, which include the controller's own state"
            ) from exc
        except ValueError as exc:
            raise UsageError(f"--vary {name!r}: {exc}") from exc
        title = f"Model {args.model} family (each orbit after settling from its neighbour)"
    paths = fam.save(args.out)
    found = [r for r in fam.rows if r["status"] == "ok"]
    if found:
        png = Path(args.out) / "family.png"
        plot_family(fam.rows, fam.parameter, title=title, path=png, label=_axis(fam.parameter))
        paths.append(png)
    summary = {
        "parameter": fam.parameter,
        "method": fam.method,
        "stopped": fam.stopped,
        "orbits": len(found),
        "values": len(fam.rows),
        "stable": sum(bool(r["stable"]) for r in found),
        "bifurcations": [
            {fam.parameter: r[fam.parameter], "bifurcation": r["bifurcation"]}
            for r in fam.bifurcations
        ],
        "files": [str(p) for p in paths],
    }
    if args.json:
        print(dumps(summary))
    else:
        _print_summary(summary)
    return 0 if found else 1


def _print_summary(s: dict) -> None:
    print(
        f"{s['orbits']} orbit(s) of {s['values']} along {s['parameter']} "
        f"({s['method']}; {s['stable']} stable; ended: {s['stopped']})"
    )
    for b in s["bifurcations"]:
        print(f"  {s['parameter']} = {b[s['parameter']]:.6g}: {b['bifurcation']}")
    for f in s["files"]:
        print(f"wrote {f}")
