"""Tests of a run's result (scoutsim.result)."""
