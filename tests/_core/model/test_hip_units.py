"""The hip units (scoutsim._core.model.hip_unit): the registry and the compiled hooks written
from it.

Laws checked: every registered unit declares what a unit must (name, whether it is geared,
which robots it applies to, and the belt spring of a geared unit); code 0 is a unit without
a gear train (the unit of a parameter array without one); a robot runs on the unit its
model calls for (rigid for ideal / Model I / passive, the belt for Model II); the compiled
hooks ``geared`` and ``belt_spring`` give, for every code, what that unit's module says.
"""

from __future__ import annotations

import numpy as np
import pytest

import scoutsim
from scoutsim._core.model import hip_unit
from scoutsim._core.model import layout as L
from scoutsim._core.model.packing import robot_array


def test_every_unit_declares_its_hooks():
    for unit in hip_unit.UNITS:
        assert isinstance(unit.NAME, str) and unit.NAME
        assert isinstance(unit.GEARED, bool)
        assert callable(unit.applies)
        if unit.GEARED:
            assert callable(unit.spring)
    assert len(set(hip_unit.NAMES)) == len(hip_unit.UNITS)
    assert not hip_unit.UNITS[0].GEARED


@pytest.mark.parametrize(
    "model,geared", [("II", True), ("I", False), ("ideal", False), ("passive", False)]
)
def test_the_hip_unit_follows_the_model(model, geared):
    code = int(robot_array(scoutsim.RobotParameters(), model)[L.P_HIP_UNIT])
    assert hip_unit.is_geared(code) is geared
    assert hip_unit.NAMES[code] == ("belt" if geared else "rigid")


@pytest.mark.parametrize("code", range(len(hip_unit.UNITS)))
def test_compiled_hooks_dispatch_to_the_units_module(code):
    unit = hip_unit.UNITS[code]
    P = robot_array(scoutsim.RobotParameters(), "II")
    P[L.P_HIP_UNIT] = code
    assert hip_unit.geared(P) is unit.GEARED
    if not unit.GEARED:
        return
    for leg in (L.BACK, L.FRONT):
        for delta in np.linspace(-0.1, 0.1, 41):
            assert hip_unit.belt_spring(delta, leg, P) == unit.spring.py_func(delta, leg, P)
