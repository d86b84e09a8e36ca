"""ParameterError, and how values and unknown names are written in its messages."""

from __future__ import annotations

import difflib
import math
import numbers
import typing


class ParameterError(ValueError):
    """A parameter value, unit, key or file is not acceptable.

    Parameters
    ----------
    message : str
        Human-readable explanation naming the field, the offending value and what is allowed.
    field : str or None, optional
        Name of the offending field, when there is one.
    """

    def __init__(self, message: str, field: str | None = None):
        super().__init__(message)
        self.field = field


def format_value(x: object) -> str:
    """Short, noise-free text for a value (``-1.0``, ``95.0``, ``nan``, ``2``, ``true``)."""
    if isinstance(x, bool):
        return "true" if x else "false"
    if isinstance(x, numbers.Integral):
        return str(int(x))
    if isinstance(x, numbers.Real):
        x = float(x)
        return repr(x) if not math.isfinite(x) else repr(float(f"{x:.12g}"))
    return repr(x)


def format_bound(x: float) -> str:
    return f"{x:.12g}"


def unknown_name_error(
    name: str, context: str, candidates: typing.Iterable[str], kind: str = "parameter"
) -> ParameterError:
    """Error for an unknown key or section, suggesting the closest valid name."""
    candidates = list(candidates)
    close = difflib.get_close_matches(name, candidates, n=1, cutoff=0.6)
    hint = f"did you mean '{close[0]}'?" if close else f"valid names: {', '.join(candidates)}"
    return ParameterError(f"unknown {kind} '{name}' {context}; {hint}", name)
