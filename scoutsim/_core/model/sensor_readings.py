"""What the robot's sensors read (compiled): the plant side of the controller boundary.

At every control sample the controller sees the sensor readings (``layout.SN_*``,
``layout.SENSOR_CHANNELS``) and nothing else of the plant (docs/specification.md section 6):

* hip encoders, per virtual leg: the hip angle and rate relative to the torso, at the motor
  (the driven-gear angle alpha in Model II, which differs from the leg angle phi by the
  belt's deflection) or at the leg;
* leg length (a linear potentiometer in each leg);
* an IMU at the torso COM: pitch [rad], pitch rate [rad/s], and the accelerometer's
  specific force in the torso frame, f = R(theta)^T (a - g) [m/s^2] (x along the torso
  axis, z along its upward normal; +g on z at rest, level);
* the two laser range finders at the torso's ends, pointing along the torso's downward
  normal (the paper's measurement chain, Sec. IV.B): range = (y -+ d sin theta) / cos theta
  - offset over flat ground, back then front;
* motor current per motor [A] and battery voltage [V].

The IMU's accelerations, the currents and the battery voltage belong to the instant just
before the sample, under the command held over the period that ends there (the evaluation
the integrator ended the period with).

The readings are ideal unless the sensor specification gives a channel noise, a bias, a
resolution or a delay (:func:`measure`): reading = quantize(true + bias + noise), reported
``delay`` control periods later. The noise is white Gaussian, drawn by a counter-based
generator from (seed, sample, slot): the same seed gives the same noise on any machine,
whatever the run's chunking.
"""

from __future__ import annotations

import math

import numpy as np

from ..._numba.jit import kernel
from .flags import is_set
from .layout import (
    A_CURRENT,
    A_VBATT,
    IALB,
    IL_B,
    IPHB,
    ITH,
    IX,
    IY,
    NAUX_LEG,
    NQ,
    NSN,
    SG_LASER_HALF_SPACING,
    SG_LASER_MOUNT_OFFSET,
    SG_MOTOR_SIDE,
    SN_ACCEL_X,
    SN_ACCEL_Z,
    SN_ANGLE_B,
    SN_BATTERY,
    SN_CURRENT_B,
    SN_LENGTH_B,
    SN_PITCH,
    SN_PITCH_RATE,
    SN_RANGE_B,
    SN_RANGE_F,
    SN_RATE_B,
    SPEC_BIAS,
    SPEC_DELAY,
    SPEC_NOISE,
    SPEC_RESOLUTION,
)


@kernel
def read_encoders(s, motor_side, y):
    """Fill the hip encoder and leg length slots of y from the state s: hip angles [rad]
    and rates [rad/s] at the motor (``motor_side``: alpha) or at the leg (phi), and leg
    lengths [m]. Outside Model II alpha equals phi."""
    i0 = IALB if motor_side else IPHB
    for leg in range(2):
        y[SN_ANGLE_B + leg] = s[i0 + leg]
        y[SN_RATE_B + leg] = s[NQ + i0 + leg]
        y[SN_LENGTH_B + leg] = s[IL_B + leg]


@kernel
def true_readings(s, ds, aux, gravity, geom, y):
    """Every sensor's true reading (``layout.SN_*``, SI) at the state ``s``, with ``ds`` and
    ``aux`` the model's evaluation there (accelerations, motor currents, battery voltage),
    ``gravity`` [m/s^2] and the sensor geometry ``geom`` (``layout.SG_*``)."""
    read_encoders(s, is_set(geom[SG_MOTOR_SIDE]), y)
    th = s[ITH]
    c = math.cos(th)
    sn = math.sin(th)
    y[SN_PITCH] = th
    y[SN_PITCH_RATE] = s[NQ + ITH]
    # specific force a - g (g = (0, -gravity)) in the torso frame
    fx = ds[NQ + IX]
    fy = ds[NQ + IY] + gravity
    y[SN_ACCEL_X] = fx * c + fy * sn
    y[SN_ACCEL_Z] = -fx * sn + fy * c
    d = geom[SG_LASER_HALF_SPACING]
    off = geom[SG_LASER_MOUNT_OFFSET]
    y[SN_RANGE_B] = (s[IY] - d * sn) / c - off
    y[SN_RANGE_F] = (s[IY] + d * sn) / c - off
    for leg in range(2):
        y[SN_CURRENT_B + leg] = aux[leg * NAUX_LEG + A_CURRENT]
    y[SN_BATTERY] = aux[A_VBATT]


_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)


@kernel
def _mix64(z):
    """SplitMix64's finalizer (Steele, Lea & Flood, OOPSLA 2014): a bijection of uint64
    whose outputs pass BigCrush for consecutive inputs."""
    z = (z ^ (z >> np.uint64(30))) * _M1
    z = (z ^ (z >> np.uint64(27))) * _M2
    return z ^ (z >> np.uint64(31))


@kernel
def uniform01(seed, counter):
    """A uniform number in (0, 1) from (seed, counter), both >= 0: 53 random bits."""
    z = _mix64(_mix64(np.uint64(seed)) + _GOLDEN * (np.uint64(counter) + np.uint64(1)))
    return (float(z >> np.uint64(11)) + 0.5) * (1.0 / 9007199254740992.0)


@kernel
def standard_normal(seed, sample, slot):
    """A standard normal number for (seed, control sample, sensor slot): Box-Muller on two
    counter-based uniforms."""
    c = (np.int64(sample) * NSN + slot) * 2
    u1 = uniform01(seed, c)
    u2 = uniform01(seed, c + 1)
    return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)


@kernel
def measure(k, spec, seed, hist, y):
    """Turn the true readings ``y`` at control sample ``k`` into what the sensors report,
    in place: bias, noise, resolution (``spec``, ``layout.SPEC_*`` rows by slot), then the
    delay through the ring buffer ``hist`` (rows: samples modulo its length; it must be
    longer than the longest delay). A delayed channel reports its first reading until the
    run has lasted ``delay`` samples."""
    depth = hist.shape[0]
    row = k % depth
    for i in range(NSN):
        v = y[i] + spec[SPEC_BIAS, i]
        sd = spec[SPEC_NOISE, i]
        if sd > 0.0:
            v += sd * standard_normal(seed, k, i)
        q = spec[SPEC_RESOLUTION, i]
        if q > 0.0:
            v = q * math.floor(v / q + 0.5)
        hist[row, i] = v
    for i in range(NSN):
        j = k - np.int64(spec[SPEC_DELAY, i])
        if j < 0:
            j = 0
        y[i] = hist[j % depth, i]
