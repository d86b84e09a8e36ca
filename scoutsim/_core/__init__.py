"""The compiled core (private): the hybrid model (:mod:`._core.model`), its integrators
and event handling (:mod:`._core.numerics`) and the run loop that composes them with the
controller (:mod:`._core.loop`), all compiled with Numba (:mod:`scoutsim._numba`).

Nothing here is public API: the layers above reach a run through
:func:`scoutsim.simulate` and :class:`scoutsim.SimulationResult`, the recorded codes
through :mod:`scoutsim.names` and states through :mod:`scoutsim.state`, so the core's
array layouts can change under them. CONTRIBUTING.md says how to work on it.
"""
