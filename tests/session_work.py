"""Work the test session does once, for all its tests, whether they run in one process or
on several workers (pytest-xdist, ``-n`` in pyproject.toml's ``addopts``).

- :func:`compile_the_core`: compile the run loop of each integration method, the carried
  derivatives' code and the right-hand side as the tests call it, before the workers
  start. On an empty cache every worker would otherwise compile the same functions at the
  same time (each a minute of CPU); compiled once here, the workers load them from the
  disk cache.
- :class:`AsIsRun`: the second process of ``tests/_numba/test_compile_steps.py``, which
  compiles the whole core afresh with Numba's compiler steps as they are. It is started
  once for the session (by the process that starts the workers, or by the single test
  process at collection) so that its minute or two of compiling overlaps other work, and
  the test reads its result from a directory (:data:`AS_IS_DIRECTORY`), whichever worker
  runs it.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import textwrap
import threading
import time
from pathlib import Path

#: the test that reads the second process's result
AS_IS_TEST = "test_the_core_compiled_without_the_replacements_runs_bit_for_bit_the_same"
#: the file of that test, relative to the tests' directory
AS_IS_FILE = Path("_numba") / "test_compile_steps.py"
#: the models the second process runs, and their duration [s]
AS_IS_MODELS = ("II", "I")
AS_IS_DURATION = 0.3
#: the longest the test waits for the second process [s] (it compiles the core: 1-3 min
#: alone, longer beside a busy suite)
AS_IS_TIMEOUT = 900.0
#: the environment variable through which workers find the directory of the second
#: process started before them (its results, and a file with its exit code once it ends)
AS_IS_DIRECTORY = "SCOUTSIM_TEST_AS_IS_DIR"

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


class AsIsRun:
    """The second process, started in a directory of its own: its results
    (``as_is.npz``), its stderr and, once it has ended, its exit code (``rc``, written by
    a thread of the process that started it). ``wait()`` returns (the exit code, stderr,
    the path of the ``.npz`` of every recorded column by ``"MODEL/column"``), from the
    process that started it or, by :meth:`attached`, from any other."""

    models = AS_IS_MODELS
    duration = AS_IS_DURATION

    def __init__(self, directory: Path | None = None):
        self._tmp = None
        self.process = None
        if directory is None:
            self._tmp = tempfile.TemporaryDirectory(prefix="scoutsim-as-is-")
            directory = Path(self._tmp.name)
            self._start(directory)
        self.dir = Path(directory)
        self.out = self.dir / "as_is.npz"

    @classmethod
    def attached(cls, directory: str) -> AsIsRun:
        """The run another process started in ``directory``."""
        return cls(Path(directory))

    def _start(self, root: Path) -> None:
        env = dict(os.environ, SCOUTSIM_NUMBA_AS_IS="1", NUMBA_CACHE_DIR=str(root / "cache"))
        env.pop(AS_IS_DIRECTORY, None)
        with open(root / "stderr.txt", "w") as stderr:
            self.process = subprocess.Popen(
                [
                    sys.executable,
                    "-c",
                    _RUN,
                    str(root / "as_is.npz"),
                    str(AS_IS_DURATION),
                    ",".join(AS_IS_MODELS),
                ],
                env=env,
                stdout=subprocess.DEVNULL,
                stderr=stderr,
            )
        process = self.process

        def note_the_end():
            rc = process.wait()
            (root / "rc.tmp").write_text(str(rc))
            os.replace(root / "rc.tmp", root / "rc")

        threading.Thread(target=note_the_end, daemon=True, name="as-is-run").start()

    def wait(self):
        rc_file = self.dir / "rc"
        deadline = time.monotonic() + AS_IS_TIMEOUT
        while not rc_file.exists():
            if time.monotonic() > deadline:
                raise TimeoutError(f"the second process did not end in {AS_IS_TIMEOUT:.0f} s")
            time.sleep(0.5)
        stderr = (self.dir / "stderr.txt").read_text()
        return int(rc_file.read_text()), stderr, self.out

    def close(self):
        if self.process is not None and self.process.poll() is None:
            self.process.kill()
            self.process.wait()
        if self._tmp is not None:
            self._tmp.cleanup()


def as_is_test_selected(config) -> bool:
    """Whether the session's command line selects the second process's test, as far as
    it can be told before collection: no ``-k`` or ``-m``, and a path argument (or the
    configured test paths) that is the test's file, or a directory holding it."""
    if config.option.keyword or config.option.markexpr:
        return False
    tests = Path(__file__).resolve().parent
    target = tests / AS_IS_FILE
    args = config.args or [str(tests)]
    for arg in args:
        path = Path(arg.split("::")[0])
        if not path.is_absolute():
            path = Path(config.invocation_params.dir) / path
        path = path.resolve()
        if path == target or path in target.parents:
            if "::" not in arg or arg.endswith("::" + AS_IS_TEST):
                return True
    return False


def compile_the_core() -> None:
    """Compile (or load from the disk cache) what the tests compile: the run loop of each
    integration method, the carried derivatives' code (the operations' and DOPRI5's
    flow), and the right-hand side called from Python; in two processes side by side
    (Numba compiles on one core, and writes each cache file whole under a temporary name
    before renaming it, so two processes may write the same one): this one compiles the
    ARK3 and ARK4 run loops and the right-hand side called from Python, a second one the
    rest (:func:`compile_part`), which this one
    compiles itself after them if the second one failed."""
    helper = subprocess.Popen(
        [sys.executable, str(Path(__file__).resolve()), "rest"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        compile_part("loops")
    finally:
        rc = helper.wait()
    if rc != 0:
        compile_part("rest")


def compile_part(part: str) -> None:
    """Part ``part`` of :func:`compile_the_core`: "loops", the ARK3 and ARK4 run loops and
    the right-hand side called from Python; "rest", the DOPRI5 run loop, the carried
    derivatives' operations and DOPRI5's flow (every orbit's; ARK3's flow is carried by a
    few tests only, which compile it beside the other worker's tests)."""
    import numpy as np

    import scoutsim
    from scoutsim.simulation.engine import start_engine
    from scoutsim.simulation.integrator import IntegratorSettings

    if part == "loops":
        for method in ("ark3", "ark4"):
            scoutsim.simulate(
                duration=0.01, model="II", integrator=IntegratorSettings(method=method)
            )
        _right_hand_side_from_python()
        return
    scoutsim.simulate(duration=0.01, model="II", integrator=IntegratorSettings(method="dopri5"))
    e = start_engine(None, 1.0, model="II", integrator=IntegratorSettings(method="dopri5"))
    e.carry_sensitivities(np.eye(e.sensitivities.shape[0])[:, :1])
    e.advance(2)


def _right_hand_side_from_python() -> None:
    """The right-hand side called from Python (the model's tests)."""
    import numpy as np

    import scoutsim
    from scoutsim._core.model import evaluate as D
    from scoutsim._core.model import layout as L
    from scoutsim._core.model import workspace as W
    from scoutsim._core.model.packing import robot_array

    s = np.zeros(L.NS)
    P = robot_array(scoutsim.RobotParameters(), "II")
    mi = np.zeros(L.NMI, dtype=np.int64)
    mf = np.zeros(L.NMF)
    wk, wA, piv = W.new_eval_workspace()
    st = np.zeros((L.NS, 2 * D.NSTIFF))
    D.evaluate_ws(s, P, mi, mf, np.zeros(2), np.zeros(L.NS), np.zeros(L.NAUX),
                  (wk, wA, piv, st), True, st, True)  # fmt: skip
    D.evaluate(s, P, mi, mf, np.zeros(2), np.zeros(L.NS), np.zeros(L.NAUX))


if __name__ == "__main__":
    compile_part(sys.argv[1])
