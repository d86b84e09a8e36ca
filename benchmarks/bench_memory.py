"""Memory benchmark: a 60 s Model II run keeps its full time series under 100 MB, and a
run streamed to disk needs the same memory whatever its duration.

    python benchmarks/bench_memory.py

Prints the bytes held by the result's arrays and the peak traced allocation during the run
(tracemalloc), against the 100 MB target and against one float64 state copy per sample
(the baseline a plain solver that stores only the state would need); then the peak of
runs of 60 s and 600 s held in memory and streamed (``simulate(stream_to=...)``, the
default 60 s kept in memory), measured in the same run.
"""

import tempfile
import time
import tracemalloc

import scoutsim


def main():
    scoutsim.simulate(duration=0.01, model="II")  # compile outside the trace
    tracemalloc.start()
    t0 = time.perf_counter()
    r = scoutsim.simulate(duration=60.0, model="II", friction_coefficient=0.8)
    wall = time.perf_counter() - t0
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    held = sum(a.nbytes for a in (r.t, r.state, r.aux, r.modes, r.events))
    state_only = r.state.nbytes
    print(f"60 s Model II: outcome {r.outcome}, {len(r.t)} samples, wall {wall:.1f} s")
    print(f"result arrays held      {held / 1e6:8.1f} MB   target < 100 MB")
    print(f"peak traced during run  {peak / 1e6:8.1f} MB")
    print(f"state-only baseline     {state_only / 1e6:8.1f} MB   ratio {held / state_only:.2f}")
    print("peak traced memory [MB]   held in memory   streamed to disk")
    with tempfile.TemporaryDirectory() as tmp:
        for duration in (60.0, 600.0):
            peaks = []
            for kw in ({}, {"stream_to": f"{tmp}/run{duration:g}"}):
                tracemalloc.start()
                scoutsim.simulate(duration=duration, model="II", **kw)
                peaks.append(tracemalloc.get_traced_memory()[1] / 1e6)
                tracemalloc.stop()
            print(f"  {duration:5.0f} s run           {peaks[0]:10.1f}   {peaks[1]:16.1f}")


if __name__ == "__main__":
    main()
