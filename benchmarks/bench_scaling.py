"""How the cost of a run grows with its length: ``scoutsim run`` and ``simulate()`` at
10, 60, 600 and 3600 s simulated, in one run.

    python benchmarks/bench_scaling.py [--durations 10 60 600 3600] [--model II]
                                       [--record-rate HZ]

Each measurement is a new process, the compiled core warm (a 1 s run first fills the
cache):

* ``scoutsim run --duration D --out DIR`` as a user types it (default options: tables,
  summary, no figures; a run over the memory budget streams): wall time of the process,
  its peak resident memory (``ru_maxrss`` of the child), the size of what it wrote and
  whether it streamed;
* ``simulate(duration=D, model=..., energy=True)`` and the run's ``summary()`` (the gait
  analysis) in a process of their own: the wall time of each inside the process, and the
  process's peak memory.

``--record-rate HZ`` runs both at that record rate (``--record-rate``, ``record_rate=``).
Then the marginal cost, wall time per added simulated second with the start-up excluded,
between consecutive durations, and the ratio of the last interval's to the one before
(the target: within 1.3x, the cost per simulated second not growing with the run's
length), for both. Prints the machine and its load; asserts nothing.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from machine import machine

#: the in-process measurement: simulate, then its summary, timed inside the process
_IN_PROCESS = """
import json, resource, sys, time
import scoutsim
d, model = float(sys.argv[1]), sys.argv[2]
rate = float(sys.argv[3]) if len(sys.argv) > 3 else None
t0 = time.perf_counter()
r = scoutsim.simulate(duration=d, model=model, energy=True, record_rate=rate)
t1 = time.perf_counter()
s = r.summary()
t2 = time.perf_counter()
print(json.dumps({"simulate_s": t1 - t0, "summary_s": t2 - t1, "outcome": r.outcome,
                  "strides": s.get("n_strides"),
                  "peak_gb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6}))
"""


def cli_run(duration: float, model: str, scratch: Path, rate: float | None) -> dict:
    out = scratch / f"run_{duration:g}"
    argv = [
        sys.executable,
        "-m",
        "scoutsim",
        "run",
        "--duration",
        f"{duration:g}",
        "--model",
        model,
        "--out",
        str(out),
        "--quiet",
        "--no-progress",
    ] + ([] if rate is None else ["--record-rate", f"{rate:g}"])
    t0 = time.perf_counter()
    p = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    _, status, usage = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    err = p.stderr.read() if p.stderr else ""
    if os.waitstatus_to_exitcode(status) != 0:
        raise RuntimeError(f"{' '.join(argv)} failed:\n{err[-2000:]}")
    size = sum(f.stat().st_size for f in out.rglob("*") if f.is_file())
    streamed = json.loads((out / "manifest.json").read_text()).get("streamed")
    shutil.rmtree(out, ignore_errors=True)
    return {
        "wall_s": wall,
        "peak_gb": usage.ru_maxrss / 1e6,
        "output_mb": size / 1e6,
        "streamed": streamed,
    }


def in_process(duration: float, model: str, rate: float | None = None) -> dict:
    argv = [sys.executable, "-c", _IN_PROCESS, f"{duration:g}", model]
    argv += [] if rate is None else [f"{rate:g}"]
    p = subprocess.run(argv, capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(f"simulate({duration:g} s) failed:\n{p.stderr[-2000:]}")
    return json.loads(p.stdout.strip().splitlines()[-1])


def marginal(durations, walls) -> list[float]:
    """Wall time per added simulated second [ms/s] between consecutive durations."""
    return [
        1e3 * (walls[i + 1] - walls[i]) / (durations[i + 1] - durations[i])
        for i in range(len(durations) - 1)
    ]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--durations", type=float, nargs="+", default=[10.0, 60.0, 600.0, 3600.0])
    ap.add_argument("--model", default="II")
    ap.add_argument("--record-rate", type=float, default=None, metavar="HZ")
    args = ap.parse_args(argv)
    durations = sorted(args.durations)
    print(f"machine: {machine()}; load average {os.getloadavg()}", flush=True)
    if args.record_rate is not None:
        print(f"record rate {args.record_rate:g} Hz", flush=True)
    in_process(1.0, args.model)  # the compiled core warm in the cache
    cli, sim = [], []
    with tempfile.TemporaryDirectory(prefix="bench_scaling_") as tmp:
        for d in durations:
            c = cli_run(d, args.model, Path(tmp), args.record_rate)
            s = in_process(d, args.model, args.record_rate)
            cli.append(c)
            sim.append(s)
            print(
                f"{d:7g} s: scoutsim run {c['wall_s']:8.2f} s (real-time factor "
                f"{d / c['wall_s']:6.1f}), peak {c['peak_gb']:.2f} GB, output "
                f"{c['output_mb']:.0f} MB{' (streamed)' if c['streamed'] else ''} | simulate {s['simulate_s']:7.2f} s + summary "
                f"{s['summary_s']:6.2f} s ({s['strides']} strides), peak {s['peak_gb']:.2f} GB",
                flush=True,
            )
    for name, walls in (
        ("scoutsim run", [c["wall_s"] for c in cli]),
        ("simulate + summary", [s["simulate_s"] + s["summary_s"] for s in sim]),
        ("summary alone", [s["summary_s"] for s in sim]),
    ):
        m = marginal(durations, walls)
        spans = ", ".join(
            f"{durations[i]:g}-{durations[i + 1]:g} s: {v:.2f} ms/s" for i, v in enumerate(m)
        )
        ratio = f"; last / previous {m[-1] / m[-2]:.2f}x" if len(m) >= 2 and m[-2] > 0 else ""
        print(f"marginal cost, {name}: {spans}{ratio}")
    print(f"load average at the end {os.getloadavg()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
