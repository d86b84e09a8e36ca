"""scoutsim leaves other Numba users of a process alone (scoutsim._numba): foreign compiled
code (IR-level inlining, an ``overload`` with ``inline="always"``, literal arguments, a call
into one of scoutsim's compiled functions) gives the same results in a process where
scoutsim was imported and ran its compiled core as in one where it was never imported, and
Numba's own methods are in place there once scoutsim's compile is over."""

import json
import subprocess
import sys
import textwrap

import scoutsim

#: foreign Numba code, compiled in a fresh process (nothing cached on disk): functions that
#: inline at the IR level, an always-inlined overload, literal dispatch and a literal
#: argument; prints the results as JSON (floats as their hex form: bit for bit)
_FOREIGN = textwrap.dedent("""
    import numba
    import numpy as np
    from numba import literally, njit, types
    from numba.extending import overload

    @njit(inline="always")
    def leaf(x, k):
        return x * k + 0.25

    def twice(x):
        pass

    @overload(twice, inline="always")
    def _twice(x):
        if isinstance(x, types.Float):
            def impl(x):
                return leaf(x, 2.0) + leaf(x, 2.0)
            return impl

    @njit
    def power(x, n):
        return x ** literally(n)

    @njit
    def branchy(x, flag):
        if flag:
            return leaf(x, 3.0)
        return leaf(x, -3.0)

    @njit
    def foreign(a):
        s = 0.0
        for i in range(a.shape[0]):
            s += twice(a[i]) + branchy(a[i], True) + branchy(a[i], False) + power(a[i], 3)
        return s

    a = np.linspace(-1.0, 2.0, 7)
    results = {"foreign": foreign(a), "branchy": branchy(1.5, True), "power": power(1.1, 2),
               "signatures": [str(s) for s in power.signatures]}
""")

_WITHOUT_SCOUTSIM = _FOREIGN + textwrap.dedent("""
    import json, sys
    assert not any(m.startswith("scoutsim") for m in sys.modules)
    print(json.dumps({k: v.hex() if isinstance(v, float) else v for k, v in results.items()}))
""")

#: scoutsim imported, its core run (compiled or loaded from the cache), a compiled function
#: of scoutsim's compiled inside foreign code, then the foreign code; Numba's methods
#: before scoutsim's import and after compared by identity, and what was in place while
#: the foreign functions compiled
_WITH_SCOUTSIM = (
    textwrap.dedent("""
    import json, sys
    from numba.core import caching, dispatcher, inline_closurecall, targetconfig, event
    from numba.core.registry import CPUDispatcher

    def numba_methods():
        return {
            "TargetConfig.__hash__": targetconfig.TargetConfig.__hash__,
            "InlineWorker.inline_ir": inline_closurecall.InlineWorker.inline_ir,
            "InlineWorker.inline_function": inline_closurecall.InlineWorker.inline_function,
            "Dispatcher.get_call_template": dispatcher.Dispatcher.get_call_template,
            "Dispatcher.compile": dispatcher.Dispatcher.compile,
            "CPUDispatcher.get_call_template": CPUDispatcher.get_call_template,
            "CPUDispatcher.compile": CPUDispatcher.compile,
        }

    before = numba_methods()
    locators = list(caching.CacheImpl._locator_classes)
    import scoutsim
    from scoutsim._numba import compile_steps
    scoutsim.simulate(duration=0.05)
    compile_probe = {}

    class Probe(event.Listener):
        def on_start(self, ev):
            name = ev.data["dispatcher"].py_func.__name__
            compile_probe.setdefault(name, compile_steps.in_place())

        def on_end(self, ev):
            pass

    event.register("numba:compile", Probe())
""")
    + _FOREIGN
    + textwrap.dedent("""
    from numba import njit
    from scoutsim._core.model.sensor_readings import uniform01

    @njit
    def calls_scoutsim(seed):
        return uniform01(seed, 3) + uniform01(seed, 4)

    results["calls_scoutsim"] = calls_scoutsim(7)
    results["uniform01"] = uniform01(7, 3) + uniform01(7, 4)
    after = numba_methods()
    moved = sorted(k for k in before if after[k] is not before[k])
    extra = [c.__name__ for c in caching.CacheImpl._locator_classes if c not in locators]
    out = {k: v.hex() if isinstance(v, float) else v for k, v in results.items()}
    out.update(moved=moved, extra_locators=extra, compile_probe=compile_probe)
    print(json.dumps(out))
""")
)


def _run(script: str) -> dict:
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr[-3000:]
    return json.loads(p.stdout.strip().splitlines()[-1])


def test_foreign_numba_code_is_unaffected_by_scoutsim():
    """Foreign functions compile to the same results, bit for bit, with and without
    scoutsim in the process; while they compile scoutsim's replacements are not in place,
    and afterwards Numba's methods are the very objects they were before scoutsim was
    imported. The only addition to Numba is the cache locator that answers for scoutsim's
    own files."""
    scoutsim.simulate(duration=0.05)  # the core in the cache: the subprocess loads it
    without = _run(_WITHOUT_SCOUTSIM)
    with_ = _run(_WITH_SCOUTSIM)
    for k in ("foreign", "branchy", "power", "signatures"):
        assert with_[k] == without[k], k
    # the literal argument kept its literal dispatch (not widened by scoutsim's typing)
    assert any("Literal" in s for s in without["signatures"])
    # a check of the foreign results themselves (x*k + 0.25 and x**3, summed)
    import numpy as np

    a = np.linspace(-1.0, 2.0, 7)
    expect = sum(2 * (2 * x + 0.25) + (3 * x + 0.25) + (-3 * x + 0.25) + x**3 for x in a)
    assert abs(float.fromhex(without["foreign"]) - expect) < 1e-12
    assert with_["calls_scoutsim"] == with_["uniform01"]  # scoutsim's, called from foreign code
    assert with_["moved"] == []
    assert with_["extra_locators"] == ["_CoreCacheLocator"]
    probe = with_["compile_probe"]
    for name in ("foreign", "branchy", "power", "calls_scoutsim", "_twice", "impl"):
        if name in probe:
            assert probe[name] is False, (name, probe)
    assert {"foreign", "branchy", "power", "calls_scoutsim"} <= set(probe)
    # scoutsim's own function, if compiled (not loaded from the cache) while typing the
    # foreign caller, was compiled in the context
    for name in ("uniform01", "_mix64"):
        if name in probe:
            assert probe[name] is True, (name, probe)
