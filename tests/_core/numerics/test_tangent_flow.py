"""The flow's derivative step by step (scoutsim._core.numerics.tangent_flow).

Law checked: convergence under tightened tolerances. The derivative a run carries is the
flow's along the computed trajectory, so as the tolerance tightens it must converge like
the trajectory does. Where a motor current meets or leaves the torque-speed line inside a
step (a kink of the right-hand side: the flow is continuous there, its Jacobian jumps),
differentiating the step whole leaves an error of first order in the step that the error
control does not see; the step is split at the kink for the derivative. Measured on the
default Model II orbit (four such crossings a stride): the stride map's Jacobian at rtol
1e-11 differed from the one at rtol 1e-13 by 7.9e-6 of its scale differentiated whole,
5.3e-7 split, while the strides' end states agreed to 5e-11 either way. (The ARK methods'
steps are not split: at their tolerances the Jacobian's error follows the state's, 200
times it, and the split changed it by less than a factor 1.5 either way.)
"""

from __future__ import annotations

import numpy as np
import pytest

from scoutsim.analysis.controlled_orbit import NewtonSettings, controlled_fixed_point
from scoutsim.analysis.stride_map import StrideMap
from scoutsim.simulation.integrator import IntegratorSettings


@pytest.fixture(scope="module")
def orbit():
    return controlled_fixed_point(settle_duration=8.0, newton=NewtonSettings(tol=1e-9))


def _stride(orbit, rtol: float):
    m = StrideMap(
        integrator=IntegratorSettings(rtol=rtol, atol=rtol / 10.0),
        section=orbit.setting["section"],
    )
    c = m.crossing(orbit.state, exact=True)
    assert c.jacobian is not None and c.smoothness is not None
    return m.z_of(c.state), c.jacobian, c.smoothness


def test_the_stride_jacobian_converges_with_the_tolerance_across_the_line(orbit):
    z_loose, J_loose, smooth = _stride(orbit, 1e-11)
    z_tight, J_tight, _ = _stride(orbit, 1e-13)
    assert smooth["nonsmooth"] == 0
    scale = np.abs(J_tight).max()
    # the trajectory converges ...
    assert np.abs(z_loose - z_tight).max() < 1e-9
    # ... and so does its derivative (measured 5.3e-7; differentiated whole, the steps
    # across the line left 7.9e-6)
    assert np.abs(J_loose - J_tight).max() < 2e-6 * scale
