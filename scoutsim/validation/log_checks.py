"""The checks a log passes as it is loaded: its header (every required column, one of each
set of alternatives, no duplicates) and its values (no gaps, uniform increasing time
[s], leg states 0/1/2, ranges plausible in the declared units, no isolated spikes).

Errors
------
:func:`~scoutsim.validation.log_reading.load_log` raises :class:`LogError` naming the file,
the column and the row (data rows count from 1; for CSV the file line is given too) for:
unreadable file, missing or duplicate columns, non-numeric cells, NaN / empty gaps,
non-increasing or non-uniform time, leg states other than 0/1/2, values whose range betrays
wrong units (angles beyond 2 pi rad suggest degrees, lengths above 5 m suggest millimetres,
...), and isolated spikes in the position-like signals
(:func:`~scoutsim.validation.log_spikes.isolated_spikes`: one to three samples far from the
median of their neighbours while the neighbours agree among themselves; laser ranges,
pitch, height, leg angles, leg lengths).
"""

from __future__ import annotations

import math

import numpy as np

from ..names import LegState
from .log_format import ALTERNATIVE_COLUMNS, COLUMN_UNITS, REQUIRED_COLUMNS, LogError, row_text
from .log_spikes import check_spikes

__all__ = ["UNIFORM_TOLERANCE"]

# (max |value| plausible in the declared unit, what a larger value suggests)
_PLAUSIBLE = {
    "laser_front_m": (5.0, "millimetres (expected metres)"),
    "laser_back_m": (5.0, "millimetres (expected metres)"),
    "height_m": (5.0, "millimetres (expected metres)"),
    "leg_length_back_m": (5.0, "millimetres (expected metres)"),
    "leg_length_front_m": (5.0, "millimetres (expected metres)"),
    "pitch_rad": (2 * math.pi, "degrees (expected radians)"),
    "phi_back_rad": (2 * math.pi, "degrees (expected radians)"),
    "phi_front_rad": (2 * math.pi, "degrees (expected radians)"),
    "dphi_back_rad_s": (200.0, "deg/s (expected rad/s)"),
    "dphi_front_rad_s": (200.0, "deg/s (expected rad/s)"),
    "current_back_a": (200.0, "milliamperes (expected amperes)"),
    "current_front_a": (200.0, "milliamperes (expected amperes)"),
    "torque_back_nm": (500.0, "N mm (expected N m)"),
    "torque_front_nm": (500.0, "N mm (expected N m)"),
}
_NONNEGATIVE = (
    "laser_front_m",
    "laser_back_m",
    "height_m",
    "leg_length_back_m",
    "leg_length_front_m",
)

#: Relative deviation of a time step from the median step that counts as non-uniform.
UNIFORM_TOLERANCE = 0.01


def check_columns(path, names):
    seen = set()
    for j, n in enumerate(names):
        if n == "":
            raise LogError(f"{path}: column {j + 1} of the header has no name", path)
        if n in seen:
            raise LogError(f"{path}: column '{n}' appears twice in the header", path, n)
        seen.add(n)
    missing = [c for c in REQUIRED_COLUMNS if c not in seen]
    if missing:
        import difflib

        hints = []
        unknown = [n for n in names if n not in COLUMN_UNITS]
        for c in missing:
            close = difflib.get_close_matches(c, unknown, n=1)
            if close:
                hints.append(f"'{c}' (found '{close[0]}': wrong name or unit?)")
            else:
                hints.append(f"'{c}'")
        raise LogError(
            f"{path}: missing column(s) {', '.join(hints)}; a log needs "
            f"{', '.join(REQUIRED_COLUMNS)} (see scoutsim.validation.logs)",
            path,
            missing[0],
        )
    for options in ALTERNATIVE_COLUMNS.values():
        if not any(all(c in seen for c in opt) for opt in options):
            present = [c for opt in options for c in opt if c in seen]
            want = " or ".join("(" + ", ".join(opt) + ")" for opt in options)
            first_missing = next(c for c in options[0] if c not in seen)
            if present:
                opt = next(o for o in options if any(c in o for c in present))
                first_missing = next(c for c in opt if c not in seen)
            raise LogError(
                f"{path}: missing column '{first_missing}': a log needs {want}"
                + (f" (found only {', '.join(present)})" if present else ""),
                path,
                first_missing,
            )


def validate_values(path, cols: dict, header_line: int | None, repairs: list | None = None):
    """Check values; raise LogError at the first problem (isolated spikes: repaired into
    ``repairs`` if it is a list, :func:`check_spikes`)."""
    n = len(cols["t"])
    if n < 2:
        raise LogError(f"{path}: only {n} data row(s); a log needs at least 2", path, "t")
    used = [c for c in COLUMN_UNITS if c in cols]
    # NaN gaps
    for c in used:
        bad = ~np.isfinite(cols[c])
        if bad.any():
            k0 = int(np.argmax(bad))
            k1 = k0
            while k1 + 1 < n and bad[k1 + 1]:
                k1 += 1
            what = (
                "NaN/empty/infinite value"
                if k1 == k0
                else f"gap of {k1 - k0 + 1} NaN/empty/infinite values through data row {k1 + 1}"
            )
            raise LogError(
                f"{path}: column '{c}', {row_text(k0 + 1, header_line)}: {what} "
                f"({int(bad.sum())} in the column); fill or cut the gap",
                path,
                c,
                k0 + 1,
            )
    t = cols["t"]
    dt = np.diff(t)
    if np.any(dt <= 0):
        k = int(np.argmax(dt <= 0)) + 1
        raise LogError(
            f"{path}: column 't', {row_text(k + 1, header_line)}: time does not "
            f"increase (t = {t[k]:.9g} s after {t[k - 1]:.9g} s)",
            path,
            "t",
            k + 1,
        )
    h = float(np.median(dt))
    dev = np.abs(dt - h) > UNIFORM_TOLERANCE * h
    if dev.any():
        k = int(np.argmax(dev)) + 1
        raise LogError(
            f"{path}: column 't', {row_text(k + 1, header_line)}: non-uniform "
            f"sampling (step {dt[k - 1]:.6g} s, median {h:.6g} s); the FFT low-pass "
            "needs uniform samples: resample the log",
            path,
            "t",
            k + 1,
        )
    if h > 0.5:
        raise LogError(
            f"{path}: column 't': median step {h:g} s is implausible for a "
            "control-rate log (milliseconds instead of seconds?)",
            path,
            "t",
        )
    for c in used:
        v = cols[c]
        if c.startswith("leg_state_"):
            bad = ~np.isin(v, [float(state) for state in LegState])
            if bad.any():
                k = int(np.argmax(bad))
                raise LogError(
                    f"{path}: column '{c}', {row_text(k + 1, header_line)}: value "
                    f"{v[k]:g} is not a leg state (0 flight, 1 stance-retraction, "
                    "2 stance-brake)",
                    path,
                    c,
                    k + 1,
                )
            continue
        if c in _PLAUSIBLE:
            lim, suggestion = _PLAUSIBLE[c]
            big = np.abs(v) > lim
            if big.any():
                k = int(np.argmax(big))
                raise LogError(
                    f"{path}: column '{c}', {row_text(k + 1, header_line)}: "
                    f"|value| {abs(v[k]):.6g} exceeds {lim:.4g} "
                    f"{COLUMN_UNITS[c]}; this suggests {suggestion}",
                    path,
                    c,
                    k + 1,
                )
        if c in _NONNEGATIVE:
            neg = v < 0
            if neg.any():
                k = int(np.argmax(neg))
                raise LogError(
                    f"{path}: column '{c}', {row_text(k + 1, header_line)}: "
                    f"negative length {v[k]:.6g} m",
                    path,
                    c,
                    k + 1,
                )
    check_spikes(path, cols, header_line, repairs)
