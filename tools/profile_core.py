"""Where the compiled core spends its time: a `perf` profile of warm runs, by compiled
function.

    perf record -F 2000 -o core.data python tools/profile_core.py [--runs 300] [--no-energy]
    perf report -i core.data --no-children --sort dso,symbol -g none --stdio | grep -e JIT -e libm

Numba's machine code lives in anonymous memory, so `perf` cannot name it. This script
compiles the core in its own process (into an empty cache directory, so that every
function's LLVM module is at hand: code loaded from the on-disk cache has none), writes
the address and size of every compiled function to ``/tmp/perf-<pid>.map`` (the map
`perf report` reads for code it has no file for), then runs ``--runs`` times 10 s of
Model II with the default settings. The compile takes about a minute and dominates the
samples; the report's ``[JIT]`` rows and libm are the runs. A function's inlined helpers
count as its own time (``evaluate_ws`` includes the projection, mass matrix, actuators,
contact rows and KKT solve; ``step3`` the ARK3 stage sums and, with the energy accounting,
the stages' power flows).

To see the hot instructions of one function, ``--dump NAME`` writes the machine code of
the first compiled function whose symbol contains NAME to ``/tmp/<NAME>.bin`` after the
runs (``objdump -D -b binary -m i386:x86-64 /tmp/NAME.bin``); the offsets of the samples
within it are the sampled addresses (``perf script -F ip,sym``) less the function's
address in the map.
"""

from __future__ import annotations

import argparse
import ctypes
import gc
import os
import re
import sys
import tempfile
import time


def compiled_functions() -> list[tuple[int, str, object]]:
    """(address, symbol, library) of every compiled function of the loaded dispatchers
    that has its LLVM module (compiled in this process)."""
    from numba.core.registry import CPUDispatcher

    found: dict[int, tuple[str, object]] = {}
    seen: set[int] = set()
    for obj in gc.get_objects():
        if not isinstance(obj, CPUDispatcher):
            continue
        for cres in obj.overloads.values():
            lib = cres.library
            if id(lib) in seen:
                continue
            seen.add(id(lib))
            try:
                module = lib._final_module
            except AttributeError:  # loaded from a cache: no module
                continue
            for f in module.functions:
                if f.is_declaration:
                    continue
                address = lib.get_pointer_to_function(f.name)
                if address:
                    found[address] = (f.name, lib)
    return sorted((a, n, lib) for a, (n, lib) in found.items())


def readable(symbol: str) -> str:
    """The qualified name of a Numba symbol (``_ZN8scoutsim5_core...evaluate_wsB3v...``:
    ``scoutsim._core...evaluate_ws``), its wrapper marked."""
    wrapper = symbol.startswith("_ZN7cpython")
    body = symbol[len("_ZN7cpython") if wrapper else len("_ZN") :]
    parts = []
    while True:
        m = re.match(r"(\d+)", body)
        if not m:
            break
        n = int(m.group(1))
        start = len(m.group(1))
        parts.append(body[start : start + n])
        body = body[start + n :]
    name = ".".join(parts) or symbol[:80]
    return ("cpython wrapper of " if wrapper else "") + name


def write_map(functions) -> str:
    path = f"/tmp/perf-{os.getpid()}.map"
    with open(path, "w") as fh:
        for i, (address, symbol, _) in enumerate(functions):
            end = functions[i + 1][0] if i + 1 < len(functions) else address + 4096
            fh.write(f"{address:x} {min(end - address, 1 << 20):x} {readable(symbol)}\n")
    return path


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=300, help="10 s runs to profile")
    ap.add_argument("--no-energy", action="store_true", help="runs without energy accounting")
    ap.add_argument("--dump", metavar="NAME", help="write one function's machine code")
    args = ap.parse_args()
    os.environ["NUMBA_CACHE_DIR"] = tempfile.mkdtemp(prefix="scoutsim_profile_")
    import scoutsim

    energy = not args.no_energy
    t0 = time.perf_counter()
    scoutsim.simulate(duration=0.5, energy=energy)
    functions = compiled_functions()
    path = write_map(functions)
    print(
        f"compiled in {time.perf_counter() - t0:.0f} s; {len(functions)} functions in {path}",
        file=sys.stderr,
    )
    t0 = time.perf_counter()
    for _ in range(args.runs):
        scoutsim.simulate(duration=10.0, energy=energy)
    per_run = (time.perf_counter() - t0) / args.runs
    print(f"{args.runs} runs of 10 s, {1e3 * per_run:.1f} ms each", file=sys.stderr)
    if args.dump:
        for i, (address, symbol, _) in enumerate(functions):
            if args.dump in symbol and not symbol.startswith("_ZN7cpython"):
                end = functions[i + 1][0] if i + 1 < len(functions) else address + 4096
                out = f"/tmp/{args.dump}.bin"
                with open(out, "wb") as fh:
                    fh.write(ctypes.string_at(address, end - address))
                print(f"{readable(symbol)} at {address:x}: {out}", file=sys.stderr)
                break


if __name__ == "__main__":
    main()
