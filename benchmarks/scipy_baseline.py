"""The same Scout II model integrated by SciPy's solve_ivp (RK45) in plain Python.

Run with NUMBA_DISABLE_JIT=1 so that scoutsim's model functions (right-hand side, event
functions, mode transitions, controller) execute as ordinary Python: this is what a user
would get by writing the model for solve_ivp. solve_ivp integrates each 1 ms control period
with the current modes' event functions; at a plant event the mode transition is applied
and integration restarts, exactly as in scoutsim's compiled loop.

Usage: NUMBA_DISABLE_JIT=1 python benchmarks/scipy_baseline.py DURATION_S [MODEL] [MU]
Prints one JSON line: simulated seconds, wall seconds, event count, final state.
"""

import json
import math
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp

from scoutsim import ControllerParameters, RobotParameters, default_initial_state
from scoutsim._core.model import layout as L
from scoutsim._core.model.evaluate import evaluate
from scoutsim._core.model.kinematics import project_state
from scoutsim._core.model.packing import robot_array
from scoutsim._core.model.sensor_readings import read_encoders
from scoutsim._core.numerics.events import event_values
from scoutsim._core.numerics.stats import NSTAT
from scoutsim._core.numerics.transitions import apply_event, settle
from scoutsim.control.bounding import C_SENSE_ALPHA, bounding_step, controller_array
from scoutsim.simulation.initial_conditions import initial_state_vector


def run(duration, model="II", rtol=1e-8, atol=1e-9, friction_coefficient=math.inf):
    robot, ctrl = RobotParameters(), ControllerParameters()
    P = robot_array(robot, model, friction_coefficient=friction_coefficient)
    C = controller_array(ctrl, robot)
    s = initial_state_vector(default_initial_state(), robot, ctrl, (0, 0), True)
    mi = np.zeros(L.NMI, dtype=np.int64)
    mi[L.MI_MOTOR_B : L.MI_MOTOR_B + 2] = L.STUCK
    mi[L.MI_SLIDE_DIR_B : L.MI_SLIDE_DIR_B + 2] = 1
    mf = np.zeros(L.NMF)
    ls = np.zeros(2, dtype=np.int64)
    cmd = np.zeros(2)
    tr = np.zeros(2, dtype=np.int64)
    y = np.zeros(L.NSN)
    ds = np.zeros(L.NS)
    aux = np.zeros(L.NAUX)
    ev = np.zeros((100000, L.NEVREC))
    stats = np.zeros(NSTAT)
    imp = np.zeros(7)
    nev = 0
    dt = ctrl.control_period
    n = int(round(duration / dt))
    t = 0.0
    fell = False

    def f(tt, y):
        out = np.zeros(L.NS)
        evaluate(y, P, mi, mf, cmd, out, aux)
        return out

    def make_event(k):
        def e(tt, y):
            a = np.zeros(L.NAUX)
            d = np.zeros(L.NS)
            yy = y.copy()
            project_state(yy, P, mi, mf)
            evaluate(yy, P, mi, mf, cmd, d, a)
            v = np.zeros(L.NEV)
            event_values(yy, a, P, mi, v)
            return v[k]

        e.terminal = True
        e.direction = -1
        return e

    events = [make_event(k) for k in range(L.NEV)]
    for k in range(n):
        t = k * dt
        read_encoders(s, C[C_SENSE_ALPHA] > 0.5, y)
        bounding_step(y, C, ls, cmd, tr)
        nev = settle(t, s, P, mi, mf, cmd, ds, aux, ev, nev, stats)
        t_end = (k + 1) * dt
        while t < t_end - 1e-15:
            sol = solve_ivp(f, (t, t_end), s, method="RK45", rtol=rtol, atol=atol, events=events)
            s = sol.y[:, -1].copy()
            project_state(s, P, mi, mf)
            t = sol.t[-1]
            if sol.status == 1:
                kk = next(i for i, te in enumerate(sol.t_events) if len(te))
                evaluate(s, P, mi, mf, cmd, ds, aux)
                nev, ok = apply_event(kk, t, s, P, mi, mf, aux, ev, nev, stats, imp)
                if kk >= L.EV_FALL_HEIGHT:
                    fell = True
                    break
                nev = settle(t, s, P, mi, mf, cmd, ds, aux, ev, nev, stats)
        if fell:
            break
    return t, nev, s


if __name__ == "__main__":
    dur = float(sys.argv[1])
    model = sys.argv[2] if len(sys.argv) > 2 else "II"
    mu = float(sys.argv[3]) if len(sys.argv) > 3 else math.inf
    rtol = float(sys.argv[4]) if len(sys.argv) > 4 else 1e-8
    atol = float(sys.argv[5]) if len(sys.argv) > 5 else 1e-9
    t0 = time.perf_counter()
    t, nev, s = run(dur, model, rtol=rtol, atol=atol, friction_coefficient=mu)
    wall = time.perf_counter() - t0
    print(
        json.dumps(
            {
                "simulated_s": t,
                "wall_s": wall,
                "events": nev,
                "x": float(s[0]),
                "y": float(s[1]),
                "theta": float(s[2]),
            }
        )
    )
