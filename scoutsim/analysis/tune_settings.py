"""The settings of a tuning (:func:`scoutsim.analysis.tune.tune`), in three bundles: what it
minimises and under which constraints (:class:`TuneGoal`), the runs of every evaluation
(:class:`TuneRuns`) and how CMA-ES searches (:class:`TuneSearch`); the keywords of
``tune()`` set on them, and the checks of their values.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from ..parameters import DEFAULT_FRICTION_COEFFICIENT, RobotParameters
from .tune_evaluation import AGGREGATES, OBJECTIVES


@dataclass(frozen=True)
class TuneGoal:
    """What a tuning minimises, and under which constraints (:mod:`scoutsim.analysis.tune`).

    Attributes
    ----------
    objective : one of :data:`OBJECTIVES`.
    target : the steady speed of the ``"speed"`` objective [m/s] (None for the others).
    aggregate : one of :data:`AGGREGATES`: the worst or the mean of the scenarios' scores.
    max_belt_deflection [rad], max_current [A], min_speed [m/s] : optional constraints
        (None: not constrained).
    """

    objective: str = "speed"
    target: float | None = None
    aggregate: str = "worst"
    max_belt_deflection: float | None = None
    max_current: float | None = None
    min_speed: float | None = None


@dataclass(frozen=True)
class TuneRuns:
    """The runs of every evaluation: the base robot and controller, run for ``duration`` on
    each scenario, the product of ``models`` (or ``model``), ``floors`` and ``starts``.

    Attributes
    ----------
    model, models : the model of every run, or a list of models (default Model II).
    floors : toe friction coefficients mu [-] (default: the default floor, 1.0).
    starts : :class:`~scoutsim.InitialState` s (default: the default start).
    duration : simulated time of every run [s] (default 20).
    robot : base RobotParameters (default Scout II's).
    controller : ControllerParameters (Table I), ``"pitch-feedback"``, a
        PitchFeedbackController, a user's CompiledController or Python controller (defined
        at the top level of a module the workers can import), or a user's factory
        ``"MODULE:FACTORY"`` / ControllerSpec (it gets each candidate's robot and
        controller parameters); default Table I.
    """

    model: str = "II"
    models: list | None = None
    floors: list | None = None
    starts: list | None = None
    duration: float = 20.0
    robot: RobotParameters | None = None
    controller: object = None

    def scenarios(self) -> list:
        """The scenarios of every evaluation, ``{"model", "friction", "initial_state"}``:
        the product of the models, floors and starts (each its default if not given)."""
        models = list(self.models) if self.models else [self.model]
        floors = list(self.floors) if self.floors else [DEFAULT_FRICTION_COEFFICIENT]
        starts = list(self.starts) if self.starts else [None]
        return [
            {"model": m, "friction": mu, "initial_state": s}
            for m in models
            for mu in floors
            for s in starts
        ]


@dataclass(frozen=True)
class TuneSearch:
    """How CMA-ES searches.

    Attributes
    ----------
    budget : the most evaluations; the tuning runs whole generations of ``population``
        candidates, ``budget // population`` of them, and ends sooner if CMA-ES converges.
    seed : the optimiser's random seed.
    sigma : its initial step, a fraction of each parameter's range.
    population : candidates per generation, at least 4 (default: CMA-ES's 4 + 3 ln n for
        n parameters).
    refine : evaluations of a gradient refinement after CMA-ES (0: none; its gradient is
        the periodic gait's, :mod:`scoutsim.analysis.tune_refinement`), on top of
        ``budget``; its trust radius starts at ``sigma``.
    """

    budget: int = 200
    seed: int = 0
    sigma: float = 0.1
    population: int | None = None
    refine: int = 0


def bundles(goal, runs, search, fields: dict) -> list:
    """[goal, runs, search] (the bundles given, or their defaults) with every keyword of
    ``fields`` set on the bundle that has a field of that name; TypeError naming a
    keyword that none has."""
    known: set = set()
    out = []
    for given, cls in ((goal, TuneGoal), (runs, TuneRuns), (search, TuneSearch)):
        names = {f.name for f in dataclasses.fields(cls)}
        known |= names
        out.append(
            dataclasses.replace(
                cls() if given is None else given, **{k: v for k, v in fields.items() if k in names}
            )
        )
    unknown = [k for k in fields if k not in known]
    if unknown:
        raise TypeError(f"tune() got an unexpected keyword argument {unknown[0]!r}")
    return out


def check_settings(goal: TuneGoal, search: TuneSearch) -> None:
    """ValueError naming a setting that is not allowed: the objective, its target, the
    aggregate, CMA-ES's initial step ``sigma``, a constraint's bound."""
    objective, target, aggregate = goal.objective, goal.target, goal.aggregate
    max_belt_deflection, max_current, min_speed = (
        goal.max_belt_deflection,
        goal.max_current,
        goal.min_speed,
    )
    sigma = search.sigma
    if isinstance(search.refine, bool) or not isinstance(search.refine, int) or search.refine < 0:
        raise ValueError(
            f"refine = {search.refine!r} is not allowed: must be a whole number >= 0 "
            "(evaluations of the gradient refinement)"
        )
    if objective not in OBJECTIVES:
        raise ValueError(
            f"objective = {objective!r} is not allowed: must be one of {', '.join(OBJECTIVES)}"
        )
    if objective == "speed":
        if target is None or not (math.isfinite(target) and target > 0):
            raise ValueError(
                f"target = {target!r} is not allowed: the speed objective needs "
                "a target speed > 0 [m/s]"
            )
    elif target is not None:
        raise ValueError(f"target is only allowed with objective 'speed', not {objective!r}")
    if aggregate not in AGGREGATES:
        raise ValueError(f"aggregate = {aggregate!r} is not allowed: must be worst or mean")
    if not (math.isfinite(sigma) and 0 < sigma <= 1):
        raise ValueError(
            f"sigma = {sigma!r} is not allowed: must be in (0, 1] (a fraction "
            "of each parameter's range)"
        )
    for name, v in (
        ("max_belt_deflection", max_belt_deflection),
        ("max_current", max_current),
        ("min_speed", min_speed),
    ):
        if v is not None and not (math.isfinite(v) and v > 0):
            raise ValueError(f"{name} = {v!r} is not allowed: must be a number > 0")
