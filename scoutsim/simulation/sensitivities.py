"""The sensitivities an engine carries along its run: the rows of its extended state, the
work arrays and what they met (a parameter's row:
:mod:`scoutsim.simulation.parameter_rows`; the compiled side: :mod:`scoutsim._core.numerics.tangent`, its work arrays
:mod:`scoutsim._core.numerics.tangent_work`;
docs/explanation/derivatives.md)."""

from __future__ import annotations

import numpy as np

from .._core.numerics.tangent_call import hook_address
from .._core.numerics.tangent_work import (
    A_HOOK,
    HOOK_FLOW,
    HOOK_OPS,
    TI_EVENTS,
    TI_GRAZING,
    TI_NONSMOOTH,
    TI_SAMPLE_MARGIN,
    TI_UNSUPPORTED,
    X_CMD,
    X_CS,
    X_MF,
    X_S,
    packed,
    tangent_work,
)

__all__ = ["EXTENDED_ROWS", "engine_tangent", "smoothness", "with_hook"]

#: where each part of the extended state starts in the rows of
#: :attr:`~scoutsim.simulation.engine.HybridEngine.sensitivities`: the state (layout
#: ``NS``), the toe anchors [m], the held hip commands [N m], the controller's state array;
#: the parameters carried, if any, are the last rows
EXTENDED_ROWS = {"state": X_S, "anchors": X_MF, "commands": X_CMD, "controller_state": X_CS}


def engine_tangent(engine, m: int, parameters=None):
    """The compiled work arrays for ``m`` sensitivity columns of ``engine``'s run (0: a run
    without sensitivities); ``parameters``: None or (dP, dC, dcp), the derivatives (n_p x
    size) of the packed robot parameters, the Table I law's parameters and a compiled
    controller's parameters, each parameter then a row of x. A parameter's difference step
    is relative to the packed values it moves (absolute where they are 0)."""
    block = engine.block
    sizes = (len(engine.P), len(engine.C), len(block.params))
    if parameters is not None:
        dP, dC, dcp = (np.atleast_2d(np.asarray(a, dtype=float)) for a in parameters)
        scale = np.concatenate(
            [
                np.abs(d) / np.where(v != 0.0, np.abs(v), 1.0)
                for d, v in ((dP, engine.P), (dC, engine.C), (dcp, block.params))
            ],
            axis=1,
        )
        parameters = (dP, dC, dcp, scale.max(axis=1, initial=0.0))
    return packed(
        tangent_work(
            m, len(block.state), len(block.y), (engine.rtol, engine.atol), sizes, parameters
        )
    )


def with_hook(pack, method: int) -> None:
    """Give a run's sensitivities (``pack``) the address, in this process, of the compiled
    code a run of ``method`` (its integrator's code) calls them through
    (:mod:`scoutsim._core.numerics.tangent_call`; compiled on the first run that carries
    columns); nothing for a run that carries none."""
    if pack.Phi.shape[1] > 0:
        pack.calls[A_HOOK, HOOK_OPS] = hook_address("op")
        pack.calls[A_HOOK, HOOK_FLOW] = hook_address(method)


def smoothness(info) -> dict:
    """What the carried sensitivities met (the compiled ``info``, layout ``TI_*``):
    ``nonsmooth`` (resets where a perturbed copy ended in other modes than the run, or a
    copy the controller refused: not differentiable there), ``transversality`` (the
    smallest |n.f| / (|n| |f|) of a located event: near 0, an event that grazes),
    ``events`` (located events differentiated), ``undifferentiated`` (control samples
    whose measurement model, noise or delay, was not differentiated), ``sample_margin_s``
    (the smallest time [s] from a control sample to the zero of an event function
    approaching it: an event that close to a sample boundary crosses it under a
    perturbation, where the sampled map jumps; the derivatives are those of the side the
    run took)."""
    return {
        "nonsmooth": int(info[TI_NONSMOOTH]),
        "transversality": float(info[TI_GRAZING]),
        "events": int(info[TI_EVENTS]),
        "undifferentiated": int(info[TI_UNSUPPORTED]),
        "sample_margin_s": float(info[TI_SAMPLE_MARGIN]),
    }
