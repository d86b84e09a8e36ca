"""Fig. 10 with a torque-dependent gearbox efficiency (docs/identification.md, section 4).

The paper (Sec. IV.B) estimates hip torques from motor current with the constant maximum
efficiency, ``N eta K_T i``, and suspects that the gearbox's efficiency drop at low torque
explains why Model II and experiment differ most where the torque is small. This script
runs Model II with the robot's constant efficiency (Scout II: 68 % gearbox x 96 %
sprocket) and with the torque-dependent losses of docs/model.md ("Transmission losses")
added, then

* plots, for one steady step of each virtual leg, the torque the experiment would have
  reported (current-estimated, N eta K_T i of that leg) for both runs, and the torque the
  lossy transmission actually delivered (paper Fig. 10 layout, with the leg-state square
  wave);
* plots the motoring efficiency tau_out / (N K_T i) against the delivered torque (one
  curve per leg when the legs' hip units differ);
* prints the low-torque numbers and the gait metrics of both runs.

Run it (after ``pip install -e .`` in the repository):

    python examples/fig10_efficiency.py [--robot FILE] [--out fig10_efficiency.png] [--quick]

``--robot FILE`` is a robot file as ``scoutsim run --robot`` reads it (default Scout II;
the losses are added to its hip units); ``--out`` the PNG written (default
``fig10_efficiency.png`` in the current directory; ``--out docs/img/fig10_efficiency.png``
from the repository's root regenerates the figure of docs/identification.md);
``--quick`` simulates 4 s instead of 8 s (seconds in all).

The loss parameters (idle 0.8 N m at the leg, load coefficient 0.05) are illustrative,
not identified: Maxon gives the efficiency drop only qualitatively.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

IDLE = 0.8  # gearbox_idle_loss_torque [N m] at the leg, per physical leg
C_LOAD = 0.05  # gearbox_load_loss_coefficient [-]
DURATION = 8.0  # simulated time [s]
QUICK_DURATION = 4.0  # ... with --quick
STEADY_FROM = 2.0  # [s]: the samples after it count as the steady bound
STEP_BEFORE_END = 3.0  # [s]: the step plotted starts at the first lift-off after
# duration - STEP_BEFORE_END (at least STEADY_FROM)
LOW = 5.0  # |torque| [N m] below which a sample counts as low-torque
MOTORING_SPEED = 500.0  # motor speed [rad/s] of the efficiency curve (motoring: i, w > 0)


def one_step(res, leg, t_from):
    """Indices of one step of ``leg``: from a lift-off after t_from to the next."""
    lo = res.event_times("liftoff", leg)
    lo = lo[lo > t_from]
    if len(lo) < 2:
        raise SystemExit(
            f"{leg} leg: fewer than two lift-offs after t = {t_from:g} s "
            f"(run {res.outcome} at {res.t_end:.3f} s); no step to plot"
        )
    return np.flatnonzero((res.t >= lo[0]) & (res.t < lo[1]))


def _fmt(v, spec=".4g"):
    return "n/a" if v is None or (isinstance(v, float) and math.isnan(v)) else format(v, spec)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--robot",
        metavar="FILE",
        help="TOML robot file, as `scoutsim run --robot` (default: Scout II)",
    )
    ap.add_argument(
        "--out",
        type=Path,
        default=Path("fig10_efficiency.png"),
        help="the PNG written (default: fig10_efficiency.png)",
    )
    ap.add_argument(
        "--quick",
        action="store_true",
        help=f"simulate {QUICK_DURATION:g} s instead of {DURATION:g} s",
    )
    args = ap.parse_args(argv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from scoutsim import load_parameters, simulate
    from scoutsim._core.model import actuator
    from scoutsim._core.model.packing import robot_array
    from scoutsim.names import LEG_NAMES
    from scoutsim.parameters import DEFAULT_FRICTION_COEFFICIENT

    const, table = load_parameters(args.robot)
    lossy = const.replace(gearbox_idle_loss_torque=IDLE, gearbox_load_loss_coefficient=C_LOAD)
    duration = QUICK_DURATION if args.quick else DURATION
    step_from = max(STEADY_FROM, duration - STEP_BEFORE_END)
    kw = dict(duration=duration, model="II", friction_coefficient=DEFAULT_FRICTION_COEFFICIENT)
    runs = {
        "constant efficiency": simulate(const, table, **kw),
        "idle + load losses": simulate(lossy, table, **kw),
    }
    for name, res in runs.items():
        if res.outcome != "completed":
            raise SystemExit(f"{name}: run {res.outcome} at t = {res.t_end:.3f} s")
    # N eta K_T of each leg: the torque per ampere the experiment's estimate assumes
    k_t = {leg: const.leg(leg).torque_per_amp for leg in LEG_NAMES}

    fig, axs = plt.subplots(2, 2, figsize=(10, 6.4))
    print(
        f"{'':<22} {'leg':<6} {'low-torque samples':>18} {'mean |tau_est|':>15} "
        f"{'mean |tau_est - tau_out|':>25}"
    )
    for j, leg in enumerate(LEG_NAMES):
        ax = axs[0, j]
        for (name, res), style in zip(runs.items(), ("-", "--")):
            k = one_step(res, leg, step_from)
            t = res.t[k] - res.t[k[0]]
            est = k_t[leg] * res.motor_current(leg)[k]
            ax.plot(t, est, style, lw=1.2, label=f"{name}: N eta K_T i")
            if name != "constant efficiency":
                ax.plot(t, res.hip_torque_applied(leg)[k], ":", lw=1.2, label=f"{name}: delivered")
                st = res.leg_state(leg)[k]
                ax.step(
                    t,
                    np.where(st == 0, 30, np.where(st == 2, 20, 10)),
                    "k",
                    lw=0.6,
                    where="post",
                    label="leg state (flight / brake / retraction)",
                )
            # low-torque statistics over the whole steady part
            m = res.t > STEADY_FROM
            e_all = k_t[leg] * res.motor_current(leg)[m]
            d_all = res.hip_torque_applied(leg)[m]
            low = np.abs(e_all) < LOW
            n_low = int(low.sum())
            mean_est = np.mean(np.abs(e_all[low])) if n_low else math.nan
            mean_err = np.mean(np.abs(e_all[low] - d_all[low])) if n_low else math.nan
            print(f"{name:<22} {leg:<6} {n_low:>18} {mean_est:>13.3f} N m {mean_err:>21.3f} N m")
        ax.set_title(f"{leg} leg, one step (paper Fig. 10 layout)", fontsize=9)
        ax.set_xlabel("time since lift-off [s]")
        ax.set_ylabel("hip torque per leg [N m]")
        ax.axhspan(-LOW, LOW, color="0.9", zorder=0)
        ax.legend(fontsize=6.5, loc="lower left")

    # motoring efficiency against the delivered torque, per leg (one curve if they agree)
    P = robot_array(lossy, "I")
    curves = []
    for i, leg in enumerate(LEG_NAMES):
        one = const.leg(i)
        cur = np.linspace(0.01, one.current_limit, 400)
        tau_out = np.array([actuator.delivered_torque(c, MOTORING_SPEED, i, P) for c in cur])
        eff = tau_out / (one.gear_ratio * one.torque_constant * cur)
        curves.append((leg, one, tau_out, eff))
    (_, back, tau_b, eff_b), (_, front, tau_f, eff_f) = curves
    if (
        np.array_equal(tau_b, tau_f)
        and np.array_equal(eff_b, eff_f)
        and back.efficiency == front.efficiency
    ):
        curves = [("both legs", back, tau_b, eff_b)]
    ax = axs[1, 0]
    top = 0.0
    for label, one, tau_out, eff in curves:
        top = max(top, tau_out.max())
        (line,) = ax.plot(tau_out, 100 * eff, label=f"{label}: idle + load losses (motoring)")
        ax.axhline(
            100 * one.efficiency,
            color=line.get_color(),
            ls="--",
            label=f"{label}: constant {one.gearbox_efficiency:.0%} x {one.sprocket_efficiency:.0%}",
        )
    ax.set_xlim(0, top)
    ax.set_ylim(0, 80)
    ax.set_xlabel("delivered torque per leg [N m]")
    ax.set_ylabel("efficiency [%]")
    ax.axvspan(0, LOW, color="0.9", zorder=0)
    ax.legend(fontsize=7)
    ax.set_title(f"tau_idle = {IDLE} N m, c_load = {C_LOAD} (illustrative)", fontsize=9)

    # gait metrics
    ax = axs[1, 1]
    ax.axis("off")
    keys = (
        "mean_speed_m_s",
        "stride_frequency_hz",
        "duty_factor_back",
        "duty_factor_front",
        "pitch_max_deg",
        "pitch_min_deg",
        "height_max_m",
        "height_min_m",
        "max_belt_deflection_deg",
    )
    sums = {n: r.summary() for n, r in runs.items()}
    rows = []
    print(f"\n{'gait metric (steady)':<26}" + "".join(f"{n:>22}" for n in runs) + f"{'change':>10}")
    for key in keys:
        a, b = (sums[n].get(key) for n in runs)
        ch = (b - a) / abs(a) * 100 if (a not in (None, 0) and b is not None) else math.nan
        rows.append([key, _fmt(a), _fmt(b), f"{_fmt(ch, '+.1f')} %"])
        print(f"{key:<26}{_fmt(a):>22}{_fmt(b):>22}{_fmt(ch, '.1f'):>9}%")
    tab = ax.table(
        cellText=rows,
        colLabels=["metric", "constant", "losses", "change"],
        loc="center",
        cellLoc="right",
    )
    tab.auto_set_font_size(False)
    tab.set_fontsize(7)
    tab.scale(1, 1.2)
    ax.set_title("gait metrics, Model II, steady strides", fontsize=9)
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=110)
    print(f"\nwrote {args.out}")


if __name__ == "__main__":
    main()
