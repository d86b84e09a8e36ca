"""What a parallel run can send to its workers (scoutsim.analysis.parallel): a trial
pickle refuses, before any task runs, a lambda, a closure, an object holding a lock, a
function of a module a worker cannot import by name; a compiled controller pickles by its
function's name and runs the same law after the round trip; a run stopped by a result
(``stop_when``) keeps what arrived and runs nothing more in one process."""

import importlib.util
import pickle
import sys
import threading

import numpy as np
import pytest

from scoutsim.analysis.parallel import (
    NotSendableError,
    check_sendable,
    map_tasks,
    unsendable_reason,
)
from scoutsim.control import CompiledController


def _double(task):
    return 2 * task


def _hold(t, y, params, state, torque, leg_states):
    torque[0] = params[0] * y[0]
    torque[1] = -params[0]
    return 0


class _Holder:
    def __init__(self, thing):
        self.thing = thing


def test_a_module_level_function_and_a_compiled_controller_can_be_sent():
    assert unsendable_reason(_double) is None
    c = CompiledController(_hold, params=[2.0], state=[1.0, 2.0], control_period=2e-3, name="hold")
    c.extra = "a subclass's attribute"
    assert unsendable_reason(c) is None
    copy = pickle.loads(pickle.dumps(c))
    assert copy.command_function is _hold and copy.name == "hold"
    assert copy.control_period == 2e-3 and copy.extra == c.extra
    assert np.array_equal(copy.params, c.params)
    assert np.array_equal(copy.initial_state, c.initial_state)
    assert copy.address == c.address  # the same function: compiled once per process


def _local():
    def inner(task):
        return task

    return inner


@pytest.mark.parametrize(
    "obj, words",
    [
        (lambda task: task, "lambda"),
        (_local(), "defined inside a function"),
        (_Holder(threading.Lock()), "does not pickle"),
    ],
)
def test_what_cannot_be_sent_is_named(obj, words):
    assert words in unsendable_reason(obj)
    with pytest.raises(NotSendableError, match=f"the thing cannot be sent.*{words}.*workers=1"):
        check_sendable(obj, "the thing")


def test_a_module_a_worker_cannot_import_by_name_is_refused(tmp_path, monkeypatch):
    """A module loaded from a file path (not on sys.path): it pickles here, by a name no
    worker process can import."""
    path = tmp_path / "elsewhere_module.py"
    path.write_text("def f(task):\n    return task\n")
    spec = importlib.util.spec_from_file_location("scoutsim_elsewhere_module", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    monkeypatch.setitem(sys.modules, "scoutsim_elsewhere_module", mod)
    assert "cannot import by name" in unsendable_reason(mod.f)


def test_map_tasks_refuses_an_unsendable_task_before_any_runs():
    ran = []
    with pytest.raises(NotSendableError, match="task 2 of the runs"):
        map_tasks(_double, [1, 2, lambda: 3], workers=2, on_result=lambda i, r: ran.append(i))
    assert ran == []
    # in one process nothing needs sending
    assert map_tasks(_double, [1, 2], workers=1) == [2, 4]


@pytest.mark.parametrize("workers", [1, 2])
def test_a_result_that_asks_to_stop_keeps_what_arrived(workers):
    out = map_tasks(_double, list(range(6)), workers=workers, stop_when=lambda r: r == 4)
    assert out[2] == 4 and all(r is None or r == 2 * i for i, r in enumerate(out))
    if workers == 1:
        assert out == [0, 2, 4, None, None, None]
