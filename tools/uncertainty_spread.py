"""Draw the spread of Model II's Fig. 12 gait metrics under parameter uncertainty next to
Model II's Fig. 12 percent errors.

Reads an uncertainty study's ``samples.parquet`` (``scoutsim uncertainty``), keeps its
base samples (design blocks A and B: 2N independent draws of the parameters; the AB
blocks re-use their columns), runs Scout II with its default parameters once (the
nominal gait, same model and duration as the study), and draws, per Fig. 12 metric, the
signed percent deviation of the samples from the nominal value (box: quartiles and
median; whiskers: 5 % and 95 % quantiles) over a band of +-e, e being Model II's mean
percent error of ``scoutsim compare --example`` (docs/validation.md, "Error assessment
(Fig. 12)"; pass other errors with ``--errors``). It also prints the quantiles as a
Markdown table.

Usage::

    python tools/uncertainty_spread.py STUDY_DIR --out docs/img/uncertainty_spread.png

The study's samples must all bound for a metric to be drawn (a sample that does not
bound has no value and is left out, and the script says how many).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pandas as pd

#: the Fig. 12 metrics (paper Sec. IV.C) as the study names them, with their labels
FIG12_METRICS = {
    "stride_frequency_hz": "stride frequency",
    "duty_factor_back": "duty factor back",
    "duty_factor_front": "duty factor front",
    "pitch_max_deg": "pitch max",
    "pitch_min_deg": "pitch min",
    "height_max_m": "height max",
    "height_min_m": "height min",
}
#: Model II's mean percent errors of `scoutsim compare --example` (docs/validation.md,
#: "Error assessment (Fig. 12)"): against the synthetic example logs, not Scout II
EXAMPLE_MEAN_ERRORS = {
    "stride_frequency_hz": 2.54,
    "duty_factor_back": 6.69,
    "duty_factor_front": 1.78,
    "pitch_max_deg": 5.57,
    "pitch_min_deg": 12.49,
    "height_max_m": 0.08,
    "height_min_m": 0.38,
}
QUANTILES = (0.05, 0.25, 0.5, 0.75, 0.95)


def nominal_metrics(model: str, duration_s: float) -> dict:
    """The Fig. 12 metrics of one run with Scout II's default parameters."""
    from scoutsim import simulate

    summary = simulate(model=model, duration=duration_s).summary()
    return {m: float(summary[m]) for m in FIG12_METRICS}


def deviations(samples: pd.DataFrame, nominal: dict) -> dict:
    """Metric -> signed percent deviations of the base samples from the nominal values."""
    base = samples[samples["block"].isin(["A", "B"])]
    out = {}
    for m in FIG12_METRICS:
        v = base[m].to_numpy(dtype=float)
        v = v[np.isfinite(v)]
        out[m] = 100.0 * (v - nominal[m]) / abs(nominal[m])
    return out


def draw(dev: dict, errors: dict, path: Path, title: str) -> None:
    """The figure of the module docstring, saved to ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(FIG12_METRICS)
    fig, ax = plt.subplots(figsize=(7.0, 4.2), layout="constrained")
    for k, m in enumerate(names):
        e = errors[m]
        ax.add_patch(
            plt.Rectangle(
                (-e, k - 0.4),
                2 * e,
                0.8,
                color="tab:red",
                alpha=0.18,
                linewidth=0,
                label="Model II mean error, synthetic example (+-)" if k == 0 else None,
            )
        )
    ax.boxplot(
        [dev[m] for m in names],
        positions=np.arange(len(names)),
        orientation="horizontal",
        whis=(5, 95),
        showfliers=False,
        widths=0.5,
        medianprops={"color": "black"},
    )
    ax.axvline(0.0, color="grey", linewidth=0.8)
    ax.set_yticks(np.arange(len(names)), [FIG12_METRICS[m] for m in names])
    ax.invert_yaxis()
    ax.set_xlabel("deviation from the nominal Model II value [%]")
    ax.set_title(title, fontsize=10)
    ax.legend(loc="lower right", fontsize=8)
    fig.savefig(path, dpi=110)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("study", type=Path, help="output directory of scoutsim uncertainty")
    parser.add_argument("--out", type=Path, default=Path("uncertainty_spread.png"))
    parser.add_argument(
        "--errors",
        type=Path,
        help="JSON metric -> mean percent error to draw instead of the example's",
    )
    args = parser.parse_args(argv)

    summary = json.loads((args.study / "summary.json").read_text())
    settings = summary.get("settings", {})
    model = settings.get("model", "II")
    duration_s = float(settings.get("duration_s", 10.0))
    samples = pd.read_parquet(args.study / "samples.parquet")
    nominal = nominal_metrics(model, duration_s)
    errors = json.loads(args.errors.read_text()) if args.errors else EXAMPLE_MEAN_ERRORS
    dev = deviations(samples, nominal)
    n_base = int(samples["block"].isin(["A", "B"]).sum())

    print(f"model {model}, {duration_s:g} s; {n_base} base samples")
    print("| metric | nominal | " + " | ".join(f"q{q:.2f} [%]" for q in QUANTILES) + " | n |")
    print("|---|---|" + "---|" * len(QUANTILES) + "---|")
    for m, label in FIG12_METRICS.items():
        q = np.quantile(dev[m], QUANTILES) if dev[m].size else [np.nan] * len(QUANTILES)
        cells = " | ".join(f"{x:+.2f}" for x in q)
        print(f"| {label} | {nominal[m]:.4g} | {cells} | {dev[m].size} |")
    draw(
        dev,
        errors,
        args.out,
        f"Model II, {n_base} samples of the uncertain parameters (5-25-50-75-95 % quantiles)",
    )
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
