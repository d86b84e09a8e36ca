"""Directional derivatives of the model's right-hand side in closed form (compiled).

Forward mode, one direction at a time: each module here is the derivative of the module
of :mod:`scoutsim._core.model` of the same name. A function ``name_t`` takes the primal
values of ``name`` (as the evaluation computed them) and the tangents of its inputs along
one direction (suffix ``_t``: the derivative along the direction, in the input's units per
unit of the direction), and returns or adds the tangent of its result. Parameters enter
through ``P_t``, the tangent of the packed parameter array (zero for a direction in the
state alone). Where the primal has a kink (a limit, a stop, a friction's sign), the
derivative is that of the branch the primal took.
"""
