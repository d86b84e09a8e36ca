"""In-process speed of this checkout against an earlier commit, measured in the same run.

    python benchmarks/bench_inprocess.py --base f72f8b0 [--processes 8] [--runs 21]
    python benchmarks/bench_inprocess.py --base-tree /path/to/worktree   # already built
    python benchmarks/bench_inprocess.py --base-tree ... --energy   # with the energy accounting

The job: 10 s of Model II from the default start on the default floor with the default
integrator, in one process after its compiled code is loaded (``scoutsim.simulate``), the
number the compile-time cuts (docs/model.md, "Compile time") must not make worse; with
``--energy``, with the work-energy accounting (``energy=True``) on both sides. The
base is checked out in a temporary git worktree and its compiled core built there first (a
few minutes). Then ``--processes`` processes per side run alternately (base, this, base, ...), pinned to one core, each timing ``--runs``
runs; a process's median is its figure. Between processes of the same code the median
moves by about 2 % (where the compiled code and data land in memory), more than between
most commits, so the verdict is the median over processes with their spread, and the
ratio this / base of those medians. Nothing here asserts.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

JOB = """
import statistics, sys, time
import scoutsim
scoutsim.simulate(duration=0.5, energy={energy})
ts = []
for _ in range({runs}):
    t0 = time.perf_counter()
    scoutsim.simulate(duration=10.0, model="II", energy={energy})
    ts.append(time.perf_counter() - t0)
print(statistics.median(ts), min(ts))
"""


def run_side(tree: Path, runs: int, core: int | None, energy: bool = False) -> tuple[float, float]:
    env = dict(os.environ, PYTHONPATH=str(tree))
    cmd = [sys.executable, "-c", JOB.format(runs=runs, energy=energy)]
    if core is not None and hasattr(os, "sched_setaffinity"):
        cmd = ["taskset", "-c", str(core)] + cmd
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True, cwd=tree)
    med, best = map(float, out.stdout.split())
    return med, best


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--base", help="commit to compare with (checked out in a worktree)")
    ap.add_argument("--base-tree", type=Path, help="an existing checkout of the base")
    ap.add_argument("--processes", type=int, default=8, help="processes per side")
    ap.add_argument("--runs", type=int, default=21, help="runs per process")
    ap.add_argument("--core", type=int, default=1, help="CPU to pin to (-1: none)")
    ap.add_argument(
        "--energy", action="store_true", help="runs with the energy accounting (energy=True)"
    )
    args = ap.parse_args()
    if (args.base is None) == (args.base_tree is None):
        ap.error("give --base COMMIT or --base-tree DIR")
    tmp = None
    base = args.base_tree
    if base is None:
        tmp = Path(tempfile.mkdtemp(prefix="scoutsim_base_"))
        base = tmp / "tree"
        subprocess.run(
            ["git", "-C", str(ROOT), "worktree", "add", "--detach", str(base), args.base],
            check=True,
            capture_output=True,
        )
    core = None if args.core < 0 else args.core
    try:
        for tree in (base, ROOT):  # build / load each side's compiled core
            print(f"preparing {tree} ...", file=sys.stderr, flush=True)
            run_side(tree, 1, core, args.energy)
        meds = {"base": [], "this": []}
        bests = {"base": [], "this": []}
        for i in range(args.processes):
            for side, tree in (("base", base), ("this", ROOT)):
                m, b = run_side(tree, args.runs, core, args.energy)
                meds[side].append(m)
                bests[side].append(b)
                print(
                    f"  process {i + 1} {side}: median {m * 1e3:.2f} ms, best {b * 1e3:.2f} ms",
                    flush=True,
                )
        print(
            f"10 s of Model II in one process{' with energy=True' if args.energy else ''}, "
            f"{args.processes} processes x {args.runs} runs per side"
        )
        for side in ("base", "this"):
            ms = [m * 1e3 for m in meds[side]]
            print(
                f"  {side:4s}: median over processes {statistics.median(ms):.2f} ms "
                f"(process medians {min(ms):.2f}-{max(ms):.2f}); best run "
                f"{min(bests[side]) * 1e3:.2f} ms"
            )
        ratio = statistics.median(meds["this"]) / statistics.median(meds["base"])
        print(
            f"  this / base: {ratio:.3f} (median over processes); best runs "
            f"{min(bests['this']) / min(bests['base']):.3f}"
        )
    finally:
        if tmp is not None:
            subprocess.run(
                ["git", "-C", str(ROOT), "worktree", "remove", "--force", str(base)],
                capture_output=True,
            )


if __name__ == "__main__":
    main()
