"""Tests of how the core is compiled and cached (scoutsim._numba)."""
