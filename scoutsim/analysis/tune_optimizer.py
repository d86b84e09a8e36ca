"""The optimiser of a tuning (:mod:`scoutsim.analysis.tune`) and what makes a tuning
resumable: CMA-ES from the ``cmaes`` library, its state saved after every generation, and
the names of the two files in the output directory that a resumed tuning goes on from.

``out/evaluations.jsonl`` (:data:`EVALUATIONS`) gets one JSON record per finished
evaluation, ``{"key": ..., "row": ...}``, appended as it arrives; ``out/optimizer.pkl``
(:data:`OPTIMIZER_STATE`) holds the pickled optimiser, its random generator and the
number of generations told, written atomically. Records and state are keyed by
:func:`checkpoint_key`, a hash of the tuning's settings (and of the generation and candidate), so a
call with other settings starts afresh.
"""

from __future__ import annotations

import hashlib
import json
import pickle
from pathlib import Path

from ..io.run_directory import atomic_write

__all__ = ["MissingDependencyError", "EVALUATIONS", "OPTIMIZER_STATE"]

#: the checkpoint of the evaluations: one JSON record per evaluation, appended as it arrives
EVALUATIONS = "evaluations.jsonl"
#: the optimiser's state before the next generation (pickled, written atomically)
OPTIMIZER_STATE = "optimizer.pkl"


class MissingDependencyError(ImportError):
    """The optional optimiser library is not installed (the message says what to install)."""


def cma_class():
    """The optimiser's class, ``cmaes.CMA``; MissingDependencyError without ``cmaes``."""
    try:
        from cmaes import CMA
    except ImportError:
        raise MissingDependencyError(
            "tuning needs the CMA-ES library 'cmaes', which is not installed: "
            "pip install cmaes (or pip install 'scoutsim[tune]')"
        ) from None
    return CMA


def checkpoint_key(blob) -> str:
    """A short hash of ``blob`` (as JSON, keys sorted): the key of a tuning's settings, and
    of an evaluation from the settings' key, its generation and its place in it."""
    text = json.dumps(blob, sort_keys=True, default=repr)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def read_state(path: Path):
    """The optimiser's state saved in ``path`` ({key, generation, cma}), or None."""
    if not path.exists():
        return None
    try:
        state = _thaw(path.read_bytes())
        return state if "key" in state else None
    except (
        OSError,
        pickle.UnpicklingError,
        EOFError,
        AttributeError,
        ImportError,
        KeyError,
        TypeError,
        ValueError,
    ):
        return None


def _freeze(key: str, generation: int, cma) -> bytes:
    """The optimiser's state as bytes. ``cmaes.CMA`` leaves its random generator out of its
    pickle (an unpickled one draws from a fresh, unseeded generator), so the generator's
    state is saved beside it."""
    return pickle.dumps(
        {"key": key, "generation": generation, "cma": cma, "rng": cma._rng.get_state()}
    )


def _thaw(blob: bytes) -> dict:
    """:func:`_freeze` undone: the optimiser with its random generator where it was."""
    state = pickle.loads(blob)
    state["cma"]._rng.set_state(state.pop("rng"))
    return state


def write_state(path: Path | None, key: str, generation: int, cma):
    """Save the optimiser's state to ``path`` (atomically; None: nowhere) and return the
    optimiser as read back from it, so that an uninterrupted tuning goes on from exactly
    what a resumed one reads."""
    blob = _freeze(key, generation, cma)
    if path is not None:
        atomic_write(path, lambda p: p.write_bytes(blob))
    return _thaw(blob)["cma"]
