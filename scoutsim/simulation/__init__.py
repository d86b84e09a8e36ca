"""A run: :func:`simulate` (:mod:`.simulator`) and what it is made of: the run put
together for the compiled core (:mod:`.assembly`), the engine that drives the core in
chunks (:mod:`.engine`), the start of a run as the core takes it
(:mod:`.initial_conditions`), the integrator settings (:mod:`.integrator`), what a run
needs before it starts (:mod:`.budgets`) and a run streamed to disk (:mod:`.streaming`)."""

from .integrator import IntegratorSettings
from .simulator import ControllerError, Recording, Sensors, simulate

__all__ = ["simulate", "Recording", "ControllerError", "Sensors", "IntegratorSettings"]
