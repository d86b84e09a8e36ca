"""The test that compiles the whole core afresh in a second process
(``test_compile_steps.py``, the core compiled without the compile-step replacements) starts
that process as soon as the session's tests are collected and runs last: the compile, a
minute or two on one core, overlaps the rest of the suite on the machine's other core
instead of adding to the suite's time. The test waits for the process to finish (however
long it takes, up to its timeout) and checks its result; a session that ends before the
test runs (``-x``, ``-k``) stops the process."""

import os
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

import pytest

#: the test that reads the second process's result
AS_IS_TEST = "test_the_core_compiled_without_the_replacements_runs_bit_for_bit_the_same"
#: the models the second process runs, and their duration [s]
AS_IS_MODELS = ("II", "I")
AS_IS_DURATION = 0.3
#: the longest the test waits for the second process [s] (it compiles the core: 1-3 min)
AS_IS_TIMEOUT = 900.0

_RUN = textwrap.dedent("""
    import sys
    import numpy as np
    import scoutsim
    from scoutsim._numba import jit
    from scoutsim._numba import compile_steps
    # the replacements are off in this process
    assert all(v.startswith("off") for v in compile_steps.status().values()), jit.status()
    out = {}
    for model in sys.argv[3].split(","):
        r = scoutsim.simulate(duration=float(sys.argv[2]), model=model)
        out.update({f"{model}/{k}": np.asarray(v) for k, v in r.columns().items()})
    np.savez(sys.argv[1], **out)
""")

_KEY = pytest.StashKey[dict]()


class AsIsRun:
    """The second process: ``wait()`` returns (its return code, stderr, the path of its
    ``.npz`` of every recorded column by ``"MODEL/column"``)."""

    models = AS_IS_MODELS
    duration = AS_IS_DURATION

    def __init__(self):
        self.dir = tempfile.TemporaryDirectory(prefix="scoutsim-as-is-")
        root = Path(self.dir.name)
        self.out = root / "as_is.npz"
        self.stderr = open(root / "stderr.txt", "w+")  # noqa: SIM115 (closed by close())
        env = dict(os.environ, SCOUTSIM_NUMBA_AS_IS="1", NUMBA_CACHE_DIR=str(root / "cache"))
        self.process = subprocess.Popen(
            [
                sys.executable,
                "-c",
                _RUN,
                str(self.out),
                str(AS_IS_DURATION),
                ",".join(AS_IS_MODELS),
            ],
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=self.stderr,
        )

    def wait(self):
        rc = self.process.wait(timeout=AS_IS_TIMEOUT)
        self.stderr.seek(0)
        return rc, self.stderr.read(), self.out

    def close(self):
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait()
        self.stderr.close()
        self.dir.cleanup()


def pytest_collection_modifyitems(session, config, items):
    chosen = [item for item in items if item.name == AS_IS_TEST]
    if not chosen:
        return
    for item in chosen:
        items.remove(item)
        items.append(item)
    config.stash[_KEY] = {"run": AsIsRun()}


def pytest_unconfigure(config):
    started = config.stash.get(_KEY, None)
    if started is not None:
        started["run"].close()


@pytest.fixture
def as_is_run(request):
    """The second process started at collection (started here if it was not)."""
    started = request.config.stash.get(_KEY, None)
    if started is None:
        started = request.config.stash[_KEY] = {"run": AsIsRun()}
    return started["run"]
