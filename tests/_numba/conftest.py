"""The test that compiles the whole core afresh in a second process
(``test_compile_steps.py``, the core compiled without the compile-step replacements) starts
that process as soon as it can and runs last: the compile, a minute or two on one core,
overlaps other work instead of adding to the suite's time. On several workers the process
that starts them has started it already (``tests/conftest.py``); in one process it starts
when the session's tests are collected. The test waits for the process to end (however
long it takes, up to its timeout) and checks its result; a session that ends before the
test runs (``-x``, ``-k``) stops the process."""

import os

import pytest
from session_work import AS_IS_DIRECTORY, AS_IS_TEST, AsIsRun

_KEY = pytest.StashKey[dict]()


def pytest_collection_modifyitems(session, config, items):
    chosen = [item for item in items if item.name == AS_IS_TEST]
    if not chosen:
        return
    for item in chosen:
        items.remove(item)
        items.append(item)
    if os.environ.get(AS_IS_DIRECTORY):
        return  # started before the workers (tests/conftest.py)
    if hasattr(config, "workerinput"):
        return  # a worker that may not run the test: started by the fixture if it does
    config.stash[_KEY] = {"run": AsIsRun()}


def pytest_unconfigure(config):
    started = config.stash.get(_KEY, None)
    if started is not None:
        started["run"].close()


@pytest.fixture
def as_is_run(request):
    """The second process: started before the workers, at collection, or here."""
    if os.environ.get(AS_IS_DIRECTORY):
        return AsIsRun.attached(os.environ[AS_IS_DIRECTORY])
    started = request.config.stash.get(_KEY, None)
    if started is None:
        started = request.config.stash[_KEY] = {"run": AsIsRun()}
    return started["run"]
