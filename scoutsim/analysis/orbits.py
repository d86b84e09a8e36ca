"""Periodic orbits (Poincaré analysis) of bounding: return maps, fixed points, Floquet
multipliers and a one-parameter continuation (docs/orbits.md).

Passive conservative model (docs/specification.md section 2: massless, undamped legs placed in flight at
prescribed touchdown angles from the world vertical, ``model="passive"``):

* **Section**: the torso apex in double flight, ``dy = 0`` with ``y`` at a maximum. The
  section state is ``z = (y, theta, dx, dtheta)`` (x is irrelevant: the dynamics are
  invariant under horizontal translation; the legs are massless, so they carry no state).
* **Return map** :func:`passive_apex_map`: from an apex, simulate until both legs have had
  a stance and both are in flight again, then go to the next apex. In double flight the
  torso is ballistic (massless legs transmit no force), so the apex is reached exactly by
  propagating any double-flight sample analytically: ``t_a = t_k + dy_k / g``,
  ``y_a = y_k + dy_k^2 / (2 g)``, ``theta_a = theta_k + dtheta_k (t_a - t_k)``. The map is
  therefore as accurate as the integrator (rtol 1e-12 by default), not limited by the
  1 ms sample grid.
* **Fixed points** :func:`passive_bounding_orbit`: at given forward speed ``V``, apex height
  ``H`` and pitch rate ``W`` with the torso level at the apex, ``z* = (H, 0, V, W)``, solve
  ``P(z*; gamma_b, gamma_f) = z*`` for the back and front touchdown angles by
  Levenberg-Marquardt / Gauss-Newton on the four residuals (two unknowns; the system is
  consistent because such orbits are symmetric under the time-reversal-and-mirror symmetry
  of the conservative model, which leaves two independent conditions) with a central
  finite-difference Jacobian.
* **Floquet multipliers**: eigenvalues of the central-difference Jacobian ``dP/dz`` at the
  fixed point. Energy conservation makes one of them exactly 1.

Controlled robot (:func:`controlled_fixed_point`), for any controller whose state scoutsim
can read and set (the built-in Table I law, a compiled controller, a Python controller with
``get_state()`` / ``set_state(values)``): the controller samples and holds at 1 kHz, so the
closed loop is a sampled-data system. **Section**: the first control sample after the back
leg's lift-off (a plant event every bounding run has); the section state is the complete
hybrid state there (:class:`~scoutsim.state.HybridState`: continuous state without x,
pinned toes' anchors relative to x, the controller's own state and, for a controller other
than the built-in law, the held torques; the discrete plant/controller modes must recur).
The stride map (:class:`~scoutsim.analysis.stride_map.StrideMap`) is smooth as long as the
lift-off and every controller switch stay on the same sample, so its fixed point is a
periodic orbit lasting a whole number of control periods; Newton's method (forward-
difference Jacobian, least-squares steps because pinned legs and stuck motor joints make
some coordinates dependent, halved where a step does not reduce the residual) converges on
it to a residual ~1e-12, and the eigenvalues of the Jacobian are its Floquet multipliers.
A controller that locks into a cycle of several strides of different lengths has its orbit
as a fixed point of the map's iterate (``strides``). On the Scout II defaults (Model II,
default floor) the orbit lasts 234 ms with spectral radius 0.925 (a real multiplier
-0.925: successive strides alternate about the orbit), and a long simulation from the
default start settles onto it at that rate (tests/analysis).
:func:`controlled_cycle` is the simulation-only estimate (mean of converged strides,
multipliers fitted to the transient), kept as a cross-check.

Units: SI, angles in rad (degrees only in the ``*_deg`` conveniences).

The parts have their own modules: :mod:`~scoutsim.analysis.poincare` (``MapError``, the
finite-difference Jacobian, Floquet multipliers), :mod:`~scoutsim.analysis.passive_reference`
(the independent SciPy formulation of the passive model and its apex map),
:mod:`~scoutsim.analysis.passive_orbits` (passive fixed points and their continuation),
:mod:`~scoutsim.analysis.stride_map` (the controlled section and stride map),
:mod:`~scoutsim.analysis.controlled_orbit` (its fixed point by Newton) and
:mod:`~scoutsim.analysis.controlled_cycle` (the simulation-only estimate). This module
re-exports their public names.
"""

from __future__ import annotations

from .controlled_cycle import LIFTOFF_STATE_NAMES, ControlledCycle, controlled_cycle
from .controlled_orbit import ControlledOrbit, NewtonSettings, controlled_fixed_point
from .passive_orbits import PassiveOrbit, continue_passive_family, passive_bounding_orbit
from .passive_reference import (
    APEX_STATE_NAMES,
    ORBIT_TOLERANCE,
    SIMULTANEOUS_EVENT_TOL,
    ApexMap,
    passive_apex_map,
    passive_robot,
)
from .poincare import MapError, fd_jacobian, floquet_multipliers
from .stride_map import CONTROLLED_Z_NAMES, StrideMap, controlled_stride_map, section_state

__all__ = [
    "MapError",
    "ApexMap",
    "PassiveOrbit",
    "ControlledCycle",
    "ControlledOrbit",
    "NewtonSettings",
    "StrideMap",
    "controlled_fixed_point",
    "controlled_stride_map",
    "section_state",
    "CONTROLLED_Z_NAMES",
    "passive_robot",
    "passive_apex_map",
    "fd_jacobian",
    "passive_bounding_orbit",
    "continue_passive_family",
    "floquet_multipliers",
    "controlled_cycle",
    "APEX_STATE_NAMES",
    "LIFTOFF_STATE_NAMES",
    "ORBIT_TOLERANCE",
    "SIMULTANEOUS_EVENT_TOL",
]
