"""What one stride costs: the energy flows of a run (``simulate(energy=True)``) between
the control samples nearest to the stride's two back-leg lift-offs (docs/model.md
"Work-energy balance").

Energies in J (electrical energy into the motor terminals, copper and transmission losses,
hip work, friction and dampers, touchdown impacts, change of mechanical energy, the
balance's residual), distance in m, power in W, the cost of transport dimensionless.
Consecutive strides share their boundary sample, so the strides' energies add up to the
energy over their samples.
"""

from __future__ import annotations

import numpy as np

__all__ = ["stride_energy"]


def input_and_weight(result):
    """(the balance's input flow, m g [N]) of the run: "electrical" for Model I / II,
    "hip_work" for the ideal actuator; (None, None) for the passive model or without the
    robot in the provenance."""
    prov = result.provenance or {}
    robot = prov.get("robot")
    model = prov.get("model")
    if not robot or model not in ("I", "II", "ideal"):
        return None, None
    from ..parameters import RobotParameters

    params = RobotParameters(**robot)
    return (
        "electrical" if model in ("I", "II") else "hip_work",
        params.total_mass * params.gravity,
    )


def _nearest_sample(t, te: float) -> int:
    i = int(np.searchsorted(t, te))
    if i >= len(t):
        return len(t) - 1
    if i > 0 and te - t[i - 1] <= t[i] - te:
        return i - 1
    return i


#: the keys under which :func:`stride_energy` keeps the run's impact log and its
#: :func:`input_and_weight` in ``cumulative``
_IMPACTS = "impact_log"
_INPUT = "input_and_weight"


def _impact_loss(result, t0: float, t1: float, cumulative: dict) -> float:
    """Kinetic energy lost in the touchdown impacts with t0 <= t < t1 [J]: the run's impact
    log read (and put in time order) once, kept in ``cumulative``, and the window found by
    bisection, so that the strides of a run cost time linear in its length; the same sum
    as ``result.impact_log(t0, t1)["energy_lost"].sum()``, term for term (the log is in
    time order as the run records it)."""
    if _IMPACTS not in cumulative:
        log = result.impact_log()
        times, lost = log["t"], log["energy_lost"]
        if times.size > 1 and not np.all(times[1:] >= times[:-1]):  # (put in time order)
            order = np.argsort(times, kind="stable")
            times, lost = times[order], lost[order]
        cumulative[_IMPACTS] = (times, lost)
    times, lost = cumulative[_IMPACTS]
    k0, k1 = np.searchsorted(times, [t0, t1], side="left")
    return float(lost[k0:k1].sum())


def stride_energy(result, a: float, b: float, cumulative: dict | None = None) -> dict:
    """The energy fields of :class:`Stride` for the stride from ``a`` to ``b`` [s] (the
    run's samples nearest to them); {} if the run has no ``energy_series``.
    ``cumulative``: a dict in which the run's cumulative energies by destination
    (``result.cumulative_energy``), its impact log and its input flow are kept from one
    stride to the next."""
    if getattr(result, "energy_series", None) is None or len(result.t) < 2:
        return {}
    t = np.asarray(result.t, dtype=float)
    i, j = _nearest_sample(t, a), _nearest_sample(t, b)
    if j <= i:
        return {}
    cumulative = {} if cumulative is None else cumulative

    def delta(name):
        if name not in cumulative:
            cumulative[name] = result.cumulative_energy(name)
        return float(cumulative[name][j] - cumulative[name][i])

    impacts = _impact_loss(result, t[i], t[j], cumulative)
    mech = float(result.energy[j] - result.energy[i])
    hip = delta("hip_work")
    friction = delta("friction")
    distance = float(result.x[j] - result.x[i])
    if _INPUT not in cumulative:  # (the robot read once per run, not per stride)
        cumulative[_INPUT] = input_and_weight(result)
    input_name, weight = cumulative[_INPUT]
    electrical = input_name == "electrical"
    out = {
        "energy_t_start": float(t[i]),
        "energy_t_end": float(t[j]),
        "electrical_energy_j": delta("electrical") if electrical else None,
        "copper_loss_j": delta("copper") if electrical else None,
        "transmission_loss_j": delta("transmission") if electrical else None,
        "hip_work_j": hip,
        "friction_loss_j": friction,
        "impact_loss_j": impacts,
        "mechanical_energy_change_j": mech,
        "energy_residual_j": hip - friction - delta("constraint") - impacts - mech,
        "distance_m": distance,
    }
    out["mean_electrical_power_w"] = (
        out["electrical_energy_j"] / float(t[j] - t[i]) if electrical else None
    )
    out["cost_of_transport"] = (
        delta(input_name) / (weight * distance) if input_name is not None and distance > 0 else None
    )
    return out
