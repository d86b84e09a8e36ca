"""A family of periodic gaits along one parameter, as a table: one row per orbit, in the
order of the branch (:func:`~scoutsim.analysis.passive_family.passive_family`,
:func:`~scoutsim.analysis.controlled_family.controlled_family`; docs/orbits.md, "Families of
gaits"). Saved as CSV and Parquet with the same columns.

Columns (:data:`FAMILY_COLUMNS`, after the varied parameter's own column, named as given,
e.g. ``pitch_rate_deg`` or ``controller.touchdown_angle_front_deg``):

* ``touchdown_angle_back_deg``, ``touchdown_angle_front_deg``: the touchdown angles from
  the world vertical [deg];
* ``period_s``, ``strides`` (per period), ``mean_speed_m_s``;
* ``spectral_radius``: the largest modulus of the multipliers per stride (the period's
  radius to the power 1/strides; the conservative model's energy multiplier left out);
  ``stable``: whether it is below 1 (at most 1 for the conservative model, which cannot
  attract);
* ``bifurcation``: what happened ("" if nothing): "fold", "branch point", "period
  doubling", "torus" (:func:`~scoutsim.analysis.continuation.crossing_kind`) or a change of
  the number of strides per period. A pseudo-arclength branch adds a row at the located
  point; a natural-parameter one labels the first orbit after the change;
* ``multipliers``: the largest multipliers, as ``re+imj`` text;
* ``status``: "ok", or why there is no orbit at this value.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["FAMILY_COLUMNS", "GaitFamily"]

FAMILY_COLUMNS = (
    "touchdown_angle_back_deg",
    "touchdown_angle_front_deg",
    "period_s",
    "strides",
    "mean_speed_m_s",
    "spectral_radius",
    "stable",
    "bifurcation",
    "multipliers",
    "status",
)


@dataclass
class GaitFamily:
    """A branch of periodic gaits in the parameter ``parameter`` (the name of its column,
    in the unit the name gives).

    rows : one dict per orbit (the parameter and :data:`FAMILY_COLUMNS`; ``multipliers`` a
        list of (real, imag) pairs), in the order of the branch.
    stopped : why the branch ended ("range", "lost: ...", "max_points", "values").
    setting : what the family was computed for (model, apex speed and height, ...).
    method : how it was followed ("pseudo-arclength", "natural-parameter").
    """

    parameter: str
    rows: list[dict] = field(default_factory=list)
    stopped: str = ""
    setting: dict = field(default_factory=dict)
    method: str = ""

    @property
    def columns(self) -> list[str]:
        return [self.parameter, *FAMILY_COLUMNS]

    @property
    def bifurcations(self) -> list[dict]:
        """The rows where something happened (their ``bifurcation`` set)."""
        return [r for r in self.rows if r["bifurcation"]]

    def to_frame(self):
        """The table as a pandas DataFrame (``multipliers`` as text)."""
        import pandas as pd

        df = pd.DataFrame(self.rows, columns=self.columns)
        df["multipliers"] = [
            "; ".join(f"{re:.6g}{im:+.6g}j" for re, im in m) for m in df["multipliers"]
        ]
        return df

    def save(self, out_dir, stem: str = "family") -> list[Path]:
        """Write ``<stem>.csv`` and ``<stem>.parquet`` into ``out_dir`` (created)."""
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        df = self.to_frame()
        paths = [out / f"{stem}.csv", out / f"{stem}.parquet"]
        df.to_csv(paths[0], index=False)
        df.to_parquet(paths[1], index=False)
        return paths
