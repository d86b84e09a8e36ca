"""On/off flags in the compiled core's float arrays.

Some slots of the float arrays hold a yes/no setting or outcome rather than a quantity:
the parameter array's ``P_MASSLESS``, ``P_TD_WORLD``, ``P_CLAMP_*`` and ``P_NO_SLIP``, the
evaluation summary's ``MT_KKT_OK`` and ``MT_SCHUR``, the outputs' ``A_KKT_OK``, the sensor
geometry's ``SG_*`` flags, the run loop's ``HW_*`` flags and the controller's
``C_ENABLED``. They are written as :data:`FLAG_ON` or :data:`FLAG_OFF` and read with
:func:`is_set` (compiled code) or :func:`flag_is_set` (Python code); both read a value
above one half as set.
"""

from __future__ import annotations

from ..._numba.jit import kernel

#: the value of a set flag
FLAG_ON = 1.0
#: the value of a cleared flag
FLAG_OFF = 0.0


def flag_is_set(flag) -> bool:
    """True if the flag slot value ``flag`` is set (written as :data:`FLAG_ON`)."""
    return flag > 0.5


@kernel(inline="always")
def is_set(flag):
    """True if the flag slot value ``flag`` is set (written as :data:`FLAG_ON`); the
    compiled twin of :func:`flag_is_set`, inlined into its callers."""
    return flag > 0.5
