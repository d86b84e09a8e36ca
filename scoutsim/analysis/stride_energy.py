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

__all__ = ["stride_energy", "StrideCosts"]


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


class StrideCosts:
    """The energy fields of the strides of one run, from its
    :class:`~scoutsim.result.stride_record.StrideRecord` (``record``): the cumulative
    energies at the samples nearest to the back-leg lift-offs, the impacts between them.
    The impact log and the input flow are read once for all strides, so that the strides
    of a run cost time linear in its length."""

    def __init__(self, result, record):
        self.record = record
        if not record.energy:
            return
        self.impacts = record.impacts()
        self.input_name, self.weight = input_and_weight(result)

    def impact_loss(self, t0: float, t1: float) -> float:
        """Kinetic energy lost in the touchdown impacts with t0 <= t < t1 [J]: the same
        terms, summed in the same order, as
        ``result.impact_log(t0, t1)["energy_lost"].sum()``."""
        times, lost = self.impacts
        k0, k1 = np.searchsorted(times, [t0, t1], side="left")
        return float(lost[k0:k1].sum())

    def of(self, k: int) -> dict:
        """The energy fields of the stride from lift-off ``k`` to ``k + 1`` (the record's
        rows); {} without the accounting, or when both lift-offs are nearest to one
        sample."""
        if not self.record.energy:
            return {}
        lift = self.record.liftoffs
        if lift["sample"][k + 1] <= lift["sample"][k]:
            return {}
        t0, t1 = float(lift["sample_t"][k]), float(lift["sample_t"][k + 1])

        def delta(name):
            e = lift["e_" + name]
            return float(e[k + 1] - e[k])

        impacts = self.impact_loss(t0, t1)
        mech = float(lift["sample_mechanical"][k + 1] - lift["sample_mechanical"][k])
        hip = delta("hip_work")
        friction = delta("friction")
        distance = float(lift["sample_x"][k + 1] - lift["sample_x"][k])
        input_name, weight = self.input_name, self.weight
        electrical = input_name == "electrical"
        out = {
            "energy_t_start": t0,
            "energy_t_end": t1,
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
            out["electrical_energy_j"] / (t1 - t0) if electrical else None
        )
        out["cost_of_transport"] = (
            delta(input_name) / (weight * distance)
            if input_name is not None and distance > 0
            else None
        )
        return out


def stride_energy(result, a: float, b: float) -> dict:
    """The energy fields of :class:`~scoutsim.analysis.strides.Stride` for the stride of
    ``result`` from the back-leg lift-off at ``a`` to the one at ``b`` [s] (the run's
    samples nearest to them); {} if the run has no ``energy_series`` or no such pair of
    lift-offs."""
    from ..result.stride_record import record_strides

    record = record_strides(result)
    lo = record.liftoffs["t"]
    k = int(np.searchsorted(lo, a))
    if k + 1 >= len(lo) or lo[k] != a or lo[k + 1] != b:
        return {}
    return StrideCosts(result, record).of(k)
