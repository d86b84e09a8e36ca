"""Mutation study of the model's laws (docs/testing.md, "Mutation study").

Each mutant is one textual change to one law of the compiled core (a wrong sign, a wrong
factor, a dropped term, a value read from the other leg). For each mutant the package tree
is copied into a temporary directory (without .git and the __pycache__ directories, so the
compiled core is compiled afresh from the mutated sources), the change is applied there,
and the physics tests run against that copy. A mutant is *killed* if any test fails, and
*killed by its aimed test* if one of the tests written for that law is among the failures.

    python tools/mutation_study.py                  # every mutant, a Markdown table at the end
    python tools/mutation_study.py --only leg_damper_sign
    python tools/mutation_study.py --list           # the mutants, nothing run
    python tools/mutation_study.py --jobs 2 --json results.json

Each mutant recompiles the Numba core in its copy (1-3 minutes) before its tests run, so
the whole study takes a while (docs/testing.md gives the time it took).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: the physics tests every mutant is run against
TEST_FILES = (
    "tests/_core/model",
    "tests/_core/numerics",
    "tests/control",
    "tests/analysis/test_energy.py",
    "tests/test_paper_claims.py",
)
#: a mutant whose tests have not finished after this long [s] is stopped and reported as
#: "timeout" (a law broken so that a run never ends counts as killed)
TIMEOUT_S = 3600.0
#: a single test (its setup or its call) still running after this long [s] fails with
#: ``TestTimeout``: a broken law can make a run (or the SciPy reference integration of
#: tests/_core/numerics/test_against_scipy.py) stiff enough to take hours; the unmutated
#: tests take at most about 30 s each once the core is compiled
TEST_TIMEOUT_S = 180.0
#: the pytest plugin that enforces TEST_TIMEOUT_S, written into each copy
_PLUGIN = """\
import os
import signal

import pytest

LIMIT = float(os.environ["MUTATION_TEST_TIMEOUT"])


class TestTimeout(Exception):
    pass


def _expire(signum, frame):
    raise TestTimeout(f"still running after {LIMIT:.0f} s")


def _timed():
    old = signal.signal(signal.SIGALRM, _expire)
    signal.setitimer(signal.ITIMER_REAL, LIMIT)
    return old


def _untimed(old):
    signal.setitimer(signal.ITIMER_REAL, 0.0)
    signal.signal(signal.SIGALRM, old)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_setup(item):
    old = _timed()
    try:
        yield
    finally:
        _untimed(old)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_call(item):
    old = _timed()
    try:
        yield
    finally:
        _untimed(old)
"""
#: compiles the core of a copy before its tests run (so that no test's time limit
#: includes the compilation)
_WARM_UP = (
    "import scoutsim\n"
    "for m in ('ideal', 'I', 'II', 'passive'):\n"
    "    scoutsim.simulate(duration=0.05, model=m, energy=True)\n"
)

LAWS = "tests/_core/model/test_laws.py::"
MORE = "tests/_core/model/test_laws_more.py::"
ENERGY = "tests/analysis/test_energy.py::"
IMPACT = "tests/_core/model/test_impact_laws.py::"
GAINS = "tests/control/test_per_leg_gains.py::"
BOUNDING = "tests/control/test_bounding.py::"
EOM = "tests/_core/model/test_eom_independent.py::"
ACTUATOR = "tests/_core/model/test_actuator.py::"


@dataclass(frozen=True)
class Mutant:
    """One change to one law: ``old`` (found exactly once in ``file``) becomes ``new``;
    ``aimed``: node-id prefixes of the tests written for that law."""

    name: str
    law: str
    file: str
    old: str
    new: str
    aimed: tuple[str, ...]
    equivalent: str = ""  # why the change cannot alter behaviour, if it cannot


MUTANTS = [
    # --- actuator: motor, amplifier, battery (model/actuator.py) ----------------------
    Mutant(
        "back_emf_sign",
        "back-EMF in the torque-speed line of the amplifier current",
        "scoutsim/_core/model/actuator.py",
        "        v_lo = (-vb - P[P_KW + leg] * omega_m) / r\n"
        "        v_hi = (vb - P[P_KW + leg] * omega_m) / r\n",
        "        v_lo = (-vb + P[P_KW + leg] * omega_m) / r\n"
        "        v_hi = (vb + P[P_KW + leg] * omega_m) / r\n",
        (LAWS + "test_amplifier_current_follows_the_torque_speed_line_and_the_limit",),
    ),
    Mutant(
        "current_limit_doubled",
        "current limit |i| <= i_max of the amplifier",
        "scoutsim/_core/model/actuator.py",
        "    imax = P[P_IMAX + leg]\n    ic = cmd_torque / torque_per_amp(leg, P)\n    if ic < -imax:\n",
        "    imax = 2.0 * P[P_IMAX + leg]\n    ic = cmd_torque / torque_per_amp(leg, P)\n"
        "    if ic < -imax:\n",
        (LAWS + "test_amplifier_current_follows_the_torque_speed_line_and_the_limit",),
    ),
    Mutant(
        "current_limit_removed",
        "current limit |i| <= i_max of the amplifier",
        "scoutsim/_core/model/actuator.py",
        "    if ic < -imax:\n        ic = -imax\n    if ic > imax:\n        ic = imax\n",
        "",
        (LAWS + "test_amplifier_current_follows_the_torque_speed_line_and_the_limit",),
    ),
    Mutant(
        "efficiency_dropped",
        "delivered torque N eta K_T i (torque per ampere)",
        "scoutsim/_core/model/actuator.py",
        "    return P[P_N + leg] * P[P_ETA + leg] * P[P_KT + leg]\n",
        "    return P[P_N + leg] * P[P_KT + leg]\n",
        (
            LAWS + "test_delivered_torque_is_n_eta_kt_i",
            LAWS + "test_amplifier_current_follows_the_torque_speed_line_and_the_limit",
        ),
    ),
    Mutant(
        "battery_resistance_doubled",
        "battery V_b = V_oc - R_b P / V_b",
        "scoutsim/_core/model/actuator.py",
        "    disc = voc * voc - 4.0 * rb * pw\n",
        "    disc = voc * voc - 8.0 * rb * pw\n",
        (LAWS + "test_battery_voltage_sags_with_the_power_drawn",),
    ),
    Mutant(
        "gear_idle_loss_sign_motoring",
        "transmission losses: idle loss while motoring",
        "scoutsim/_core/model/actuator.py",
        "        mag = (abs(tau0) - idle) / (1.0 + cl)\n",
        "        mag = (abs(tau0) + idle) / (1.0 + cl)\n",
        (
            ACTUATOR + "test_delivered_torque_function_directions",
            ACTUATOR + "test_losses_reduce_delivered_torque_in_motoring_samples",
        ),
    ),
    Mutant(
        "gear_loss_sign_back_driven",
        "transmission losses: idle loss while back-driven",
        "scoutsim/_core/model/actuator.py",
        "    return -d * (abs(tau0) + idle) / (1.0 - cl)",
        "    return -d * (abs(tau0) - idle) / (1.0 - cl)",
        (ACTUATOR + "test_delivered_torque_function_directions",),
    ),
    Mutant(
        "gear_load_loss_sign",
        "transmission losses: load-dependent loss while motoring",
        "scoutsim/_core/model/actuator.py",
        "        mag = (abs(tau0) - idle) / (1.0 + cl)\n",
        "        mag = (abs(tau0) - idle) / (1.0 - cl)\n",
        (
            ACTUATOR + "test_delivered_torque_function_directions",
            ACTUATOR + "test_losses_reduce_delivered_torque_in_motoring_samples",
        ),
    ),
    Mutant(
        "loss_clip_boundary",
        "transmission losses: motoring torque never reversed",
        "scoutsim/_core/model/actuator.py",
        "        if mag < 0.0:\n            mag = 0.0\n",
        "        if mag <= 0.0:\n            mag = 0.0\n",
        (),
        equivalent="at mag = 0 both versions return 0 (the sign of tau0 is applied "
        "to a zero magnitude): no input gives a different output",
    ),
    Mutant(
        "speed_line_test_back_emf_sign",
        "back-EMF in the stiff-factor test of the torque-speed line",
        "scoutsim/_core/model/actuator.py",
        "    v_lo = (-vb - P[P_KW + leg] * omega_m) / r_a\n"
        "    v_hi = (vb - P[P_KW + leg] * omega_m) / r_a\n",
        "    v_lo = (-vb + P[P_KW + leg] * omega_m) / r_a\n"
        "    v_hi = (vb + P[P_KW + leg] * omega_m) / r_a\n",
        (),
        equivalent="on_speed_line only decides whether the back-EMF damping joins the "
        "implicit (stiff) part of the ARK step; for Scout II the motor-side "
        "damping rate is about 400 /s with or without it, below "
        "STIFF_MOTOR_RATE = 1000 /s, so the columns stay zero either way "
        "(equivalent for the robots the tests use, not for a robot with a "
        "light gear train)",
    ),
    # --- telescopic leg (model/leg.py) -------------------------------------------------
    Mutant(
        "leg_damper_sign",
        "leg damper c l' in the axial leg force",
        "scoutsim/_core/model/leg.py",
        "    return k * (l0 - ll) - c * ld - fc * sat\n",
        "    return k * (l0 - ll) + c * ld - fc * sat\n",
        (
            MORE + "test_axial_leg_force_is_spring_damper_and_friction",
            EOM + "test_stance_constrained_dynamics",
        ),
    ),
    Mutant(
        "leg_damper_doubled",
        "leg damper c l' in the axial leg force",
        "scoutsim/_core/model/leg.py",
        "    return k * (l0 - ll) - c * ld - fc * sat\n",
        "    return k * (l0 - ll) - 2.0 * c * ld - fc * sat\n",
        (
            MORE + "test_axial_leg_force_is_spring_damper_and_friction",
            EOM + "test_stance_constrained_dynamics",
        ),
    ),
    Mutant(
        "leg_damper_angle_doubled",
        "angle-dependent leg damper c (1 + a phi^2)",
        "scoutsim/_core/model/leg.py",
        "    return P[P_C + leg] * (1.0 + P[P_LEG_C_ANGLE + leg] * phi * phi)\n",
        "    return P[P_C + leg] * (1.0 + 2.0 * P[P_LEG_C_ANGLE + leg] * phi * phi)\n",
        (MORE + "test_axial_leg_force_is_spring_damper_and_friction",),
    ),
    Mutant(
        "leg_friction_sign",
        "leg sliding-joint Coulomb friction",
        "scoutsim/_core/model/leg.py",
        "    return k * (l0 - ll) - c * ld - fc * sat\n",
        "    return k * (l0 - ll) - c * ld + fc * sat\n",
        (MORE + "test_axial_leg_force_is_spring_damper_and_friction",),
    ),
    Mutant(
        "leg_friction_doubled",
        "leg sliding-joint Coulomb friction",
        "scoutsim/_core/model/leg.py",
        "    return k * (l0 - ll) - c * ld - fc * sat\n",
        "    return k * (l0 - ll) - c * ld - 2.0 * fc * sat\n",
        (MORE + "test_axial_leg_force_is_spring_damper_and_friction",),
    ),
    Mutant(
        "leg_friction_side_load_doubled",
        "leg friction level F_0 + c_s |tau_hip| / l",
        "scoutsim/_core/model/leg.py",
        "    return P[P_LEG_FRIC + leg] + P[P_LEG_FRIC_SIDE + leg] * abs(tau_hip) / ll\n",
        "    return P[P_LEG_FRIC + leg] + 2.0 * P[P_LEG_FRIC_SIDE + leg] * abs(tau_hip) / ll\n",
        (MORE + "test_axial_leg_force_is_spring_damper_and_friction",),
    ),
    # --- Model II hip units (model/transmission.py, belt.py, backlash.py) ---------------
    Mutant(
        "belt_damper_sign",
        "belt damper c_b (alpha' - phi')",
        "scoutsim/_core/model/transmission.py",
        "    damper = P[P_CB + leg] * (dq[IALB + leg] - dq[IPHB + leg])\n",
        "    damper = -P[P_CB + leg] * (dq[IALB + leg] - dq[IPHB + leg])\n",
        (
            MORE + "test_belt_torque_is_spring_with_dead_zone_and_damper",
            EOM + "test_stance_constrained_dynamics",
        ),
    ),
    Mutant(
        "belt_damper_doubled",
        "belt damper c_b (alpha' - phi')",
        "scoutsim/_core/model/transmission.py",
        "    damper = P[P_CB + leg] * (dq[IALB + leg] - dq[IPHB + leg])\n",
        "    damper = 2.0 * P[P_CB + leg] * (dq[IALB + leg] - dq[IPHB + leg])\n",
        (
            MORE + "test_belt_torque_is_spring_with_dead_zone_and_damper",
            EOM + "test_stance_constrained_dynamics",
        ),
    ),
    Mutant(
        "belt_backlash_dropped",
        "belt spring dead zone (backlash)",
        "scoutsim/_core/model/backlash.py",
        "    return 0.5 * P[P_BACKLASH + leg]\n",
        "    return 0.0 * P[P_BACKLASH + leg]\n",
        (MORE + "test_belt_torque_is_spring_with_dead_zone_and_damper",),
    ),
    Mutant(
        "joint_viscous_sign",
        "motor-joint viscous friction b_J w_m",
        "scoutsim/_core/model/transmission.py",
        "    tf = P[P_B_J + leg] * om\n",
        "    tf = -P[P_B_J + leg] * om\n",
        (LAWS + "test_slipping_motor_joint_friction", EOM + "test_stance_constrained_dynamics"),
    ),
    Mutant(
        "joint_coulomb_doubled",
        "motor-joint Coulomb friction tau_s while slipping",
        "scoutsim/_core/model/transmission.py",
        "        tf += P[P_TAU_S + leg] * mode\n",
        "        tf += 2.0 * P[P_TAU_S + leg] * mode\n",
        (LAWS + "test_slipping_motor_joint_friction", EOM + "test_stance_constrained_dynamics"),
    ),
    # --- events: stiction breakaway (numerics/events.py) ------------------------------
    Mutant(
        "stiction_breakaway_doubled",
        "stiction breakaway |holding torque| = tau_s",
        "scoutsim/_core/numerics/events.py",
        "(tau_s - abs(aux[o + A_HOLD])) / tau_s",
        "(2.0 * tau_s - abs(aux[o + A_HOLD])) / tau_s",
        (LAWS + "test_stiction_breaks_away_at_its_level",),
    ),
    # --- ground contact (model/contact.py) --------------------------------------------
    Mutant(
        "toe_slide_friction_direction",
        "sliding toe friction mu F_n against the motion",
        "scoutsim/_core/model/contact.py",
        "        gt = -sig * gn\n",
        "        gt = sig * gn\n",
        (LAWS + "test_sliding_toe_friction_opposes_its_motion",),
    ),
    # --- touchdown impact (model/impact.py) -------------------------------------------
    Mutant(
        "impact_belt_not_rigid",
        "Model II impact: rigid belt (alpha' = phi' after it)",
        "scoutsim/_core/model/impact.py",
        "        if gear:\n            # rigid belt over the impact",
        "        if False:\n            # rigid belt over the impact",
        (
            IMPACT + "test_model_ii_belt_is_rigid_through_the_impact",
            IMPACT + "test_independent_impact_solve_gives_recorded_velocities_and_impulse",
        ),
    ),
    Mutant(
        "impact_toe_row_lever_sign",
        "impact: pinned toe's velocity across the leg is zero",
        "scoutsim/_core/model/impact.py",
        "            R[nr, ITH] = sL * math.sin(q[IPHB + leg]) + l[leg]\n",
        "            R[nr, ITH] = -sL * math.sin(q[IPHB + leg]) + l[leg]\n",
        (
            IMPACT + "test_no_slip_touchdown_stops_toe_across_leg_and_positions_do_not_jump",
            IMPACT + "test_angular_momentum_about_contact_point_is_conserved",
            IMPACT + "test_independent_impact_solve_gives_recorded_velocities_and_impulse",
        ),
    ),
    Mutant(
        "impact_impulse_record_doubled",
        "impact: recorded normal impulse",
        "scoutsim/_core/model/impact.py",
        "            out[leg * NIMP_LEG + IMP_NORMAL] += lam * math.sin(g)\n",
        "            out[leg * NIMP_LEG + IMP_NORMAL] += 2.0 * lam * math.sin(g)\n",
        (
            IMPACT + "test_recorded_impulse_is_change_of_linear_momentum",
            IMPACT + "test_independent_impact_solve_gives_recorded_velocities_and_impulse",
        ),
    ),
    # --- controller (control/bounding.py) ---------------------------------------------
    Mutant(
        "flight_kp_of_other_leg",
        "controller: per-leg flight gain (back gets front's)",
        "scoutsim/control/bounding.py",
        "    a[C_KPF_B] = c.flight_kp_back\n",
        "    a[C_KPF_B] = c.flight_kp_front\n",
        (
            GAINS + "test_flight_servo_uses_each_legs_gains_and_touchdown_angle",
            BOUNDING + "test_flight_and_stance_brake_are_pd_servos",
        ),
    ),
    Mutant(
        "brake_gains_of_other_leg",
        "controller: per-leg stance-brake gains",
        "scoutsim/control/bounding.py",
        "C[C_KPB_B + 2 * leg] * (sweep - ang) - C[C_KDB_B + 2 * leg] * rate",
        "C[C_KPB_B + 2 * (1 - leg)] * (sweep - ang) - C[C_KDB_B + 2 * (1 - leg)] * rate",
        (
            GAINS + "test_stance_brake_uses_each_legs_gains_and_sweep_limit",
            BOUNDING + "test_flight_and_stance_brake_are_pd_servos",
        ),
    ),
    Mutant(
        "touchdown_angle_of_other_leg",
        "controller: per-leg touchdown angle",
        "scoutsim/control/bounding.py",
        "(C[C_TD_B + leg] - ang)",
        "(C[C_TD_B + 1 - leg] - ang)",
        (
            GAINS + "test_flight_servo_uses_each_legs_gains_and_touchdown_angle",
            BOUNDING + "test_flight_and_stance_brake_are_pd_servos",
        ),
    ),
    Mutant(
        "sweep_limit_of_other_leg",
        "controller: per-leg sweep limit",
        "scoutsim/control/bounding.py",
        "        sweep = C[C_SW_B + leg]\n",
        "        sweep = C[C_SW_B + 1 - leg]\n",
        (
            GAINS + "test_sweep_limit_is_each_legs_own",
            GAINS + "test_stance_brake_uses_each_legs_gains_and_sweep_limit",
            BOUNDING + "test_flight_and_stance_brake_are_pd_servos",
        ),
    ),
    Mutant(
        "eq4_before_eq5",
        "controller: eq. (5) (no positive torque) before eq. (4)",
        "scoutsim/control/bounding.py",
        "    if tau >= 0.0:\n        tau = 0.0\n    elif tau < -lim:\n        tau = -lim\n",
        "    if abs(tau) > lim:\n        tau = -lim\n    elif tau >= 0.0:\n        tau = 0.0\n",
        (BOUNDING + "test_stance_retraction_never_commands_a_positive_torque_eq_5",),
    ),
    Mutant(
        "retraction_slope_sign",
        "controller: retraction slope A of eq. (2)",
        "scoutsim/control/bounding.py",
        "    tau = -C[C_TAU_MAX + leg] + C[C_SLOPE + leg] * rate\n",
        "    tau = -C[C_TAU_MAX + leg] - C[C_SLOPE + leg] * rate\n",
        (BOUNDING + "test_stance_retraction_commands_the_motor_torque_speed_line_eqs_2_3",),
    ),
    # --- gravity on the leg bodies (model/rigid_body.py) ------------------------------
    Mutant(
        "leg_gravity_dropped_in_potential",
        "gravity on the leg bodies: potential energy",
        "scoutsim/_core/model/rigid_body.py",
        "        e += ml * grav * yc\n",
        "        e += 0.0 * ml * grav * yc\n",
        (
            EOM + "test_potential_energy",
            EOM + "test_gravity_force_passive",
            ENERGY + "test_balance_closes",
        ),
    ),
    Mutant(
        "leg_gravity_dropped_on_leg_angle",
        "gravity on the leg bodies: force on phi",
        "scoutsim/_core/model/rigid_body.py",
        "        Q[IPHB + leg] -= mlg * d * sg\n",
        "        Q[IPHB + leg] -= 0.0 * mlg * d * sg\n",
        (
            EOM + "test_gravity_force_passive",
            EOM + "test_flight_dynamics_with_velocity",
            ENERGY + "test_balance_closes",
        ),
    ),
]


@dataclass
class Outcome:
    mutant: Mutant
    failed: list[str] = field(default_factory=list)
    timed_out: list[str] = field(default_factory=list)
    passed: int = 0
    timeout: bool = False
    seconds: float = 0.0
    tail: str = ""

    @property
    def killed(self) -> bool:
        return self.timeout or bool(self.failed)

    @property
    def by_aimed(self) -> bool:
        return any(f.startswith(a) for f in self.failed for a in self.mutant.aimed)


def copy_tree(dest: Path) -> None:
    """The package tree (work tree as it is, tests and tools included) without version
    control and compiled caches."""
    shutil.copytree(
        ROOT,
        dest,
        ignore=shutil.ignore_patterns(
            ".git", "__pycache__", "*.pyc", ".pytest_cache", "*.egg-info"
        ),
    )


def apply(tree: Path, m: Mutant) -> None:
    """Apply mutant ``m`` in ``tree``; its snippet must occur exactly once."""
    path = tree / m.file
    text = path.read_text()
    n = text.count(m.old)
    if n != 1:
        raise SystemExit(
            f"mutant {m.name}: the snippet occurs {n} times in {m.file}, not once:\n{m.old}"
        )
    path.write_text(text.replace(m.old, m.new))


_NODE = re.compile(r"^(FAILED|ERROR) (\S+)")
_COUNT = re.compile(r"(\d+) passed")


def run_mutant(
    m: Mutant | None, timeout: float = TIMEOUT_S, test_timeout: float = TEST_TIMEOUT_S
) -> Outcome:
    """Copy, mutate (``m`` None: the unmutated tree), run the physics tests; which failed."""
    t0 = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="scoutsim-mutant-") as tmp:
        tree = Path(tmp) / "scoutsim-tree"
        copy_tree(tree)
        if m is not None:
            apply(tree, m)
        env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
        env["PYTHONPATH"] = str(tree)
        env["PYTHONDONTWRITEBYTECODE"] = "1"
        env["MUTATION_TEST_TIMEOUT"] = str(test_timeout)
        (tree / "_mutation_timeout.py").write_text(_PLUGIN)
        try:  # a mutant that breaks even a short run fails in its tests, not here
            subprocess.run(
                [sys.executable, "-c", _WARM_UP],
                cwd=tree,
                env=env,
                capture_output=True,
                timeout=timeout,
            )
        except subprocess.TimeoutExpired:
            pass
        cmd = [
            sys.executable,
            "-m",
            "pytest",
            "-q",
            "-p",
            "no:cacheprovider",
            "-p",
            "_mutation_timeout",
            "--tb=no",
            "-rfE",
            *TEST_FILES,
        ]
        proc = subprocess.Popen(
            cmd,
            cwd=tree,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            start_new_session=True,
        )
        out = Outcome(m if m is not None else Mutant("none", "", "", "", "", ()))
        try:
            text, _ = proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            text, _ = proc.communicate()
            out.timeout = True
        for line in text.splitlines():
            hit = _NODE.match(line)
            if hit:
                out.failed.append(hit.group(2))
                if "TestTimeout" in line:
                    out.timed_out.append(hit.group(2))
        counts = _COUNT.search(text.splitlines()[-1] if text.strip() else "")
        out.passed = int(counts.group(1)) if counts else 0
        out.tail = "\n".join(text.splitlines()[-3:])
    out.seconds = time.monotonic() - t0
    return out


def save(path: Path, outcomes: list[Outcome]) -> None:
    path.write_text(
        json.dumps(
            [
                {
                    "name": o.mutant.name,
                    "law": o.mutant.law,
                    "file": o.mutant.file,
                    "killed": o.killed,
                    "by_aimed": o.by_aimed,
                    "timeout": o.timeout,
                    "failed": o.failed,
                    "timed_out": o.timed_out,
                    "passed": o.passed,
                    "seconds": round(o.seconds, 1),
                }
                for o in outcomes
            ],
            indent=1,
        )
    )


def _short(nodeid: str) -> str:
    return nodeid.split("/")[-1]


def _grouped(o: Outcome) -> list[tuple[str, int, bool]]:
    """The failing tests of ``o`` by test function (parametrizations together): (name,
    number failed, any timed out, aimed), the aimed tests first."""
    groups: dict[str, list[str]] = {}
    for f in o.failed:
        groups.setdefault(_short(f).split("[")[0], []).append(f)
    aimed = [
        g for g, fs in groups.items() if any(f.startswith(a) for f in fs for a in o.mutant.aimed)
    ]
    order = aimed + [g for g in groups if g not in aimed]
    return [
        (g, len(groups[g]), any(f in o.timed_out for f in groups[g]), g in aimed) for g in order
    ]


def table(outcomes: list[Outcome], most: int = 3) -> str:
    """The Markdown table of the outcomes."""
    rows = [
        "| mutant | law | killed (tests failed) | by its aimed test | failing tests (**aimed**) |",
        "|---|---|---|---|---|",
    ]
    for o in outcomes:
        m = o.mutant
        if o.timeout:
            killed = "yes (stopped)"
        else:
            killed = f"yes ({len(o.failed)})" if o.failed else "**no**"
        aimed = "yes" if o.by_aimed else ("equivalent" if m.equivalent else "**no**")
        groups = _grouped(o)
        shown = ", ".join(
            ("**`{}`**" if a else "`{}`").format(g)
            + (f" x{n}" if n > 1 else "")
            + (" (timeout)" if t else "")
            for g, n, t, a in groups[:most]
        )
        if len(groups) > most:
            shown += f", {len(groups) - most} more"
        law = m.law.replace("|", "\\|")
        rows.append(f"| `{m.name}` | {law} | {killed} | {aimed} | {shown} |")
    return "\n".join(rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--only", action="append", metavar="NAME", help="run only this mutant (repeatable)"
    )
    ap.add_argument(
        "--baseline",
        action="store_true",
        help="run the unmutated tree first (every test must pass)",
    )
    ap.add_argument("--list", action="store_true", help="list the mutants and stop")
    ap.add_argument("--jobs", type=int, default=1, help="mutants run at the same time")
    ap.add_argument("--json", type=Path, help="write the outcomes to this file")
    ap.add_argument(
        "--table",
        type=Path,
        nargs="+",
        metavar="JSON",
        help="print the table of outcomes saved with --json, nothing run",
    )
    ap.add_argument(
        "--timeout",
        type=float,
        default=TIMEOUT_S,
        help="seconds after which a mutant's tests are stopped",
    )
    ap.add_argument(
        "--test-timeout",
        type=float,
        default=TEST_TIMEOUT_S,
        help="seconds after which one test fails as TestTimeout",
    )
    args = ap.parse_args(argv)
    names = {m.name for m in MUTANTS}
    assert len(names) == len(MUTANTS), "duplicate mutant names"
    chosen = MUTANTS
    if args.only:
        unknown = set(args.only) - names
        if unknown:
            ap.error(f"unknown mutant(s) {sorted(unknown)}; --list shows them")
        chosen = [m for m in MUTANTS if m.name in args.only]
    if args.table:
        by_name = {m.name: m for m in MUTANTS}
        saved = {d["name"]: d for f in args.table for d in json.loads(f.read_text())}
        outcomes = [
            Outcome(
                by_name[n],
                failed=d["failed"],
                passed=d["passed"],
                timed_out=d.get("timed_out", []),
                timeout=d["timeout"],
                seconds=d["seconds"],
            )
            for n, d in saved.items()
            if n in by_name
        ]
        order = [m.name for m in MUTANTS]
        outcomes.sort(key=lambda o: order.index(o.mutant.name))
        print(table(outcomes))
        print(
            f"\n{sum(o.killed for o in outcomes)} of {len(outcomes)} mutants killed, "
            f"{sum(o.by_aimed for o in outcomes)} by their aimed tests; "
            f"{sum(o.seconds for o in outcomes) / 60:.1f} min of mutant runs"
        )
        return 0
    for m in chosen:  # every snippet is checked before anything runs
        text = (ROOT / m.file).read_text()
        if text.count(m.old) != 1:
            raise SystemExit(
                f"mutant {m.name}: the snippet occurs {text.count(m.old)} "
                f"times in {m.file}, not once"
            )
    if args.list:
        for m in chosen:
            print(f"{m.name:36s} {m.file:34s} {m.law}")
        return 0
    t0 = time.monotonic()
    if args.baseline:
        base = run_mutant(None, args.timeout)
        print(
            f"baseline: {base.passed} passed, {len(base.failed)} failed ({base.seconds:.0f} s)",
            flush=True,
        )
        if base.killed:
            print("\n".join(base.failed) or base.tail)
            return 2

    done = []

    def one(m):
        o = run_mutant(m, args.timeout, args.test_timeout)
        print(
            f"{m.name}: {'killed' if o.killed else 'SURVIVED'}"
            f"{' by its aimed test' if o.by_aimed else ''}, {len(o.failed)} failed "
            f"({len(o.timed_out)} timed out), {o.passed} passed, {o.seconds:.0f} s",
            flush=True,
        )
        done.append(o)
        if args.json:  # after every mutant, so an interrupted study keeps its results
            save(args.json, done)
        return o

    with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        outcomes = list(pool.map(one, chosen))
    total = time.monotonic() - t0
    print()
    print(table(outcomes))
    print(
        f"\n{sum(o.killed for o in outcomes)} of {len(outcomes)} mutants killed, "
        f"{sum(o.by_aimed for o in outcomes)} by their aimed tests; {total / 60:.1f} min"
    )
    return 0 if all(o.by_aimed or o.mutant.equivalent for o in outcomes) else 1


if __name__ == "__main__":
    sys.exit(main())
