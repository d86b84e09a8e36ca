"""The two family figures of docs/orbits.md ("Families of gaits"):

* the passive family in the apex pitch rate, 0 to 200 deg/s at apex speed 1.3 m/s and
  height 0.35 m, through the orbits the page tabulates (dotted lines), about 10 s;
* the controlled Model II family (Table I, default floor) in the front touchdown angle,
  17 to 27 deg in 0.25 deg steps, about 4 minutes.

    python tools/family_figures.py [--out docs/img] [--only passive|controlled] [--tables DIR]

Prints each family's summary and bifurcation rows; writes family_passive.png /
family_model_ii.png, and with --tables the branch tables (family_passive.csv,
family_model_ii.csv) into DIR.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from scoutsim.analysis.controlled_family import controlled_family
from scoutsim.analysis.passive_family import passive_family
from scoutsim.presentation.family_plots import plot_family


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/img")
    ap.add_argument("--only", choices=("passive", "controlled"))
    ap.add_argument("--tables", default=None, metavar="DIR")
    args = ap.parse_args()
    out = Path(args.out)
    if args.only in (None, "passive"):
        fam = passive_family(1.3, 0.35, (0.0, math.radians(200.0)))
        plot_family(
            fam.rows,
            fam.parameter,
            title="passive family, apex speed 1.3 m/s, height 0.35 m (energy multiplier left out)",
            marks=[(w, f"{w:g} deg/s (table)") for w in (50.0, 100.0, 150.0)],
            path=out / "family_passive.png",
        )
        _say(fam, args.tables, "family_passive.csv")
    if args.only in (None, "controlled"):
        fam = controlled_family(
            "controller.touchdown_angle_front_deg", np.arange(17.0, 27.001, 0.25), progress=print
        )
        plot_family(
            fam.rows,
            fam.parameter,
            title="Model II, Table I controller: the gait the robot settles on from its neighbour",
            path=out / "family_model_ii.png",
        )
        _say(fam, args.tables, "family_model_ii.csv")


def _say(fam, tables, name) -> None:
    if tables:
        Path(tables).mkdir(parents=True, exist_ok=True)
        fam.to_frame().to_csv(Path(tables) / name, index=False)
    found = [r for r in fam.rows if r["status"] == "ok"]
    several = sum(r["strides"] > 1 for r in found)
    stable = sum(bool(r["stable"]) for r in found)
    print(
        f"{fam.parameter}: {len(found)} orbits of {len(fam.rows)} rows ({stable} stable, "
        f"{several} cycles of several strides); {fam.stopped}"
    )
    lost = [r[fam.parameter] for r in fam.rows if r["status"] != "ok"]
    if lost:
        print(f"  no orbit at {lost}")
    for r in fam.bifurcations:
        print(f"  {r[fam.parameter]:.6g}: {r['bifurcation']}")


if __name__ == "__main__":
    main()
