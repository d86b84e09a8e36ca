"""Check that a change of the code leaves scoutsim's results bit for bit the same.

Runs a fixed set of 3 s scenarios (ideal, Model I, Model II with both integrators, from
three starts on the default floor and on a no-slip floor, and the massless passive model
from three orbit starts) and compares every recorded array (time, state, outputs, modes,
events) and the outcome with a reference saved from another commit. Where arrays differ,
it reports the largest difference and compares the gait metrics (to 1e-9, relative).

Usage::

    python tools/check_identical.py --base COMMIT    # reference from COMMIT (a temporary
                                                     # git worktree), then compare HEAD's
                                                     # working tree with it
    python tools/check_identical.py save REF.npz     # save this tree's results
    python tools/check_identical.py compare REF.npz  # compare this tree's results with them

``--base`` compiles the reference commit's Numba core in its worktree (minutes). Exit
status: 0 when every scenario is bit-identical, 1 otherwise.
"""

from __future__ import annotations

import argparse
import inspect
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

#: 3 s runs: (name, model, integrator method or None, start, floor friction)
STARTS = {
    "default": {},
    "nose_up": dict(y=0.33, theta=0.0, dx=0.8, dy=0.0, dtheta=1.5),
    "slow_nose_down": dict(y=0.37, theta=0.0, dx=0.5, dy=0.0, dtheta=math.radians(-30.0)),
}
FLOORS = {"mu1": 1.0, "noslip": math.inf}
MODELS = (("ideal", None), ("I", None), ("II", None), ("II", "dopri5"))
#: passive orbits: (forward speed [m/s], apex height [m], pitch rate [rad/s])
PASSIVE = (
    ("bound", 1.3, 0.35, math.radians(50.0)),
    ("pronk", 1.3, 0.35, 0.0),
    ("bound_fast", 1.6, 0.36, math.radians(60.0)),
)
DURATION = 3.0
ARRAYS = ("t", "state", "aux", "modes", "events")


def _simulate(scoutsim, robot, controller, init, model, method, friction, **kw):
    """simulate() across API versions: the floor as ``friction_coefficient=`` or as an
    environment object, whichever this tree's simulate() takes."""
    params = inspect.signature(scoutsim.simulate).parameters
    integrator = None
    if method is not None:
        integrator = scoutsim.IntegratorSettings(method=method)
    if "friction_coefficient" in params:
        kw["friction_coefficient"] = friction
    else:
        kw["environment"] = scoutsim.Environment(friction_coefficient=friction)
    if integrator is not None:
        kw["integrator"] = integrator
    return scoutsim.simulate(robot, controller, init, DURATION, model=model, **kw)


def run_scenarios() -> dict:
    """name -> {array name -> array, 'outcome' -> str, 'gait' -> metrics vector}."""
    import scoutsim
    from scoutsim.analysis.orbits import passive_bounding_orbit, passive_robot
    from scoutsim.state import InitialState

    out = {}
    for sname, start in STARTS.items():
        init = InitialState(**start)
        for fname, mu in FLOORS.items():
            for model, method in MODELS:
                name = f"{model}_{method or 'auto'}_{sname}_{fname}"
                r = _simulate(scoutsim, None, None, init, model, method, mu)
                out[name] = _record(r)
    for pname, speed, height, rate in PASSIVE:
        orb = passive_bounding_orbit(speed, height, rate)
        z = orb.z
        init = InitialState(y=z[0], theta=z[1], dx=z[2], dy=0.0, dtheta=z[3])
        r = _simulate(
            scoutsim,
            passive_robot(),
            None,
            init,
            "passive",
            None,
            math.inf,
            passive_touchdown_angles=orb.touchdown_angles,
        )
        out[f"passive_{pname}"] = _record(r)
    return out


def _record(r) -> dict:
    rec = {a: np.asarray(getattr(r, a)) for a in ARRAYS}
    rec["outcome"] = str(r.outcome)
    summary = r.summary()
    rec["gait"] = np.array(
        [
            np.nan if v is None else float(v)
            for v in summary.values()
            if v is None or isinstance(v, (int, float))
        ],
        dtype=float,
    )
    return rec


def save(path: Path) -> None:
    flat = {}
    for name, rec in run_scenarios().items():
        for key, val in rec.items():
            flat[f"{name}/{key}"] = np.asarray(val)
    np.savez(path, **flat)
    print(f"saved {len(flat)} arrays of {len(flat) // (len(ARRAYS) + 2)} scenarios to {path}")


def compare(path: Path) -> bool:
    ref = np.load(path)
    names = sorted({k.split("/")[0] for k in ref.files})
    cur = run_scenarios()
    all_same = True
    for name in names:
        if name not in cur:
            print(f"{name:40s} MISSING in this tree")
            all_same = False
            continue
        rec = cur[name]
        diffs = []
        for a in ARRAYS:
            x, y = np.asarray(rec[a]), ref[f"{name}/{a}"]
            if x.shape != y.shape:
                diffs.append(f"{a} shape {x.shape} vs {y.shape}")
            elif not np.array_equal(x, y, equal_nan=True):
                d = np.nanmax(np.abs(x.astype(float) - y.astype(float)))
                diffs.append(f"{a} max |diff| {d:.3g}")
        if str(rec["outcome"]) != str(ref[f"{name}/outcome"]):
            diffs.append(f"outcome {rec['outcome']} vs {ref[f'{name}/outcome']}")
        if not diffs:
            print(f"{name:40s} identical")
            continue
        all_same = False
        g, g0 = rec["gait"], ref[f"{name}/gait"]
        ok = np.allclose(g, g0, rtol=1e-9, atol=0.0, equal_nan=True)
        print(
            f"{name:40s} DIFFERENT: {'; '.join(diffs)}; gait metrics "
            f"{'agree to 1e-9' if ok else f'DIFFER {g} vs {g0}'}"
        )
    return all_same


def reference_from(commit: str, path: Path) -> None:
    """Save the results of ``commit`` (checked out in a git worktree under the temporary
    directory, kept for its compiled cache) to ``path``."""
    tree = Path(tempfile.gettempdir()) / f"scoutsim_ref_tree_{commit}"
    if not tree.exists():
        subprocess.run(
            ["git", "-C", str(ROOT), "worktree", "add", "--detach", str(tree), commit],
            check=True,
            capture_output=True,
        )
    env = dict(os.environ, PYTHONPATH=str(tree))
    subprocess.run(
        [sys.executable, str(Path(__file__).resolve()), "save", str(path)],
        check=True,
        cwd=str(tree),
        env=env,
    )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("action", nargs="?", choices=("save", "compare"))
    ap.add_argument("path", nargs="?", type=Path)
    ap.add_argument("--base", help="commit whose results are the reference")
    args = ap.parse_args(argv)
    if args.base:
        ref = Path(tempfile.gettempdir()) / f"scoutsim_ref_{args.base}.npz"
        if not ref.exists():
            reference_from(args.base, ref)
        return 0 if compare(ref) else 1
    if args.action is None or args.path is None:
        ap.error("give --base COMMIT, or save/compare with a path")
    if args.action == "save":
        save(args.path)
        return 0
    return 0 if compare(args.path) else 1


if __name__ == "__main__":
    sys.exit(main())
