"""Memory benchmark: a 60 s Model II run keeps its full time series under 100 MB.

    python benchmarks/bench_memory.py

Prints the bytes held by the result's arrays and the peak traced allocation during the run
(tracemalloc), against the 100 MB target and against one float64 state copy per sample
(the baseline a plain solver that stores only the state would need).
"""

import time
import tracemalloc

import scoutsim


def main():
    scoutsim.simulate(duration=0.01, model="II")            # compile outside the trace
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


if __name__ == "__main__":
    main()
