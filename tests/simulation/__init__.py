"""Tests of a run (scoutsim.simulation)."""
