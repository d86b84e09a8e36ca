"""Tests of the compiled core (scoutsim._core): the model and the numerics."""
