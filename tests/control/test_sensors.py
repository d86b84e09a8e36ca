"""The sensors a controller sees (scoutsim.control.sensors, scoutsim._core.model.sensor_readings): ideal
readings against the plant's state and independent formulations (the validation chain's
laser geometry, free fall of the massless-leg model, the velocity's difference quotient),
and each measurement effect (bias, noise, resolution, delay) as specified, reproducible
from its seed; the robot file's [sensors] section."""

import math

import numpy as np
import pytest

import scoutsim
from scoutsim import BoundingController, InitialState, RobotParameters
from scoutsim._core.model import layout as L
from scoutsim.control.sensors import (
    CHANNELS,
    SensorChannel,
    SensorParameters,
    Sensors,
    load_sensors,
)
from scoutsim.parameters import ParameterError
from scoutsim.validation.torso_sensors import LaserGeometry, laser_ranges

ROBOT = RobotParameters()


class Recording(BoundingController):
    """The Table I law called from Python, keeping every reading it was given (the Table I
    law reads only the hip encoders and leg lengths)."""

    def __init__(self):
        super().__init__()
        self.readings, self.times = [], []

    def command(self, t, sensors):
        self.readings.append(sensors.vector.copy())
        self.times.append(t)
        return super().command(t, sensors)


def _run(model="II", duration=1.0, sensors=None, controller=None, **kw):
    c = controller or Recording()
    r = scoutsim.simulate(None, c, None, duration, model=model, sensors=sensors, **kw)
    return r, c, np.array(c.readings)


@pytest.fixture(scope="module")
def ideal():
    """One second of Model II bounding, read by ideal sensors."""
    return _run()


def test_ideal_sensors_read_the_state_at_the_sample_instants(ideal):
    """Ideal IMU, encoders (motor side in Model II) and leg potentiometers: the reading of
    sample k is the recorded state at t_k, exactly."""
    r, c, y = ideal
    assert len(y) == len(r.t) and np.array_equal(np.array(c.times), r.t)
    assert np.array_equal(y[:, L.SN_PITCH], r.pitch)
    assert np.array_equal(y[:, L.SN_PITCH_RATE], r.pitch_rate)
    for leg in (L.BACK, L.FRONT):
        assert np.array_equal(y[:, L.SN_ANGLE_B + leg], r.state[:, L.IALB + leg])
        assert np.array_equal(y[:, L.SN_RATE_B + leg], r.state[:, L.NQ + L.IALB + leg])
        assert np.array_equal(y[:, L.SN_LENGTH_B + leg], r.leg_length(leg))
    # the belt deflects: the motor side is not the leg side
    assert np.max(np.abs(y[:, L.SN_ANGLE_B] - r.leg_angle("back"))) > 1e-3


def test_the_lasers_read_the_validation_chains_geometry(ideal):
    """The torso lasers against the validation chain's own inverse geometry
    (scoutsim.validation.torso_sensors.laser_ranges), at the torso ends (torso_length / 2)."""
    r, _, y = ideal
    front, back = laser_ranges(r.height, r.pitch, LaserGeometry(0.5 * ROBOT.torso_length))
    np.testing.assert_allclose(y[:, L.SN_RANGE_B], back, rtol=0, atol=1e-15)
    np.testing.assert_allclose(y[:, L.SN_RANGE_F], front, rtol=0, atol=1e-15)
    assert np.ptp(y[:, L.SN_RANGE_F] - y[:, L.SN_RANGE_B]) > 0.05  # the torso pitches


class Hold:
    """Holds one command for the whole run, keeping every reading."""

    def __init__(self, torques=(-1.0, 1.0)):
        self.torques, self.y = torques, []

    def command(self, t, sensors):
        self.y.append(sensors.vector.copy())
        return self.torques


def test_the_accelerometer_reads_the_velocitys_rate_of_change():
    """Specific force f = R(theta)^T (a - g): rotated back to the world and with gravity
    removed, it is the torso's acceleration. Under a held command (Model I, a drop onto
    both legs, flight and stance), the mean of the readings at both ends of a sample
    period equals the velocity's difference quotient over it, to dt^2 |d2a/dt2| / 12, in
    the periods without a contact event (measured median 5e-6 m/s^2 of accelerations up
    to 10 m/s^2)."""
    h = Hold()
    r = scoutsim.simulate(None, h, InitialState(y=0.42, dx=0.5, dtheta=0.0), 0.4, model="I")
    y = np.array(h.y)
    n = len(y)  # (a run that falls records its last state off the grid)
    t, th = r.t[:n], r.pitch[:n]
    fx, fz = y[:, L.SN_ACCEL_X], y[:, L.SN_ACCEL_Z]
    ax = fx * np.cos(th) - fz * np.sin(th)
    ay = fx * np.sin(th) + fz * np.cos(th) - ROBOT.gravity
    qx = np.diff(r.forward_speed[:n]) / np.diff(t)
    qy = np.diff(r.state[:n, L.NQ + L.IY]) / np.diff(t)
    events = r.events[:, L.EVR_T]
    calm = np.array(
        [not np.any((events > a - 1e-9) & (events <= b + 1e-9)) for a, b in zip(t[:-1], t[1:])]
    )
    calm[0] = False  # the first reading is taken under the zero command before the run
    stance = (r.contact_mode("back")[1:n] != 0) | (r.contact_mode("front")[1:n] != 0)
    assert (calm & stance).sum() > 50 and (calm & ~stance).sum() > 50
    assert np.max(np.abs(qy[calm])) > 5.0  # the legs catch the torso
    ex = np.abs(0.5 * (ax[:-1] + ax[1:]) - qx)[calm]
    ey = np.abs(0.5 * (ay[:-1] + ay[1:]) - qy)[calm]
    assert np.median(ex) < 5e-5 and np.median(ey) < 5e-5


def test_a_massless_leg_robot_in_flight_is_in_free_fall():
    """Passive massless-leg model in flight: only gravity acts on the torso, so the
    accelerometer reads zero and the pitch rate is constant."""
    robot = ROBOT.replace(leg_mass=0.0, leg_inertia=0.0)
    start = InitialState(y=0.6, dx=1.0, dtheta=0.5)

    class Watch:
        def __init__(self):
            self.f = []

        def command(self, t, s):
            self.f.append((s.acceleration.copy(), s.pitch_rate))
            return (0.0, 0.0)

    w = Watch()
    r = scoutsim.simulate(robot, w, start, 0.1, model="passive")
    assert not r.event_times("touchdown").size
    f = np.array([a for a, _ in w.f])
    assert np.max(np.abs(f)) < 1e-9 * ROBOT.gravity
    assert np.ptp([q for _, q in w.f]) < 1e-12


def test_current_and_battery_sensors_read_the_motor_and_supply():
    """Under a command that does not change, the current sensor and the battery monitor
    read what the run records at each sample (Model I, a battery with internal
    resistance so the voltage sags with the load, V = V_oc - R_b I_b)."""
    robot = ROBOT.replace(battery_resistance=0.3)

    h = Hold((-1.5, 1.0))
    r = scoutsim.simulate(robot, h, InitialState(y=1.0, dx=0.0, dtheta=0.0), 0.2, model="I")
    y = np.array(h.y)
    for leg in (L.BACK, L.FRONT):
        np.testing.assert_array_equal(y[1:, L.SN_CURRENT_B + leg], r.motor_current(leg)[1:])
    np.testing.assert_array_equal(y[1:, L.SN_BATTERY], r.battery_voltage[1:])
    assert np.ptp(y[1:, L.SN_BATTERY]) > 0.1 and np.all(y[1:, L.SN_BATTERY] < ROBOT.battery_voltage)
    # the first sample is read under the zero command held before the run: no current,
    # the open-circuit voltage
    assert np.all(y[0, [L.SN_CURRENT_B, L.SN_CURRENT_F]] == 0.0)
    assert y[0, L.SN_BATTERY] == ROBOT.battery_voltage


# -----------------------------------------------------------------------------------------
# the measurement model: bias, noise, resolution, delay
# -----------------------------------------------------------------------------------------
def test_a_bias_adds_to_every_reading(ideal):
    """Bias on pitch and (per leg) on the leg lengths: reading - ideal reading = bias
    (the Table I law does not read pitch; leg-length biases below the contact thresholds'
    margins would change its timing, so they are checked on the first reading)."""
    _, _, y0 = ideal
    sensors = SensorParameters(pitch=SensorChannel(bias=0.02))
    _, _, y = _run(sensors=sensors)
    np.testing.assert_allclose(y[:, L.SN_PITCH] - y0[:, L.SN_PITCH], 0.02, rtol=0, atol=1e-15)
    other = [i for i in range(L.NSN) if i != L.SN_PITCH]
    assert np.array_equal(y[:, other], y0[:, other])


def test_noise_is_white_with_the_given_deviation_and_reproducible(ideal):
    """Pitch-rate noise sigma = 0.05 rad/s over 1000 samples: mean and standard deviation
    of reading - truth within 4 standard errors of 0 and sigma, lag-1 correlation within
    4 / sqrt(n) of 0; the same seed gives the same readings bit for bit, another seed other
    readings; the other channels stay ideal."""
    _, _, y0 = ideal
    sigma = 0.05
    noisy = SensorParameters(pitch_rate=SensorChannel(noise=sigma), seed=11)
    _, _, y = _run(sensors=noisy)
    e = y[:, L.SN_PITCH_RATE] - y0[:, L.SN_PITCH_RATE]
    n = e.size
    assert abs(e.mean()) < 4 * sigma / math.sqrt(n)
    assert abs(e.std() / sigma - 1.0) < 4 / math.sqrt(2 * n)
    assert abs(np.corrcoef(e[1:], e[:-1])[0, 1]) < 4 / math.sqrt(n)
    _, _, again = _run(sensors=noisy)
    assert np.array_equal(again, y)
    _, _, other = _run(sensors=noisy.replace(seed=12))
    assert not np.array_equal(other[:, L.SN_PITCH_RATE], y[:, L.SN_PITCH_RATE])
    keep = [i for i in range(L.NSN) if i != L.SN_PITCH_RATE]
    assert np.array_equal(y[:, keep], y0[:, keep])


def test_noise_does_not_depend_on_how_the_run_is_cut():
    """The noise of sample k is drawn from (seed, k, slot): runs cut into different chunks
    read the same."""
    noisy = SensorParameters(pitch=SensorChannel(noise=0.01), seed=3)
    _, _, a = _run(duration=0.3, sensors=noisy, chunk_seconds=1.0)
    _, _, b = _run(duration=0.3, sensors=noisy, chunk_seconds=0.017)
    assert np.array_equal(a, b)


def test_a_resolution_quantizes_to_its_step():
    """An encoder of 500 counts per motor revolution (resolution 2 pi / (500 N) at the
    hip): every hip-angle reading is a whole number of steps and within half a step of
    the recorded motor-side angle."""
    q = 2 * math.pi / (500 * ROBOT.gear_ratio)
    sensors = SensorParameters(hip_angle=SensorChannel(resolution=q))
    r, _, y = _run(sensors=sensors, duration=0.5)
    for leg in (L.BACK, L.FRONT):
        read = y[:, L.SN_ANGLE_B + leg]
        steps = read / q
        np.testing.assert_allclose(steps, np.round(steps), rtol=0, atol=1e-9)
        assert np.max(np.abs(read - r.state[:, L.IALB + leg])) <= 0.5 * q * (1 + 1e-12)
        assert np.unique(np.round(steps)).size > 20


def test_a_delay_reports_the_reading_of_an_earlier_sample(ideal):
    """Pitch delayed by 3 control periods: the reading of sample k is the ideal reading of
    sample k - 3, and the first reading until then."""
    _, _, y0 = ideal
    sensors = SensorParameters(pitch=SensorChannel(delay=3))
    _, _, y = _run(sensors=sensors)
    assert np.array_equal(y[3:, L.SN_PITCH], y0[:-3, L.SN_PITCH])
    assert np.array_equal(y[:3, L.SN_PITCH], np.full(3, y0[0, L.SN_PITCH]))


def test_the_builtin_controller_reads_the_sensors_too():
    """The compiled Table I law sees the measured readings: an encoder bias of 2 deg on
    both legs moves where its flight servo holds the legs by 2 deg (the servo holds the
    reading at the touchdown angle), a Python copy of the law agrees bit for bit."""
    bias = math.radians(2.0)
    sensors = SensorParameters(hip_angle=SensorChannel(bias=bias))
    a = scoutsim.simulate(
        duration=0.05,
        model="ideal",
        sensors=sensors,
        initial_state=InitialState(y=1.0, dx=0.0, dtheta=0.0),
    )
    b = scoutsim.simulate(
        duration=0.05, model="ideal", initial_state=InitialState(y=1.0, dx=0.0, dtheta=0.0)
    )
    np.testing.assert_allclose(a.leg_angle("back")[-1], b.leg_angle("back")[-1] - bias, atol=2e-3)
    r, _, _ = _run("ideal", 0.3, sensors=sensors)
    builtin = scoutsim.simulate(duration=0.3, model="ideal", sensors=sensors)
    assert np.array_equal(r.state, builtin.state)


# -----------------------------------------------------------------------------------------
# the Sensors object and the robot file
# -----------------------------------------------------------------------------------------
def test_sensors_name_every_channel():
    s = Sensors.from_vector(np.arange(L.NSN, dtype=float))
    for name, (slot, n, _) in CHANNELS.items():
        value = getattr(s, name)
        assert np.array_equal(np.atleast_1d(value), np.arange(slot, slot + n))
    with pytest.raises(ValueError):
        s.hip_angle[0] = 1.0  # readings are read-only
    hand = Sensors(hip_angle=(0.1, 0.2), hip_rate=(0.0, 0.0), leg_length=(0.3, 0.3), pitch=0.05)
    assert hand.pitch == 0.05 and math.isnan(hand.battery_voltage)


def test_a_robot_file_describes_its_sensors(tmp_path):
    f = tmp_path / "robot.toml"
    f.write_text(
        "[robot]\ntorso_mass = 21.0\n\n[sensors]\nseed = 5\n\n"
        '[sensors.pitch]\nnoise = { value = 0.5, unit = "deg" }\ndelay = 2\n\n'
        "[sensors.hip_angle]\ncounts_per_revolution = 1000\n\n"
        '[sensors.leg_length]\nbias = [{ value = 1, unit = "mm" }, 0.0]\n'
    )
    s = load_sensors(f)
    assert s.seed == 5 and s.pitch.delay == 2
    assert s.pitch.noise == pytest.approx(math.radians(0.5))
    assert s.hip_angle.resolution == pytest.approx(2 * math.pi / (1000 * ROBOT.gear_ratio))
    assert s.leg_length.bias == pytest.approx((1e-3, 0.0))
    robot, _ = scoutsim.load_parameters(f)  # the other loaders leave [sensors] alone
    assert robot.torso_mass == 21.0


def test_a_robot_files_sensors_show_in_the_readings(tmp_path, ideal):
    """From file to readings: a pitch bias of 1 deg and a pitch-rate noise of 2 deg/s set
    in a robot file show in what a controller reads, and the file's seed reproduces
    them."""
    _, _, y0 = ideal
    f = tmp_path / "robot.toml"
    f.write_text(
        '[sensors]\nseed = 9\n[sensors.pitch]\nbias = { value = 1, unit = "deg" }\n'
        '[sensors.pitch_rate]\nnoise = { value = 2, unit = "deg/s" }\n'
    )
    _, _, y = _run(sensors=scoutsim.load_sensors(f))
    np.testing.assert_allclose(
        y[:, L.SN_PITCH] - y0[:, L.SN_PITCH], math.radians(1.0), rtol=0, atol=1e-15
    )
    e = y[:, L.SN_PITCH_RATE] - y0[:, L.SN_PITCH_RATE]
    assert abs(e.std() / math.radians(2.0) - 1.0) < 4 / math.sqrt(2 * e.size)
    _, _, again = _run(sensors=scoutsim.load_sensors(f))
    assert np.array_equal(again, y)


@pytest.mark.parametrize(
    "text, field",
    [
        ("[sensors.pitch]\nnoise = -1.0\n", "sensors.pitch.noise"),
        ("[sensors.pitch]\ndelay = 1.5\n", "sensors.pitch.delay"),
        ("[sensors.pitch]\ndelay = 1000\n", "sensors.pitch.delay"),
        ('[sensors.pitch]\nnoise = { value = 1, unit = "m" }\n', "sensors.pitch.noise"),
        ("[sensors.pich]\nnoise = 1.0\n", "pich"),
        ("[sensors]\nseed = -3\n", "sensors.seed"),
        ("[sensors.leg_length]\nbias = [0.0, 0.0, 0.0]\n", "sensors.leg_length.bias"),
    ],
)
def test_bad_sensor_entries_name_the_field(tmp_path, text, field):
    f = tmp_path / "bad.toml"
    f.write_text(text)
    with pytest.raises(ParameterError, match=field.replace(".", r"\.")):
        load_sensors(f)
