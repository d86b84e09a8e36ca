"""Integrator statistics: the slots of the stats array the compiled run fills, and their
names in ``SimulationResult.stats``."""

# integrator statistics slots
S_NFEV = 0
S_NSTEP = 1
S_NREJECT = 2
S_NEVENT = 3
S_NEND_SLIDE = 4  # end-of-stance slides (docs/specification.md section 3 consistency case)
S_NSTRUT = 5
S_MAX_FRICTION = 6  # largest |Ft|/Fn in stance with Fn above 5 % body weight
S_MAX_IMPULSE_RATIO = 7
S_HMIN = 8
S_HMAX = 9
S_NSTUB = 10  # toe-stub slides (toe_enters_ground)
NSTAT = 11
#: result.stats keys, in slot order
STAT_NAMES = (
    "rhs_evaluations",
    "steps",
    "rejected_steps",
    "events",
    "end_of_stance_slides",
    "strut_phases",
    "max_friction_ratio",
    "max_impact_impulse_ratio",
    "min_step_s",
    "max_step_s",
    "toe_stub_slides",
)
