"""Robot and controller parameters (docs/specification.md sections 2, 4, 5, 6; paper Tables I-III).

All fields are SI (angles in rad). The defaults live once, as data, in
``scoutsim/data/scout2.toml`` with unit and provenance; :func:`load_robot` and
:func:`load_controller` read that file, apply a user's TOML file and/or Python overrides,
convert units once; constructing a parameter set validates every value (and warns of
values far outside what a robot of Scout II's kind has).

Mass and hip-unit quantities are per *physical* leg. A virtual leg lumps
``legs_per_virtual_leg`` physical legs (docs/specification.md section 1); the compiled model multiplies
per-leg quantities by that number in exactly one place (the compiled model, ``scoutsim._core.model``).

Modules (each imports only those above it):

* ``errors``: :class:`ParameterError` and how its messages write values and unknown names.
* ``units``: :data:`UNITS` (unit strings, dimensions, SI factors) and :func:`quantity_to_si`.
* ``packaged``: reading the packaged ``scout2.toml`` and the decorator that makes its values
  the dataclasses' defaults.
* ``schema``: every field's section, type, unit, dimension, default, source and plausible
  range (:func:`field_dimension`, :func:`plausible_range`), and :data:`PER_LEG_FIELDS`.
* ``plausibility``: :class:`ImplausibleParameterWarning`, for a value far outside what a
  robot of Scout II's kind has, naming the likely unit slip.
* ``field_rules``: allowed ranges (sign rules and physical bounds: :func:`allowed_range`,
  :func:`closed_range`, :func:`physical_limit`) and the type and range check of each field
  by itself.
* ``field_couplings``: the rules that couple fields (within a robot, within a controller,
  between the two).
* ``quick_scan``: the single-field checks by comparison alone, for a set that passes them.
* ``validation``: the checks the dataclasses run when they are constructed, and
  :func:`validate_robot`, :func:`validate_controller`, :func:`validate_parameters`.
* ``robot``, ``controller``: :class:`RobotParameters` (with its derived quantities; the
  leg, hip-unit and motor quantities of :data:`PER_LEG_FIELDS` may differ between the back
  and front legs) and :class:`ControllerParameters`; constructing either checks it.
* ``robot_fields``: a robot's field by name, one leg's value of a per-leg field included
  (``leg_stiffness.front``): :func:`robot_value`, :func:`robot_with_value`.
* ``environment``: :class:`Environment` (the floor), :data:`DEFAULT_FRICTION_COEFFICIENT`,
  :func:`floor_label`.
* ``files``: :func:`load_robot`, :func:`load_controller`, :func:`load_parameters` (TOML files
  and overrides, :data:`SECTIONS`, :data:`SEPARATE_SECTIONS`), :func:`parameter_table`,
  :func:`to_dict` / :func:`from_dict`.
"""

from .controller import ControllerParameters
from .environment import DEFAULT_FRICTION_COEFFICIENT, Environment, floor_label
from .files import (
    SECTIONS,
    SEPARATE_SECTIONS,
    from_dict,
    load_controller,
    load_parameters,
    load_robot,
    parameter_table,
    to_dict,
)
from .parameter_error import ParameterError
from .plausibility import ImplausibleParameterWarning, plausibility_warnings_off
from .robot import PER_LEG_FIELDS, RobotParameters
from .robot_fields import robot_value, robot_with_value
from .schema import field_dimension, plausible_range
from .units import UNITS, quantity_to_si
from .validation import (
    allowed_range,
    closed_range,
    physical_limit,
    validate_controller,
    validate_parameters,
    validate_robot,
)

__all__ = [
    "DEFAULT_FRICTION_COEFFICIENT",
    "UNITS",
    "SECTIONS",
    "SEPARATE_SECTIONS",
    "Environment",
    "floor_label",
    "RobotParameters",
    "PER_LEG_FIELDS",
    "robot_value",
    "robot_with_value",
    "ControllerParameters",
    "ParameterError",
    "ImplausibleParameterWarning",
    "plausibility_warnings_off",
    "quantity_to_si",
    "field_dimension",
    "plausible_range",
    "physical_limit",
    "allowed_range",
    "closed_range",
    "validate_robot",
    "validate_controller",
    "validate_parameters",
    "load_robot",
    "load_controller",
    "load_parameters",
    "parameter_table",
    "to_dict",
    "from_dict",
]
