"""``scoutsim orbit``: a periodic bounding orbit and its Floquet multipliers
(docs/orbits.md). With --passive, the conservative massless-leg model's bound through a
level-torso apex (touchdown angles solved for); otherwise the controlled robot's orbit,
found by Newton's method on the stride map sampled at the first control sample after the
back leg's lift-off, for any controller whose state scoutsim can read and set.

    scoutsim orbit [--passive] [--speed V] [--apex-height H] [--pitch-rate W]
                   [--model {ideal,I,II}] [--friction MU] [--duration S] [--robot FILE]
                   [--controller C] [--strides K] [--section {plant,controller}]
                   [--sensitivity NAME[,NAME...]|all] [--json]

Exit code 1 if no periodic orbit is found.
"""

from __future__ import annotations

import math
import sys

from ._common import (
    UsageError,
    add_controller_option,
    add_no_progress_option,
    add_parallel_options,
    controller_choice,
    controller_label,
    dumps,
    finite_float,
    load_parameters,
    make_controller,
    positive_int,
    progress_messages,
)
from ._given import refuse_given
from ._orbit_options import (
    CONTROLLED_ONLY,
    PARALLEL,
    PASSIVE_ONLY,
    add_controlled_orbit_options,
    add_passive_apex_options,
)

NAME = "orbit"


def register(sub, common) -> None:
    orbit = sub.add_parser(
        NAME,
        help="periodic bounding orbit and its Floquet multipliers (docs/orbits.md)",
        description="--passive: the conservative massless-leg model's periodic bound through "
        "a level-torso apex of the given speed, height and pitch rate; solves for "
        "the touchdown angles (from the world vertical) and prints them, the "
        "period, the multipliers of the apex return map and the map residual. "
        "Without --passive: the controlled robot's periodic orbit (Newton on the "
        "stride map sampled at the first control sample after the back leg's "
        "lift-off, started from a converged run; any --controller whose state "
        "scoutsim can read and set), its touchdown angles from the world "
        "vertical, period, Floquet multipliers and residual.",
    )
    orbit.add_argument(
        "--passive",
        action="store_true",
        help="the passive conservative model (massless legs, docs/orbits.md)",
    )
    add_passive_apex_options(orbit)
    orbit.add_argument(
        "--pitch-rate",
        type=finite_float,
        default=0.0,
        metavar="W",
        help="--passive: pitch rate at the apex [deg/s] (default: 0)",
    )
    add_controlled_orbit_options(orbit, "simulated time to the Newton start")
    orbit.add_argument(
        "--strides",
        type=positive_int,
        default=None,
        metavar="K",
        help="controlled: look for an orbit of K strides per period, a fixed point of the "
        "stride map's K-th iterate (default: the cycle the run settles on, read from 48 "
        "strides after 32 more)",
    )
    orbit.add_argument(
        "--sensitivity",
        metavar="NAME[,NAME...]|all",
        default=None,
        help="also the sensitivities of the orbit to these parameters, by the implicit "
        "function theorem on the fixed point, and their elasticities [%% per %%]. "
        "Controlled: the speed, stride frequency, duty factors, pitch and height "
        "extremes, electrical power, cost of transport and spectral radius, to "
        "robot.<field> (robot.<field>.back / .front: one leg of a per-leg field; a "
        "robot whose legs differ in it takes only these), controller.<field> of the "
        "Table I law, friction_coefficient (SI; a _deg suffix on an angle gives its value "
        "and derivatives in degrees); the parameters shared out to --workers "
        "processes or a --scheduler's cluster. --passive: the touchdown angles, period, "
        "mean speed and spectral radius, from exact derivatives, to robot.leg_stiffness, "
        "robot.leg_rest_length, robot.torso_mass, robot.torso_inertia, robot.hip_spacing",
    )
    orbit.add_argument(
        "--jacobian",
        choices=("exact", "fd"),
        default=None,
        help="how the return map's Jacobian (the multipliers, Newton's steps) is obtained: "
        "exact (derivatives carried with the run through its steps, events and control "
        "samples; the default, where the controller runs in the compiled loop: the Table I "
        "law, a CompiledController, --passive) or fd (differences of whole strides, the "
        "check; the default for a Python controller). The JSON says which in "
        "jacobian_method",
    )
    orbit.add_argument(
        "--section",
        choices=("plant", "controller"),
        default=None,
        help="controlled: the section, the first control sample after the back leg's "
        "lift-off (plant, any controller) or the sample after the Table I controller "
        "detects it (controller; the default for the Table I law); the orbit is the same",
    )
    orbit.add_argument(
        "--robot",
        metavar="FILE",
        help="TOML robot/controller file with the layout of "
        "scoutsim/data/scout2.toml (--passive: its massless-leg "
        "configuration); unset entries keep the Scout II defaults",
    )
    add_controller_option(orbit)
    add_parallel_options(orbit)
    orbit.add_argument("--json", action="store_true", help="print one JSON object")
    add_no_progress_option(orbit)
    orbit.set_defaults(func=execute)


def execute(args) -> int:
    from ..analysis.controlled_orbit import ControlledOrbit, NewtonSettings, controlled_fixed_point
    from ..analysis.passive_orbits import PassiveOrbit, passive_bounding_orbit
    from ..analysis.poincare import MapError
    from ..control.dispatch import ControllerStateError

    robot, cparams = load_parameters(args.robot)
    law, cparams = controller_choice(args.controller, cparams)
    controller = cparams
    if args.passive and args.controller != "table-i":
        raise UsageError(
            "--controller is not allowed with --passive (the passive model has no controller)"
        )
    if args.passive:
        refuse_given(
            args,
            CONTROLLED_ONLY + PARALLEL,
            "with --passive (the passive model's orbit has no controller, floor or settling "
            "run, and its exact sensitivities are computed in one process)",
        )
    else:
        refuse_given(args, PASSIVE_ONLY, "without --passive (the passive model's apex state)")
        if not args.sensitivity:
            refuse_given(
                args,
                PARALLEL,
                "without --sensitivity (the orbit is found in one process; the "
                "sensitivities' parameters are what is shared out)",
            )
    if not args.passive:
        controller = make_controller(law, cparams, robot)
    names = _sensitivity_names(args, controller, robot)
    if not args.passive and args.jacobian == "exact":
        _check_exact(args, controller, robot)
    orb: PassiveOrbit | ControlledOrbit
    try:
        if args.passive:
            orb = passive_bounding_orbit(
                args.speed,
                args.apex_height,
                math.radians(args.pitch_rate),
                robot=robot,
                jacobian=args.jacobian or "exact",
            )
        else:
            orb = controlled_fixed_point(
                model=args.model,
                friction_coefficient=args.friction,
                robot=robot,
                controller=controller,
                settle_duration=args.duration,
                progress=progress_messages(args, NAME),
                strides=args.strides,
                section=args.section,
                newton=NewtonSettings(jacobian=args.jacobian),
            )
    except ValueError as exc:
        if args.section is None or not str(exc).startswith("section ="):
            raise
        raise UsageError(f"--section {args.section}: {exc}") from exc  # not this controller's
    except ControllerStateError as exc:
        raise UsageError(
            f"--controller {args.controller}: {exc}; scoutsim orbit restarts strides from "
            "section states, which include the controller's own state"
        ) from exc
    except MapError as exc:
        print(f"scoutsim orbit: {exc}", file=sys.stderr)
        return 1
    d = orb.to_dict()
    sens = None
    if names and isinstance(orb, ControlledOrbit):
        from ..analysis.orbit_sensitivity import orbit_sensitivities
        from ..analysis.sweep_points import si_name

        sens, metrics = orbit_sensitivities(
            orb,
            [si_name(n)[0] for n in names],
            progress=progress_messages(args, NAME),
            workers=args.workers,
            scheduler=args.scheduler,
        )
        d["metrics"] = metrics
        d["sensitivities"] = {n: _as_named(n, sens[si_name(n)[0]].to_dict()) for n in names}
    elif names and isinstance(orb, PassiveOrbit):
        from ..analysis.passive_sensitivity import passive_orbit_sensitivities

        sens, metrics = passive_orbit_sensitivities(orb, names, robot=robot)
        d["metrics"] = metrics
        d["sensitivities"] = {n: s.to_dict() for n, s in sens.items()}
    if args.json:
        print(dumps(d))
    elif args.passive:
        _print_passive(args, orb, d)
        if sens is not None:
            _print_sensitivities(d, PASSIVE_COLUMNS, "touchdown_angle_back")
    else:
        _print_controlled(args, orb, d)
        if sens is not None:
            _print_sensitivities(d, CONTROLLED_COLUMNS, "mean_speed_m_s")
    return 0


def _sensitivity_names(args, controller, robot) -> list[str] | None:
    """The parameters of --sensitivity (None without it); UsageError naming a bad one."""
    if args.sensitivity is None:
        return None
    if args.passive:
        from ..analysis.passive_sensitivity import PASSIVE_SENSITIVITY_PARAMETERS

        known = list(PASSIVE_SENSITIVITY_PARAMETERS)
        everything = known
    else:
        from ..analysis.orbit_sensitivity import sensitivity_parameter_names
        from ..names import LEG_NAMES
        from ..parameters import PER_LEG_FIELDS
        from ..parameters.robot_fields import robot_value

        known = sensitivity_parameter_names(controller, robot)
        # (one leg's value of a per-leg field may be named on any robot; both legs at
        # once only where they are equal, which robot_value checks)
        everything = sensitivity_parameter_names(controller) + [
            f"robot.{f}.{leg}" for f in PER_LEG_FIELDS for leg in LEG_NAMES
        ]
    if args.sensitivity.strip() == "all":
        return known
    from ..analysis.sweep_points import si_name
    from ..parameters import field_dimension

    names = [n.strip() for n in args.sensitivity.split(",") if n.strip()]
    for n in names:
        si, scale = si_name(n)
        parts = si.split(".")  # section, field[, leg]
        if (
            scale != 1.0
            and si in everything
            and len(parts) > 1
            and field_dimension(parts[1]) == "angle"
        ):
            n = si  # (an angle in degrees: computed in SI, shown in degrees)
        if n not in everything:
            import difflib

            near = difflib.get_close_matches(n, known, n=1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            allowed = (
                ", ".join(known)
                if args.passive
                else "robot.<field> (robot.<field>.back / .front for one leg of a per-leg "
                "field), controller.<field> (the Table I law's; a _deg suffix on an angle "
                "takes degrees) or friction_coefficient"
            )
            raise UsageError(
                f"--sensitivity {n!r} is not allowed: must be 'all' or names of {allowed}{hint}"
            )
        if not args.passive and n.startswith("robot."):
            try:
                robot_value(robot, n.partition(".")[2], "robot.")
            except ValueError as e:
                raise UsageError(f"--sensitivity: {e}") from None
    return names


def _as_named(name: str, sens: dict) -> dict:
    """A parameter's sensitivities (``ParameterSensitivity.to_dict``, SI) in the unit its
    name gives: for a ``_deg`` angle the value and the radius's step in degrees and the
    derivatives per degree (the elasticities have no unit)."""
    from ..analysis.sweep_points import si_name

    scale = si_name(name)[1]  # [rad per deg] for a _deg name, else 1
    if scale == 1.0:
        return sens
    return sens | {
        "value": sens["value"] / scale,
        "derivative": {m: v * scale for m, v in sens["derivative"].items()},
        "spectral_radius_step": sens["spectral_radius_step"] / scale,
    }


#: the elasticities printed for a controlled and a passive orbit
CONTROLLED_COLUMNS = ("mean_speed_m_s", "electrical_power_w", "cost_of_transport",
                      "spectral_radius")  # fmt: skip
PASSIVE_COLUMNS = ("touchdown_angle_back", "touchdown_angle_front", "period_s",
                   "spectral_radius")  # fmt: skip


def _print_sensitivities(d, cols, lead: str) -> None:
    """The elasticities [% per %] of the main metrics ``cols``, the parameters that move
    ``lead`` most first."""
    rows = [(n, s) for n, s in d["sensitivities"].items() if s["status"] == "ok"]

    def size(row) -> float:
        e = row[1]["elasticity"][lead]
        return -1.0 if e is None or math.isnan(e) else abs(e)

    rows.sort(key=size, reverse=True)
    w = max(20, max(len(c) for c in cols) + 2)
    print("  elasticities [% per %] at the orbit (implicit function theorem):")
    print(f"    {'parameter':<40}" + "".join(f"{c:>{w}}" for c in cols))
    for n, s in rows:
        print(f"    {n:<40}" + "".join(f"{s['elasticity'][c]:>{w}.4f}" for c in cols))
    print(
        "    (nan: a parameter at 0, whose elasticity is not defined; its derivative is in --json)"
    )
    for n, s in d["sensitivities"].items():
        if s["status"] != "ok":
            print(f"    {n}: {s['status']}")


def _print_passive(args, orb, d) -> None:
    print(
        f"scoutsim orbit: passive model, apex speed {args.speed:g} m/s, height "
        f"{args.apex_height:g} m, pitch rate {args.pitch_rate:g} deg/s, torso level"
    )
    print(
        f"  touchdown angle back / front  {d['touchdown_angle_back_deg']:.6f} / "
        f"{d['touchdown_angle_front_deg']:.6f} deg (from the world vertical)"
    )
    print(f"  period                        {d['period_s']:.6f} s")
    print(
        "  eigenvalues                   "
        + ", ".join(f"{m.real:.6f}{m.imag:+.6f}j" for m in orb.multipliers)
        + f"  (|.| = {', '.join(f'{abs(m):.4f}' for m in orb.multipliers)})"
    )
    print(f"  residual max|P(z)-z|          {d['residual']:.2e}")


def _print_controlled(args, orb, d) -> None:
    import numpy as np

    from ..analysis.controlled_orbit import NOISE_MULTIPLE

    law = controller_label(args.controller)
    print(
        f"scoutsim orbit: model {args.model}, {law} controller, mu = "
        f"{args.friction:g}; section: {d['section']}; Newton on the sampled stride map"
    )
    print(
        f"  touchdown angle back / front  {d['touchdown_angle_back_deg']:.4f} / "
        f"{d['touchdown_angle_front_deg']:.4f} deg (from the world vertical, on the orbit)"
    )
    print(
        f"  period                        {d['period_s']:.6f} s "
        f"({d['strides_per_period']} stride(s)), mean speed {d['mean_speed_m_s']:.4f} m/s"
    )
    print(
        f"  lift-off from a sample boundary {d['section_margin_s'] * 1e6:.2f} us (a change "
        "that moves it further moves the section by a sample)"
    )
    for name, v in d["state"].items():
        print(f"    {name:<18} {v: .9f}")
    mags = np.abs(orb.multipliers)
    big = np.argsort(-mags)[:6]
    print(
        "  largest multipliers           "
        + ", ".join(f"{orb.multipliers[i].real:.4f}{orb.multipliers[i].imag:+.4f}j" for i in big)
        + f"  (spectral radius {mags.max():.4f}: {'stable' if orb.stable else 'unstable'})"
    )
    print(
        f"  residual max|P(z)-z|          {d['residual']:.2e} after {d['iterations']} "
        "Newton iterations"
        + (
            ""
            if math.isnan(orb.residual_noise)
            else f" (above the tolerance, within {NOISE_MULTIPLE:g} x the map's own "
            f"rounding noise {orb.residual_noise:.1e}: accepted)"
        )
    )


def _check_exact(args, controller, robot) -> None:
    """UsageError if ``--jacobian exact`` is asked of a controller the compiled loop does
    not run (a Python controller: its stride map is differenced)."""
    from ..control.dispatch import plan_controller

    if plan_controller(controller, args.model, robot).kind not in ("builtin", "compiled"):
        raise UsageError(
            f"--jacobian exact: controller {args.controller} runs in Python, outside the "
            "compiled loop that carries the derivatives; use --jacobian fd (its default)"
        )
