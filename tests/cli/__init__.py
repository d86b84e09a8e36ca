"""Tests of the command line (scoutsim.cli)."""
