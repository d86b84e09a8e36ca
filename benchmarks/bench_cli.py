"""End-to-end benchmark of the command line: what a user waits for.

    python benchmarks/bench_cli.py [--venv DIR] [--repeat 3]

Measures in one run, each command in a new process, as a user types it:

* install: a fresh venv and ``pip install -e REPO`` (the README's first command; reported,
  not a target), unless ``--venv`` names an existing one;
* first run: ``scoutsim run --plots`` (10 s of Model II with its figures, the README's main
  job) with an empty Numba cache (``NUMBA_CACHE_DIR`` set to a new directory), compilation
  included;
* warm runs from the cache the first run filled: ``scoutsim run --duration 1``,
  ``--duration 10`` and ``--duration 61`` (median of ``--repeat``), tables and summary
  written as by default;
* the end-to-end real-time factor (61 s - 1 s) / (wall(61 s) - wall(1 s));
* baselines measured in the same run: the start-up floor of any Numba program in that venv
  (``python -c "import numba, scipy.linalg"``) and the simulator's own speed, 10 s of
  Model II repeated in one process (best of ``--repeat``).

The targets (docs/explanation/performance.md) are printed next to the measurements (first run <= 60 s,
warm 1 s run <= 1.0 s, warm 10 s run <= 1.5 s, end-to-end real-time factor >= 100); nothing asserts.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def timed(cmd, env=None, cwd=None) -> float:
    t0 = time.perf_counter()
    subprocess.run(
        cmd, env=env, cwd=cwd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
    )
    return time.perf_counter() - t0


def verdict(ok: bool) -> str:
    return "meets" if ok else "MISSES"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--venv",
        type=Path,
        default=None,
        help="use this venv (scoutsim installed) instead of a fresh one",
    )
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        if args.venv is None:
            venv = tmp / "venv"
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
            subprocess.run(
                [str(venv / "bin" / "pip"), "install", "-q", "-e", str(REPO)], check=True
            )
            print(
                f"install (fresh venv, pip install -e .)   {time.perf_counter() - t0:7.1f} s",
                flush=True,
            )
        else:
            venv = args.venv
        py = str(venv / "bin" / "python")
        scoutsim = str(venv / "bin" / "scoutsim")
        env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp / "numba_cache"))

        first = timed([scoutsim, "run", "--plots", "--out", str(tmp / "first")], env=env)
        print(
            f"first `scoutsim run --plots` (empty cache) {first:6.1f} s   target <= 60 s: "
            f"{verdict(first <= 60.0)}",
            flush=True,
        )

        walls = {}
        for duration in (1, 10, 61):
            walls[duration] = statistics.median(
                timed(
                    [
                        scoutsim,
                        "run",
                        "--duration",
                        str(duration),
                        "--out",
                        str(tmp / f"warm{duration}"),
                    ],
                    env=env,
                )
                for _ in range(args.repeat)
            )
        rtf = (61 - 1) / (walls[61] - walls[1])
        print(
            f"warm `scoutsim run --duration 1`          {walls[1]:7.2f} s   target <= 1.0 s: "
            f"{verdict(walls[1] <= 1.0)}"
        )
        print(
            f"warm `scoutsim run` (10 s)                {walls[10]:7.2f} s   target <= 1.5 s: "
            f"{verdict(walls[10] <= 1.5)}"
        )
        print(f"warm `scoutsim run --duration 61`         {walls[61]:7.2f} s")
        print(
            f"end-to-end real-time factor (61-1)/(w61-w1) {rtf:5.0f}x    target >= 100: "
            f"{verdict(rtf >= 100.0)}"
        )

        floor = statistics.median(
            timed([py, "-c", "import numba, scipy.linalg"], env=env) for _ in range(args.repeat)
        )
        code = (
            "import time, scoutsim; scoutsim.simulate(duration=0.01); w = []\n"
            f"for _ in range({args.repeat}):\n"
            "    t = time.perf_counter(); scoutsim.simulate(duration=10.0); "
            "w.append(time.perf_counter() - t)\n"
            "print(min(w))"
        )
        out = subprocess.run([py, "-c", code], env=env, check=True, capture_output=True, text=True)
        inproc = float(out.stdout.split()[-1])
        print(
            f"baseline: start-up floor (import numba, scipy.linalg) {floor:5.2f} s; the warm "
            f"1 s run takes {walls[1] / floor:.1f}x that"
        )
        print(
            f"baseline: 10 s of Model II in one process {inproc * 1e3:7.1f} ms (real-time "
            f"factor {10.0 / inproc:.0f}x); the command's marginal cost per simulated "
            f"second is {(walls[61] - walls[1]) / 60 / (inproc / 10):.1f}x the simulator's"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
