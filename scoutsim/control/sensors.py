"""The robot's sensors as a controller sees them: the readings (:class:`Sensors`) and how
each channel measures (:class:`SensorParameters`: noise, bias, resolution, delay).

Channels (SI units; leg channels are (back, front) pairs; the compiled model computes them,
:mod:`scoutsim._core.model.sensor_readings`):

=================  ======  ===========================================================
channel            unit    what reads it
=================  ======  ===========================================================
hip_angle          rad     hip encoder: angle relative to the torso (motor side in
                           Model II when the controller senses the motor angle)
hip_rate           rad/s   hip encoder rate
leg_length         m       leg potentiometer
pitch              rad     IMU: torso pitch, nose up positive
pitch_rate         rad/s   IMU: torso pitch rate
acceleration       m/s^2   IMU accelerometer at the torso COM: specific force along the
                           torso axis and its upward normal (reads (0, g) at rest, level)
laser_range        m       laser range finders at the torso's back and front ends
motor_current      A       motor current, per motor
battery_voltage    V       motor supply voltage
=================  ======  ===========================================================

Compiled controllers read the same readings from a float array by slot: the module
constants ``HIP_ANGLE`` (back; ``HIP_ANGLE + 1`` front), ``HIP_RATE``, ``LEG_LENGTH``,
``PITCH``, ``PITCH_RATE``, ``ACCELERATION`` (x; ``+ 1`` z), ``LASER_RANGE``,
``MOTOR_CURRENT``, ``BATTERY``, and ``N_SENSORS`` slots in all.

A robot file describes its sensors in a ``[sensors]`` section (all optional; by default
every sensor is ideal)::

    [sensors]
    seed = 7                                   # of the noise; same seed, same noise
    laser_half_spacing = { value = 0.35, unit = "m" }   # default: torso_length / 2

    [sensors.pitch]
    noise = { value = 0.3, unit = "deg" }      # standard deviation of white noise
    bias = { value = 0.5, unit = "deg" }       # a number, or [back, front] for leg channels
    resolution = { value = 0.01, unit = "deg" }  # quantization step
    delay = 2                                  # control periods

    [sensors.hip_angle]
    counts_per_revolution = 2000               # motor encoder: resolution at the hip is
                                               # 2 pi / (counts x gear ratio)
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
import typing
from dataclasses import dataclass
from os import PathLike

import numpy as np

from .._core.model import layout as L
from .._core.model.flags import FLAG_OFF, FLAG_ON
from ..parameters import ParameterError, RobotParameters, quantity_to_si

__all__ = [
    "Sensors",
    "SensorChannel",
    "SensorParameters",
    "load_sensors",
    "CHANNELS",
    "SLOT_NAMES",
    "HIP_ANGLE",
    "HIP_RATE",
    "LEG_LENGTH",
    "PITCH",
    "PITCH_RATE",
    "ACCELERATION",
    "LASER_RANGE",
    "MOTOR_CURRENT",
    "BATTERY",
    "N_SENSORS",
]

# slots of the readings array, for compiled controllers
HIP_ANGLE = L.SN_ANGLE_B
HIP_RATE = L.SN_RATE_B
LEG_LENGTH = L.SN_LENGTH_B
PITCH = L.SN_PITCH
PITCH_RATE = L.SN_PITCH_RATE
ACCELERATION = L.SN_ACCEL_X
LASER_RANGE = L.SN_RANGE_B
MOTOR_CURRENT = L.SN_CURRENT_B
BATTERY = L.SN_BATTERY
N_SENSORS = L.NSN

#: channel name -> (first slot, number of slots, SI unit)
CHANNELS = {name: (slot, n, unit) for name, slot, n, unit in L.SENSOR_CHANNELS}
#: every slot's name, in slot order: the channel's name, and for a two-slot channel its
#: part ("_back" / "_front"; the accelerometer's "_axial" along the torso axis, then
#: "_normal")
SLOT_NAMES = tuple(
    name if n == 1 else f"{name}_{part}"
    for name, (slot, n, unit) in sorted(CHANNELS.items(), key=lambda item: item[1][0])
    for part in (("axial", "normal") if name == "acceleration" else ("back", "front"))[:n]
)
#: channel -> the dimension of its unit (parameters.UNITS)
_DIMENSIONS = {
    "hip_angle": "angle",
    "hip_rate": "angular rate",
    "leg_length": "length",
    "pitch": "angle",
    "pitch_rate": "angular rate",
    "acceleration": "acceleration",
    "laser_range": "length",
    "motor_current": "current",
    "battery_voltage": "voltage",
}


class Sensors:
    """The sensor readings of one control sample (SI units; see the module docstring).

    Attributes (read-only): ``hip_angle``, ``hip_rate``, ``leg_length``, ``acceleration``,
    ``laser_range``, ``motor_current`` ((2,) arrays, back then front; acceleration: along
    the torso axis, then its normal), ``pitch``, ``pitch_rate``, ``battery_voltage``
    (floats), and ``vector``, every reading by slot (this module's ``HIP_ANGLE`` ... ``BATTERY``;
    their names: :data:`SLOT_NAMES`).

    ``Sensors(hip_angle, hip_rate, leg_length, **other_channels)`` makes readings by hand
    (e.g. to test a controller); channels not given are NaN.
    """

    __slots__ = ("_v",)

    def __init__(self, hip_angle=None, hip_rate=None, leg_length=None, **channels):
        v = np.full(L.NSN, np.nan)
        given = dict(channels, hip_angle=hip_angle, hip_rate=hip_rate, leg_length=leg_length)
        for name, value in given.items():
            if name not in CHANNELS:
                raise TypeError(
                    f"Sensors: unknown channel {name!r}; channels: {', '.join(CHANNELS)}"
                )
            if value is None:
                continue
            slot, n, _ = CHANNELS[name]
            v[slot : slot + n] = np.broadcast_to(np.asarray(value, dtype=float), (n,))
        v.flags.writeable = False
        self._v = v

    @classmethod
    def from_vector(cls, y) -> Sensors:
        """Readings from a readings array (``layout.NSN`` slots); copies it."""
        obj = cls.__new__(cls)
        v = (
            y.copy()
            if type(y) is np.ndarray and y.dtype == np.float64
            else np.array(y, dtype=float)
        )
        v.flags.writeable = False  # (its slices, the channels, are read-only too)
        obj._v = v
        return obj

    @property
    def vector(self) -> np.ndarray:
        """Every reading by slot (``HIP_ANGLE`` ... ``BATTERY`` of this module), read-only."""
        return self._v

    def _pair(self, slot):
        return self._v[slot : slot + 2]

    hip_angle = property(
        lambda self: self._pair(L.SN_ANGLE_B),
        doc="hip angles relative to the torso [rad] (back, front)",
    )
    hip_rate = property(lambda self: self._pair(L.SN_RATE_B), doc="hip rates [rad/s] (back, front)")
    leg_length = property(
        lambda self: self._pair(L.SN_LENGTH_B), doc="leg lengths [m] (back, front)"
    )
    acceleration = property(
        lambda self: self._pair(L.SN_ACCEL_X),
        doc="accelerometer: specific force along the torso axis and its upward normal [m/s^2]",
    )
    laser_range = property(
        lambda self: self._pair(L.SN_RANGE_B),
        doc="laser ranges at the torso's back and front ends [m]",
    )
    motor_current = property(
        lambda self: self._pair(L.SN_CURRENT_B), doc="motor currents [A] (back, front)"
    )
    pitch = property(lambda self: float(self._v[L.SN_PITCH]), doc="torso pitch [rad]")
    pitch_rate = property(
        lambda self: float(self._v[L.SN_PITCH_RATE]), doc="torso pitch rate [rad/s]"
    )
    battery_voltage = property(lambda self: float(self._v[L.SN_BATTERY]), doc="battery voltage [V]")

    def as_dict(self) -> dict:
        """Every channel by name (lists for the leg channels)."""
        out = {}
        for name, (slot, n, _) in CHANNELS.items():
            out[name] = float(self._v[slot]) if n == 1 else self._v[slot : slot + n].tolist()
        return out

    def __repr__(self):
        parts = ", ".join(f"{k}={v}" for k, v in self.as_dict().items())
        return f"Sensors({parts})"

    def __eq__(self, other):
        return isinstance(other, Sensors) and np.array_equal(self._v, other._v, equal_nan=True)

    __hash__ = None  # type: ignore[assignment]  # (mutable readings: not hashable)


@dataclass(frozen=True)
class SensorChannel:
    """How one sensor channel measures (in the channel's SI unit, see :data:`CHANNELS`).

    Attributes
    ----------
    noise : float
        Standard deviation of white Gaussian noise, one draw per sample and slot.
    bias : float or (back, front)
        Constant offset; a number, or (back, front) for a two-slot channel.
    resolution : float or (back, front)
        Quantization step (0: continuous); the reading is the nearest multiple; a number,
        or (back, front) for a two-slot channel (a motor encoder's step at the hip of legs
        whose gear ratios differ).
    delay : int
        How many control periods late the reading arrives (0 .. layout.MAX_SENSOR_DELAY).
    """

    noise: float = 0.0
    bias: float | tuple = 0.0
    resolution: float | tuple = 0.0
    delay: int = 0

    def is_ideal(self) -> bool:
        return (
            self.noise == 0
            and _all_zero(self.bias)
            and _all_zero(self.resolution)
            and self.delay == 0
        )


def _all_zero(value) -> bool:
    """A number, or each entry of a (back, front) pair or array, is 0."""
    if isinstance(value, (int, float)):
        return value == 0
    return all(x == 0 for x in np.ravel(value))


_IDEAL = SensorChannel()


@dataclass(frozen=True)
class SensorParameters:
    """The robot's sensors: one :class:`SensorChannel` per channel, the noise seed and the
    laser range finders' geometry. The default: every sensor ideal.

    Attributes
    ----------
    hip_angle, hip_rate, leg_length, pitch, pitch_rate, acceleration, laser_range, motor_current, battery_voltage : SensorChannel
        How each channel measures (default: ideal).
    seed : int
        Seed of the noise, >= 0 (the same seed gives the same noise, bit for bit).
    laser_half_spacing : float or None
        Distance of each laser from the torso COM along the torso axis [m] (None: half the
        robot's ``torso_length``, the torso's ends).
    laser_mount_offset : float
        The lasers' aperture below the torso axis [m].
    """

    hip_angle: SensorChannel = _IDEAL
    hip_rate: SensorChannel = _IDEAL
    leg_length: SensorChannel = _IDEAL
    pitch: SensorChannel = _IDEAL
    pitch_rate: SensorChannel = _IDEAL
    acceleration: SensorChannel = _IDEAL
    laser_range: SensorChannel = _IDEAL
    motor_current: SensorChannel = _IDEAL
    battery_voltage: SensorChannel = _IDEAL
    seed: int = 0
    laser_half_spacing: float | None = None
    laser_mount_offset: float = 0.0

    def __post_init__(self):
        for name in CHANNELS:
            ch = getattr(self, name)
            if not isinstance(ch, SensorChannel):
                raise ParameterError(
                    f"sensors.{name} must be a SensorChannel, not {type(ch).__name__}",
                    f"sensors.{name}",
                )
            n = CHANNELS[name][1]
            for what in ("noise", "resolution"):
                v = getattr(ch, what)
                values = (
                    v
                    if (what == "resolution" and n == 2 and isinstance(v, tuple) and len(v) == 2)
                    else (v,)
                )
                if not all(
                    isinstance(x, (int, float)) and math.isfinite(x) and x >= 0 for x in values
                ):
                    pair = (
                        " (or a (back, front) pair of them)"
                        if what == "resolution" and n == 2
                        else ""
                    )
                    raise ParameterError(
                        f"sensors.{name}.{what} = {v!r} is not allowed: must "
                        f"be a finite number >= 0{pair} {CHANNELS[name][2]}",
                        f"sensors.{name}.{what}",
                    )
            bias = np.asarray(ch.bias, dtype=float)
            if not (bias.shape in ((), (n,)) and np.all(np.isfinite(bias))):
                raise ParameterError(
                    f"sensors.{name}.bias = {ch.bias!r} is not allowed: must "
                    f"be a finite number{' or (back, front)' if n == 2 else ''}"
                    f" [{CHANNELS[name][2]}]",
                    f"sensors.{name}.bias",
                )
            d = ch.delay
            if not (
                isinstance(d, (int, np.integer))
                and not isinstance(d, bool)
                and 0 <= d <= L.MAX_SENSOR_DELAY
            ):
                raise ParameterError(
                    f"sensors.{name}.delay = {d!r} is not allowed: must be a "
                    f"whole number of control periods in [0, "
                    f"{L.MAX_SENSOR_DELAY}]",
                    f"sensors.{name}.delay",
                )
        if not (
            isinstance(self.seed, (int, np.integer))
            and not isinstance(self.seed, bool)
            and 0 <= self.seed < 2**63
        ):
            raise ParameterError(
                f"sensors.seed = {self.seed!r} is not allowed: must be a whole number in [0, 2^63)",
                "sensors.seed",
            )
        h = self.laser_half_spacing
        if h is not None and not (isinstance(h, (int, float)) and math.isfinite(h) and h > 0):
            raise ParameterError(
                f"sensors.laser_half_spacing = {h!r} m is not allowed: must be a finite number > 0",
                "sensors.laser_half_spacing",
            )
        if not math.isfinite(self.laser_mount_offset):
            raise ParameterError(
                f"sensors.laser_mount_offset = {self.laser_mount_offset!r} m "
                "is not allowed: must be finite",
                "sensors.laser_mount_offset",
            )

    def is_ideal(self) -> bool:
        """True if no channel has noise, bias, resolution or delay."""
        return all(getattr(self, name).is_ideal() for name in CHANNELS)

    def replace(self, **changes) -> SensorParameters:
        return dataclasses.replace(self, **changes)

    def spec_array(self) -> np.ndarray:
        """The measurement model by slot (``layout.SPEC_*`` rows, ``layout.NSN`` columns)."""
        spec = np.zeros((L.NSPEC, L.NSN))
        for name, (slot, n, _) in CHANNELS.items():
            ch = getattr(self, name)
            if ch is _IDEAL:  # every entry 0, as the array starts
                continue
            cols = slice(slot, slot + n)
            spec[L.SPEC_NOISE, cols] = ch.noise
            spec[L.SPEC_BIAS, cols] = np.broadcast_to(np.asarray(ch.bias, float), (n,))
            spec[L.SPEC_RESOLUTION, cols] = np.broadcast_to(np.asarray(ch.resolution, float), (n,))
            spec[L.SPEC_DELAY, cols] = ch.delay
        return spec

    def geometry_array(self, robot: RobotParameters, motor_side: bool) -> np.ndarray:
        """The sensors' geometry and flags (``layout.SG_*``) on ``robot``."""
        g = np.zeros(L.NSG)
        g[L.SG_LASER_HALF_SPACING] = (
            0.5 * robot.torso_length if self.laser_half_spacing is None else self.laser_half_spacing
        )
        g[L.SG_LASER_MOUNT_OFFSET] = self.laser_mount_offset
        g[L.SG_MOTOR_SIDE] = FLAG_ON if motor_side else FLAG_OFF
        g[L.SG_MEASURED] = FLAG_OFF if self.is_ideal() else FLAG_ON
        return g

    def as_dict(self) -> dict:
        """JSON-safe form (provenance)."""
        out: dict[str, typing.Any] = {
            "seed": int(self.seed),
            "laser_half_spacing": self.laser_half_spacing,
            "laser_mount_offset": self.laser_mount_offset,
        }
        for name in CHANNELS:
            ch = getattr(self, name)
            if not ch.is_ideal():
                bias = np.asarray(ch.bias, float)
                res = ch.resolution
                out[name] = {
                    "noise": ch.noise,
                    "bias": bias.tolist(),
                    "resolution": list(res) if isinstance(res, tuple) else res,
                    "delay": int(ch.delay),
                }
        return out


_CHANNEL_KEYS = ("noise", "bias", "resolution", "delay", "counts_per_revolution")


def sensors_from_dict(
    section: dict, robot: RobotParameters | None = None, where: str = ""
) -> SensorParameters:
    """:class:`SensorParameters` from the ``[sensors]`` table of a robot file (see the module
    docstring; units as there); ``robot`` gives the gear ratio for an encoder's
    ``counts_per_revolution`` (default Scout II)."""
    robot = robot if robot is not None else RobotParameters()
    kw: dict = {}
    for key, entry in section.items():
        label = f"sensors.{key}"
        if key == "seed":
            if isinstance(entry, bool) or not isinstance(entry, int):
                raise ParameterError(
                    f"{label} = {entry!r} is not allowed: must be a whole "
                    f"number in [0, 2^63){where}",
                    label,
                )
            kw["seed"] = entry
        elif key in ("laser_half_spacing", "laser_mount_offset"):
            kw[key] = quantity_to_si(entry, "length", "m", label + where)
        elif key in CHANNELS:
            if not isinstance(entry, dict):
                raise ParameterError(
                    f"[sensors.{key}] must be a table with keys "
                    f"{', '.join(_CHANNEL_KEYS[:4])}{where}",
                    label,
                )
            kw[key] = _channel(key, entry, robot, where)
        else:
            import difflib

            close = difflib.get_close_matches(key, list(CHANNELS) + ["seed"], n=1)
            hint = (
                f"did you mean '{close[0]}'?"
                if close
                else f"channels: {', '.join(CHANNELS)}; also seed, laser_half_spacing, laser_mount_offset"
            )
            raise ParameterError(f"unknown sensor entry '{key}'{where}; {hint}", label)
    return SensorParameters(**kw)


def _channel(name: str, entry: dict, robot: RobotParameters, where: str) -> SensorChannel:
    dim = _DIMENSIONS[name]
    unit = CHANNELS[name][2]
    kw: dict = {}
    for key, value in entry.items():
        label = f"sensors.{name}.{key}"
        if key in ("noise", "resolution"):
            kw[key] = quantity_to_si(value, dim, unit, label + where)
        elif key == "bias":
            if isinstance(value, list):
                kw[key] = tuple(quantity_to_si(v, dim, unit, label + where) for v in value)
            else:
                kw[key] = quantity_to_si(value, dim, unit, label + where)
        elif key == "delay":
            if isinstance(value, bool) or not isinstance(value, int):
                raise ParameterError(
                    f"{label} = {value!r} is not allowed: must be a whole "
                    f"number of control periods{where}",
                    label,
                )
            kw[key] = value
        elif key == "counts_per_revolution" and name == "hip_angle":
            if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
                raise ParameterError(
                    f"{label} = {value!r} is not allowed: must be a whole number > 0{where}", label
                )
            if "resolution" in entry:
                raise ParameterError(
                    f"sensors.hip_angle: give resolution or counts_per_revolution, not both{where}",
                    label,
                )
            # the encoder is on the motor: one count is 2 pi / counts of the motor shaft,
            # 2 pi / (counts N) at the hip (per leg when the gear ratios differ)
            back, front = (2.0 * math.pi / (value * robot.leg(leg).gear_ratio) for leg in (0, 1))
            kw["resolution"] = back if back == front else (back, front)
        else:
            allowed = _CHANNEL_KEYS if name == "hip_angle" else _CHANNEL_KEYS[:4]
            raise ParameterError(
                f"unknown key '{key}' in [sensors.{name}]{where}; allowed: {', '.join(allowed)}",
                label,
            )
    return SensorChannel(**kw)


def load_sensors(
    path: str | PathLike | None = None, robot: RobotParameters | None = None
) -> SensorParameters:
    """The sensors of a robot file's ``[sensors]`` section (ideal sensors if the file has
    none, or for ``path`` None). ``robot``: for an encoder's ``counts_per_revolution``."""
    if path is None:
        return SensorParameters()
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"malformed TOML in parameter file '{path}': {exc}") from exc
    section = data.get("sensors", {})
    if not isinstance(section, dict):
        raise ParameterError(f"[sensors] in parameter file '{path}' must be a table")
    return sensors_from_dict(section, robot, where=f" (in file '{path}')")
