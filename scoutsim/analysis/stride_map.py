"""The stride map of the controlled robot: its Poincaré section and one stride of the
sampled closed loop.

The Table I law samples and holds at 1 kHz, so the closed loop is a sampled-data system.
**Section**: the control sample at which the controller detects back-leg lift-off. The
section coordinates ``z`` (:data:`CONTROLLED_Z_NAMES`, SI: m, rad, m/s, rad/s) are the
complete hybrid state there (:class:`~scoutsim.state.HybridState`) without x, with the
pinned toes' anchors relative to x; the discrete plant / controller modes must recur.
:func:`controlled_stride_map` is smooth as long as every controller transition stays on
the same sample, so its fixed point (:mod:`scoutsim.analysis.controlled_orbit`) is a
periodic orbit lasting a whole number of control periods.
"""

from __future__ import annotations

import numpy as np

from ..names import ContactMode, Leg
from ..parameters import DEFAULT_FRICTION_COEFFICIENT
from ..simulation.integrator import IntegratorSettings
from ..simulation.simulator import simulate
from ..state import HybridState, state_index, state_vector
from .poincare import MapError

__all__ = ["controlled_stride_map", "section_state", "CONTROLLED_Z_NAMES"]

#: names of the section coordinates z of the controlled stride map (SI)
CONTROLLED_Z_NAMES = (
    "y",
    "theta",
    "phi_back",
    "phi_front",
    "alpha_back",
    "alpha_front",
    "dx",
    "dy",
    "dtheta",
    "dphi_back",
    "dphi_front",
    "dalpha_back",
    "dalpha_front",
    "leg_length_back",
    "leg_length_front",
    "anchor_back_rel",
    "anchor_front_rel",
)
#: the components of z taken from the state vector (all but x), in z's order
_STATE_Z_NAMES = CONTROLLED_Z_NAMES[:-2]
#: the contact modes in which a toe is pinned at its anchor
_PINNED = (ContactMode.STICK, ContactMode.STRUT)


def _z_of(hs) -> np.ndarray:
    """Section coordinates of a HybridState: the state without x, and the pinned toes'
    anchors relative to x (0 for a leg not pinned)."""
    s = np.asarray(hs.state)
    x = s[state_index("x")]
    rel = [(hs.toe_anchors[leg] - x) if hs.contact_modes[leg] in _PINNED else 0.0 for leg in Leg]
    return np.concatenate([s[[state_index(n) for n in _STATE_Z_NAMES]], rel])


def hs_of(z, discrete):
    """The HybridState of section coordinates ``z`` at x = 0 with the discrete modes
    ``discrete`` (:func:`discrete_modes`)."""
    s = state_vector(x=0.0, **dict(zip(_STATE_Z_NAMES, z)))
    return HybridState(state=s, toe_anchors=(float(z[-2]), float(z[-1])), **discrete)


def discrete_modes(hs) -> dict:
    return dict(
        leg_states=hs.leg_states,
        contact_modes=hs.contact_modes,
        motor_modes=hs.motor_modes,
        slide_directions=hs.slide_directions,
    )


def section_state(result):
    """The HybridState at the second-to-last sample at which the controller of ``result``
    (a :class:`~scoutsim.SimulationResult`) detected back-leg lift-off: a Newton start for
    :func:`controlled_fixed_point`. MapError if the run has fewer than 3 such samples or
    did not complete."""
    dt = float(result.provenance["control_period_s"])
    te = result.event_times("controller_liftoff", "back")
    if result.outcome != "completed" or len(te) < 3:
        raise MapError(
            f"no steady bounding to start from (outcome {result.outcome}, "
            f"{len(te)} back-leg lift-offs in {result.t[-1]:.3g} s)"
        )
    return result.hybrid_state(int(round(te[-2] / dt)))


def controlled_stride_map(
    hs,
    *,
    model: str = "II",
    friction_coefficient: float = DEFAULT_FRICTION_COEFFICIENT,
    robot=None,
    controller=None,
    integrator: IntegratorSettings | None = None,
    max_period: float = 0.6,
):
    """One stride of the sampled closed loop from the HybridState ``hs`` taken at a control
    sample: run until the controller next detects a back-leg lift-off (a sample, so the
    stride lasts a whole number of control periods) and return
    ``(z_start, z_end, hs_end, period_s)`` with z the section coordinates
    (:data:`CONTROLLED_Z_NAMES`); z_start is ``hs`` after the projection of its dependent
    coordinates. MapError if the robot falls or no lift-off is detected."""
    r = simulate(
        robot,
        controller,
        hs,
        max_period,
        model=model,
        integrator=integrator,
        friction_coefficient=friction_coefficient,
    )
    dt = float(r.provenance["control_period_s"])
    te = r.event_times("controller_liftoff", "back")
    te = te[te > 0.5 * dt]
    if len(te) == 0:
        raise MapError(
            f"no back-leg lift-off detected within {max_period} s (outcome "
            f"{r.outcome} at t = {r.t_end:.3f} s)"
        )
    k1 = int(round(te[0] / dt))
    if k1 >= len(r.t):
        raise MapError(f"the run ended (outcome {r.outcome}) at the lift-off sample")
    h1 = r.hybrid_state(k1)
    return _z_of(r.hybrid_state(0)), _z_of(h1), h1, float(r.t[k1])
