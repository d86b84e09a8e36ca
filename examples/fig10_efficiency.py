"""Fig. 10 with a torque-dependent gearbox efficiency (docs/identification.md, section 4).

The paper (Sec. IV.B) estimates hip torques from motor current with the constant maximum
efficiency, ``N eta K_T i``, and suspects that the gearbox's efficiency drop at low torque
explains why Model II and experiment differ most where the torque is small. This script
runs Model II with the paper's constant 68 % (x 96 % sprocket) and with the
torque-dependent losses of docs/model.md ("Transmission losses"), then

* plots, for one steady step of each virtual leg, the torque the experiment would have
  reported (current-estimated, N eta K_T i) for both runs, and the torque the lossy
  transmission actually delivered (paper Fig. 10 layout, with the leg-state square wave);
* plots the motoring efficiency tau_out / (N K_T i) against the delivered torque;
* prints the low-torque numbers and the gait metrics of both runs.

    PYTHONPATH=. python examples/fig10_efficiency.py [--out docs/img/fig10_efficiency.png]

The loss parameters (idle 0.8 N m at the leg, load coefficient 0.05) are illustrative,
not identified: Maxon gives the efficiency drop only qualitatively.
"""

from __future__ import annotations

import argparse

import numpy as np

IDLE = 0.8        # gearbox_idle_loss_torque [N m] at the leg, per physical leg
C_LOAD = 0.05     # gearbox_load_loss_coefficient [-]
DURATION = 8.0
LOW = 5.0         # |torque| [N m] below which a sample counts as low-torque


def one_step(res, leg, t_from=5.0):
    """Indices of one step of ``leg``: from a lift-off after t_from to the next."""
    lo = res.event_times("liftoff", leg)
    lo = lo[lo > t_from]
    return np.flatnonzero((res.t >= lo[0]) & (res.t < lo[1]))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/img/fig10_efficiency.png")
    args = ap.parse_args(argv)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from scoutsim import simulate
    from scoutsim.model import actuator
    from scoutsim.model.packing import robot_array
    from scoutsim.parameters import RobotParameters

    const = RobotParameters()
    lossy = const.replace(gearbox_idle_loss_torque=IDLE, gearbox_load_loss_coefficient=C_LOAD)
    from scoutsim.cli import SCOUT_FLOOR_FRICTION          # the default floor (mu = 1.0)
    kw = dict(duration=DURATION, model="II", friction_coefficient=SCOUT_FLOOR_FRICTION)
    runs = {"constant 65.3 %": simulate(const, **kw),
            "idle + load losses": simulate(lossy, **kw)}
    for name, res in runs.items():
        if res.outcome != "completed":
            raise SystemExit(f"{name}: run {res.outcome} at t = {res.t_end:.3f} s")
    k_t = const.gear_ratio * const.efficiency * const.torque_constant     # N eta K_T

    fig, axs = plt.subplots(2, 2, figsize=(10, 6.4))
    print(f"{'':<22} {'leg':<6} {'low-torque samples':>18} {'mean |tau_est|':>15} "
          f"{'mean |tau_est - tau_out|':>25}")
    for j, leg in enumerate(("back", "front")):
        ax = axs[0, j]
        for (name, res), style in zip(runs.items(), ("-", "--")):
            k = one_step(res, leg)
            t = res.t[k] - res.t[k[0]]
            est = k_t * res.motor_current(leg)[k]
            ax.plot(t, est, style, lw=1.2, label=f"{name}: N eta K_T i")
            if name != "constant 65.3 %":
                ax.plot(t, res.hip_torque_applied(leg)[k], ":", lw=1.2,
                        label=f"{name}: delivered")
                st = res.leg_state(leg)[k]
                ax.step(t, np.where(st == 0, 30, np.where(st == 2, 20, 10)), "k", lw=0.6,
                        where="post", label="leg state (flight / brake / retraction)")
            # low-torque statistics over the whole steady part
            m = (res.t > 2.0)
            e_all = k_t * res.motor_current(leg)[m]
            d_all = res.hip_torque_applied(leg)[m]
            low = np.abs(e_all) < LOW
            print(f"{name:<22} {leg:<6} {int(low.sum()):>18} "
                  f"{np.mean(np.abs(e_all[low])):>13.3f} N m "
                  f"{np.mean(np.abs(e_all[low] - d_all[low])):>21.3f} N m")
        ax.set_title(f"{leg} leg, one step (paper Fig. 10 layout)", fontsize=9)
        ax.set_xlabel("time since lift-off [s]")
        ax.set_ylabel("hip torque per leg [N m]")
        ax.axhspan(-LOW, LOW, color="0.9", zorder=0)
        ax.legend(fontsize=6.5, loc="lower left")

    # motoring efficiency against the delivered torque
    P = robot_array(lossy, "I")
    cur = np.linspace(0.01, const.current_limit, 400)
    tau_out = np.array([actuator.delivered_torque(i, 500.0, P) for i in cur])
    eff = tau_out / (const.gear_ratio * const.torque_constant * cur)
    ax = axs[1, 0]
    ax.plot(tau_out, 100 * eff, label="idle + load losses (motoring)")
    ax.axhline(100 * const.efficiency, color="k", ls="--", label="paper: constant 68 % x 96 %")
    ax.set_xlim(0, tau_out.max())
    ax.set_ylim(0, 80)
    ax.set_xlabel("delivered torque per leg [N m]")
    ax.set_ylabel("efficiency [%]")
    ax.axvspan(0, LOW, color="0.9", zorder=0)
    ax.legend(fontsize=7)
    ax.set_title(f"tau_idle = {IDLE} N m, c_load = {C_LOAD} (illustrative)", fontsize=9)

    # gait metrics
    ax = axs[1, 1]
    ax.axis("off")
    keys = ("mean_speed_m_s", "stride_frequency_hz", "duty_factor_back", "duty_factor_front",
            "pitch_max_deg", "pitch_min_deg", "height_max_m", "height_min_m",
            "max_belt_deflection_deg")
    sums = {n: r.summary() for n, r in runs.items()}
    rows = []
    print(f"\n{'gait metric (steady)':<26}" + "".join(f"{n:>22}" for n in runs) + f"{'change':>10}")
    for key in keys:
        a, b = (sums[n].get(key) for n in runs)
        ch = (b - a) / abs(a) * 100 if (a not in (None, 0) and b is not None) else float("nan")
        rows.append([key, f"{a:.4g}", f"{b:.4g}", f"{ch:+.1f} %"])
        print(f"{key:<26}{a:>22.4g}{b:>22.4g}{ch:>9.1f}%")
    tab = ax.table(cellText=rows, colLabels=["metric", "constant", "losses", "change"],
                   loc="center", cellLoc="right")
    tab.auto_set_font_size(False)
    tab.set_fontsize(7)
    tab.scale(1, 1.2)
    ax.set_title("gait metrics, Model II, steady strides", fontsize=9)
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print(f"\nwrote {args.out}")


if __name__ == "__main__":
    main()
