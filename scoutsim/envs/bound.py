"""``scoutsim/Bound-v0``: the planar Scout II model as a Gymnasium environment.

One class, :class:`BoundEnv`, configured in one call (the pattern of Gymnasium's MuJoCo
environments, ``hopper_v5``): every reward weight and termination rule is a constructor
keyword, the simulator's own options (model, robot file, sensors, floor) pass straight
through, and ``step`` reports each reward term in ``info``.

A policy step is ``policy_period / control_period`` samples of the compiled run loop
(:class:`~scoutsim.simulation.engine.HybridEngine`, one engine per episode): the policy's action
is held over them, as the 1 kHz controller's command is held over a control period.

Here are the environment, its episodes and its steps; the reward's settings are in
:mod:`scoutsim.envs.reward`; what an action, the spaces, a start and the rendering can be,
and the robot and controller made from the keywords, in :mod:`scoutsim.envs.configuration`.
"""

from __future__ import annotations

import dataclasses
import math

import gymnasium
import numpy as np

from ..control.sensors import SensorParameters, load_sensors
from ..names import ContactMode
from ..parameters import ControllerParameters, RobotParameters
from ..result.failure import diagnose_failure
from ..simulation.engine import HybridEngine, start_engine
from ..state import HybridState, InitialState, standing_state
from .configuration import (
    ACTION_TYPES,
    OBSERVATION_NAMES,
    PLANT_OPTIONS,
    RANDOM_START_HALF_WIDTHS,
    RENDER_MODES,
    RENDER_SIZE,
    SETPOINT_HALF_WIDTH,
    SETPOINTS,
    STARTS,
    action_scale,
    action_space,
    environment_parameters,
    observation_space,
    split_options,
    start_state,
)
from .reward import Reward, check_weights, forward_reward, health_range

__all__ = [
    "BoundEnv",
    "Reward",
    "PLANT_OPTIONS",
    "ACTION_TYPES",
    "SETPOINTS",
    "STARTS",
    "RANDOM_START_HALF_WIDTHS",
    "SETPOINT_HALF_WIDTH",
    "OBSERVATION_NAMES",
    "RENDER_MODES",
    "RENDER_SIZE",
    "NON_PHYSICAL_ENDS",
]

#: the ends of an episode that are the simulator's, not the robot's (``info["outcome"]``):
#: the integrator or the constrained dynamics could not go on, or the controller failed
NON_PHYSICAL_ENDS = ("numerical_failure", "controller_error")
#: the engine's run length [s]: a limit no episode reaches (the time limit is the
#: registration's ``max_episode_steps``); the buffers hold one policy step, whatever it is
_ENGINE_DURATION = 1.0e7


class BoundEnv(gymnasium.Env):
    """Planar bounding of Scout II (ideal, Model I or Model II) as a Gymnasium environment.

    **Observation**: the robot's sensor readings at the sample that starts the next policy
    step, as a controller sees them (:class:`~scoutsim.control.sensors.Sensors`, in its
    order, SI; their names: ``observation_names``, :data:`OBSERVATION_NAMES`): hip angles
    (back, front) [rad], hip rates [rad/s], leg lengths [m], pitch [rad], pitch rate
    [rad/s], accelerometer along the torso axis and its normal [m/s^2], laser ranges
    (back, front) [m], motor currents [A], battery voltage [V]; with the measurement model
    of ``sensors`` (noise, bias, resolution, delay). float32 (what learning libraries
    expect), within a finite box from the robot's physical ranges
    (:func:`~scoutsim.envs.configuration.observation_bounds`): a reading outside it (noise,
    a fall's last sample) is clipped to it. The float64 readings themselves, as a compiled
    controller sees them, are ``readings``. The scales differ (0.01 rad to 36 V, the
    battery voltage constant without a battery model): normalise them for learning
    (Stable-Baselines3's ``VecNormalize``, Gymnasium's ``NormalizeObservation``).

    **Action** (``action_type``), normalised to ``Box(-1, 1)`` float32 by default
    (``normalize_actions``): a component ``a`` is ``action_center + action_half_width * a``
    in physical units (``a`` clipped to [-1, 1] first;
    :func:`~scoutsim.envs.configuration.action_scale`); with ``normalize_actions=False``
    the box is the physical range itself (float32), and an action is clipped to it:

    * "torque": the hip torques (back, front) [N m per physical leg, at the leg], held
      for the policy step; the range is the robot's current-limited torque
      +-``robot.max_leg_torque`` (Scout II: 31 N m). Model I and II limit what the motor
      delivers further (torque-speed line), as for any command.
    * "setpoints": the Table I controller's set-points :data:`SETPOINTS`
      (touchdown angles and sweep limits, back and front [rad]), which the compiled
      controller runs with at 1 kHz over the policy step (its gains and thresholds are
      ``controller``'s); the range is the controller's own set-points
      +-:data:`SETPOINT_HALF_WIDTH` (25 deg), within the parameter schema's range: an
      action of 0 runs the controller as it is.

    **Reward** per step, each term in ``info``:

    * ``reward_forward``: ``forward_reward_weight`` x (v* - |v - v*|), v the torso's mean
      forward speed over the step [m/s] and v* the ``target_speed`` (default 1.3 m/s, the
      paper's bound): speed rewarded up to the target, less beyond it; ``target_speed``
      None: ``forward_reward_weight`` x v;
    * ``reward_energy``: -``energy_cost_weight`` [1/J] x the electrical energy into the
      motor terminals over the step [J] (``info["electrical_energy"]``, from the model's
      energy balance, :meth:`~scoutsim.result.simulation_result.SimulationResult.energy_balance`; negative
      while the motors regenerate more than they draw). The accounting runs only when
      ``energy_cost_weight`` is not 0 (it costs time); otherwise the energy is NaN and the
      term 0;
    * ``reward_healthy``: ``healthy_reward`` (default 0.25) while the robot is up: its COM height in
      ``healthy_height_range`` [m] and its pitch in ``healthy_pitch_range`` [rad] at the
      end of the step, and not fallen during it; none for a step the simulator could not
      complete (below).

    **Episode end** (``info["outcome"]``: "running", "fell", "numerical_failure" or
    "controller_error", the simulator's status at the end of the step):

    * ``terminated`` when the simulator detects a fall ("fell": the torso touches the
      ground or |pitch| exceeds ``pitch_limit_deg``; the model cannot go on from there)
      and, with ``terminate_when_fallen``, when the robot is not up: terminal states of
      the task, worth nothing after them;
    * ``truncated`` through the registration's ``max_episode_steps`` (1000 steps: 10 s at
      the default policy period), at the time limit;
    * ``truncated`` too, with ``terminated`` False, when the simulator cannot go on
      (:data:`NON_PHYSICAL_ENDS`): the integrator or the constrained dynamics failed
      ("numerical_failure", ``info["numerical_failure"]`` True) or the controller did
      ("controller_error"), unless the robot is down by then (the rule above; the step
      is then ``terminated`` as any other). This is Gymnasium's truncation, an end
      "outside the scope of the MDP": the robot did not fall, its state at the failure is
      a real state whose future is not worth zero, and a learner that bootstraps from the
      last observation values it rightly, where ``terminated`` would teach it that the
      state is terminal.
      It is never a healthy step: the step earns no ``reward_healthy`` (its forward and
      energy terms cover the motion up to the failure, ``info["t"]``), and ``info`` says
      what it was, so it is not mistaken for the time limit: ``info["outcome"]``,
      ``info["numerical_failure"]`` (False at every other step) and
      ``info["failure_message"]``, the simulator's diagnosis
      (:meth:`~scoutsim.result.failure.FailureDiagnosis.message`). A learner that would rather
      count such an episode as lost tests ``info["numerical_failure"]``.

    **Start** (``start``): "random", the default (the flight start with its height,
    forward speed, pitch, pitch rate and leg angles drawn uniformly within
    ``reset_noise_scale`` x :data:`RANDOM_START_HALF_WIDTHS` of it: height 0.315-0.345 m,
    1.0-1.4 m/s, pitch +-3 deg, 100-200 deg/s nose up, each leg within 3 deg of its
    touchdown angle; raised where needed so both toes start 5 mm or more above the
    ground), "flight" (:class:`~scoutsim.state.InitialState`: released in flight at
    0.33 m, 1.2 m/s, nose rising at 150 deg/s, the same start every episode: for
    evaluation), "standing" (:func:`~scoutsim.state.standing_state`: at rest on four
    legs, the policy acting from t = 0; with set-points the Table I stance-brake law holds
    the legs at the sweep limits until the policy moves them), an InitialState or
    HybridState, or a callable ``start(np_random)`` returning one (a distribution of
    starts of your own). ``reset(seed=...)`` seeds the start's draws and the sensor noise
    (a seed drawn from the environment's generator replaces ``sensors.seed``): the same
    seed gives the same episode bit for bit.

    Parameters
    ----------
    model : {"II", "I", "ideal"}
        Transmission variant (:func:`~scoutsim.simulate`).
    action_type : {"torque", "setpoints"}
    policy_period : float
        Time between the policy's actions [s] (default 0.01 s, 100 Hz); a whole multiple
        of the control period (``controller.control_period``, 1 ms).
    reward : Reward, optional
        The reward's and the termination's settings below as one bundle; a keyword given
        as well overrides its field.
    start : str, InitialState, HybridState or callable
        The start (above).
    reset_noise_scale : float
        Width of the "random" start as a fraction of :data:`RANDOM_START_HALF_WIDTHS`.
    normalize_actions : bool
        The action box ``Box(-1, 1)`` (True, the default) or the physical range (above).
    robot : RobotParameters, optional
        The robot (default: Scout II); not together with ``robot_file``.
    controller : ControllerParameters or str, optional
        The Table I parameters (default: Table I): the gains and thresholds of the
        controller the "setpoints" action drives, and the leg angles of a start in flight
        (both action types). A string ``"MODULE:FACTORY"`` names a factory of one's own
        (:mod:`scoutsim.control.factory`), called with the environment's robot and the
        Table I parameters it would otherwise use (the robot file's ``[controller]``, or
        Table I) and returning ControllerParameters (or a
        :class:`~scoutsim.control.bounding.BoundingController` with the built-in law); the
        string, not the object, is what the environment keeps, so it is made again in each
        worker of a vector environment. Not a ControllerParameters object together with
        ``robot_file``.
    robot_file : path, optional
        A robot file (TOML: robot, controller and ``[sensors]`` sections, as
        ``scoutsim run --robot``).
    sensors : SensorParameters, optional
        The sensors' measurement model (default: the robot file's, else ideal).
    render_mode : {None, "rgb_array"}
        "rgb_array": :meth:`render` returns the robot now as an (``render_height``,
        ``render_width``, 3) uint8 image (:func:`scoutsim.presentation.frames.draw_pose`:
        a side view following the torso; torso, legs coloured by the controller's leg
        state, toes filled while on the ground, the ground with a tick every 0.25 m).
        ``metadata["render_fps"]`` is the policy rate, 1 / ``policy_period``, so a video
        of one frame per step plays in real time. None: no rendering.
    **options
        The keywords under "Other Parameters" (the fields of :class:`Reward`, of
        :data:`PLANT_OPTIONS` and of :data:`RENDER_SIZE`), and any field of
        :class:`~scoutsim.parameters.RobotParameters` or
        :class:`~scoutsim.parameters.ControllerParameters` [SI], applied over ``robot`` /
        ``controller`` / the robot file (e.g. ``current_limit=10.0``).

    Other Parameters
    ----------------
    forward_reward_weight, target_speed, energy_cost_weight, healthy_reward : float
        Reward weights (above, :class:`Reward`: each default and the reason for it);
        ``target_speed`` None rewards speed itself.
    terminate_when_fallen : bool
        End the episode when the robot is not up (above).
    healthy_height_range : (min, max) [m]
        COM heights at which the robot is up (default (0.2, inf): the bound's COM stays
        within 0.28-0.33 m in every model, 0.2 m puts the torso's underside 0.14 m above
        the ground).
    healthy_pitch_range : (min, max) [rad]
        Pitch at which it is up (default +-30 deg: 2.5 times the bound's largest pitch,
        12 deg).
    friction_coefficient : float, optional
        Coulomb coefficient of the toe on the floor (default 1.0; ``inf``: no slip).
    pitch_limit_deg : float
        |pitch| [deg] the simulator counts as a fall (default 60).
    integrator : IntegratorSettings, optional
        The integrator (default: the model's, as :func:`~scoutsim.simulate`).
    render_width, render_height : int
        The frame's size [pixels] (default 480 x 240: 320 pixels per metre).
    """

    #: Gymnasium's metadata; an instance's ``render_fps`` is its policy rate (this one is
    #: that of the default policy period, 10 ms)
    metadata = {"render_modes": list(RENDER_MODES), "render_fps": 100}

    def __init__(
        self,
        model: str = "II",
        action_type: str = "torque",
        policy_period: float = 0.01,
        *,
        reward: Reward | None = None,
        start="random",
        reset_noise_scale: float = 1.0,
        normalize_actions: bool = True,
        robot: RobotParameters | None = None,
        controller: ControllerParameters | str | None = None,
        robot_file=None,
        sensors: SensorParameters | None = None,
        render_mode: str | None = None,
        **options,
    ):
        render_width, render_height = (
            options.pop(name, default) for name, default in RENDER_SIZE.items()
        )
        reward, plant, parameters = split_options(reward, options)
        forward_reward_weight, target_speed, energy_cost_weight, healthy_reward = (
            reward.forward_reward_weight,
            reward.target_speed,
            reward.energy_cost_weight,
            reward.healthy_reward,
        )
        terminate_when_fallen, healthy_height_range, healthy_pitch_range = (
            reward.terminate_when_fallen,
            reward.healthy_height_range,
            reward.healthy_pitch_range,
        )
        friction_coefficient, pitch_limit_deg, integrator = (
            plant["friction_coefficient"],
            plant["pitch_limit_deg"],
            plant["integrator"],
        )
        if model not in ("ideal", "I", "II"):
            raise ValueError(f"model = {model!r} is not allowed: must be 'ideal', 'I' or 'II'")
        if action_type not in ACTION_TYPES:
            raise ValueError(
                f"action_type = {action_type!r} is not allowed: must be one of {list(ACTION_TYPES)}"
            )
        if render_mode is not None and render_mode not in RENDER_MODES:
            raise ValueError(
                f"render_mode = {render_mode!r} is not allowed: must be None or "
                f"one of {list(RENDER_MODES)}"
            )
        for name, v in (("render_width", render_width), ("render_height", render_height)):
            if v is not None and (
                isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 16
            ):
                raise ValueError(
                    f"{name} = {v!r} is not allowed: must be a whole number of "
                    "pixels >= 16 (or None: the default)"
                )
        #: the "MODULE:FACTORY" the Table I parameters were made by (None: given)
        self.controller_spec = controller if isinstance(controller, str) else None
        self.robot, self.controller = environment_parameters(
            robot, controller, robot_file, parameters, model
        )
        if sensors is None:
            sensors = (
                load_sensors(robot_file, self.robot)
                if robot_file is not None
                else SensorParameters()
            )
        if not isinstance(sensors, SensorParameters):
            raise TypeError(f"sensors must be SensorParameters, not {type(sensors).__name__}")
        self.sensors = sensors
        self.model = model
        self.action_type = action_type
        dt = self.controller.control_period
        n = round(policy_period / dt) if policy_period > 0 else 0
        if not (
            math.isfinite(policy_period)
            and n >= 1
            and abs(n * dt - policy_period) <= 1e-9 * policy_period
        ):
            raise ValueError(
                f"policy_period = {policy_period!r} s is not allowed: must be a "
                f"whole multiple (>= 1) of the control period {dt:g} s"
            )
        self.control_period = dt
        self.samples_per_step = int(n)
        self.policy_period = n * dt
        check_weights(reward)
        self.forward_reward_weight = float(forward_reward_weight)
        self.target_speed = None if target_speed is None else float(target_speed)
        self.energy_cost_weight = float(energy_cost_weight)
        self.healthy_reward = float(healthy_reward)
        self.terminate_when_fallen = bool(terminate_when_fallen)
        self.healthy_height_range = health_range(healthy_height_range, "healthy_height_range")
        self.healthy_pitch_range = health_range(healthy_pitch_range, "healthy_pitch_range")
        if not (
            isinstance(start, (InitialState, HybridState)) or callable(start) or start in STARTS
        ):
            raise ValueError(
                f"start = {start!r} is not allowed: must be one of "
                f"{list(STARTS)}, an InitialState, a HybridState or a callable"
            )
        if start == "standing":
            start = standing_state(self.robot, model, self.controller)
        self.start = start
        if not (math.isfinite(reset_noise_scale) and reset_noise_scale >= 0.0):
            raise ValueError(
                f"reset_noise_scale = {reset_noise_scale!r} is not allowed: "
                "must be a finite number >= 0"
            )
        self.reset_noise_scale = float(reset_noise_scale)
        self.friction_coefficient = friction_coefficient
        self.pitch_limit_deg = pitch_limit_deg
        self.integrator = integrator
        self.render_mode = render_mode
        #: the frame's size keywords of draw_pose (none: its default size)
        self._frame_size = {
            key: int(v)
            for key, v in (("width", render_width), ("height", render_height))
            if v is not None
        }
        rate = 1.0 / self.policy_period
        self.metadata = {
            **type(self).metadata,
            "render_fps": round(rate) if abs(rate - round(rate)) < 1e-9 * rate else rate,
        }
        self.observation_space = observation_space(self.robot, pitch_limit_deg)
        #: the observation's names, in its order (:data:`OBSERVATION_NAMES`)
        self.observation_names = OBSERVATION_NAMES
        self.normalize_actions = bool(normalize_actions)
        self.action_space = action_space(
            self.robot, self.controller, action_type, self.normalize_actions
        )
        centre, half = action_scale(self.robot, self.controller, action_type)
        #: the physical action of a normalised action ``a``: ``action_center +
        #: action_half_width * a`` [N m or rad] (float64)
        self.action_center, self.action_half_width = centre, half
        #: the float64 sensor readings of the last observation (in its order, SI)
        self.readings = np.full(self.observation_space.shape, np.nan)
        #: the set-points' slots in the engine's controller array ``engine.C``
        self._engine: HybridEngine | None = None
        # an engine from the first start, to check the options now (reset makes the
        # episode's)
        self._new_engine(self._start(None), 0)
        self._running = False
        self._reset_done = False

    # -- the episode ----------------------------------------------------------------------

    @property
    def dt(self) -> float:
        """Time of one environment step [s] (the policy period)."""
        return self.policy_period

    @property
    def engine(self):
        """The episode's :class:`~scoutsim.simulation.engine.HybridEngine` (its state ``s``, modes,
        energy accumulator), read-only by convention."""
        return self._engine

    @property
    def _live_engine(self) -> HybridEngine:
        """The engine, for the pieces below (the constructor makes one, reset() the
        episode's)."""
        assert self._engine is not None  # (made in __init__, never cleared)
        return self._engine

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode (see the class docstring); returns (observation, info)."""
        super().reset(seed=seed)
        noise_seed = int(self.np_random.integers(0, 2**63 - 1))
        self._new_engine(self._start(self.np_random), noise_seed)
        # the readings of sample 0 under zero torques, as simulate()'s controllers see them
        # before their first command (with torque actions the loop reads sample 0 again
        # under the first action: the accelerometer, currents and battery of that reading
        # are what a channel delayed past sample 0 reports at first)
        obs = self._observe(self._live_engine.read_sensors())
        self._reset_done = True
        return obs, self._info_now()

    def step(self, action):
        """Hold ``action`` for one policy period; returns (observation, reward, terminated,
        truncated, info)."""
        eng = self._engine
        if eng is None or not self._running:
            raise RuntimeError("BoundEnv.step: the episode has ended (or not begun): call reset()")
        a = self.physical_action(action)
        if self.action_type == "torque":
            eng.cmd[:] = a
        else:
            eng.retune(**dict(zip(SETPOINTS, a)))
        x0, t0, e0 = eng.x, eng.t_now, self._electrical()
        eng.advance(eng.k + self.samples_per_step)
        outcome = eng.status_name
        broken = outcome in NON_PHYSICAL_ENDS
        message = self._failure_message() if broken else None  # (from the step's records)
        eng.discard_records()
        obs = self._observe(eng.read_sensors())
        x1, t1 = eng.x, eng.t_now
        energy = self._electrical() - e0
        fell = eng.fell
        up_now = self._is_up()
        # healthy: a whole step that ended up; down: fallen, or not up (when that ends it)
        # at a state that is one (a state that is not finite says nothing either way)
        up = not fell and not broken and up_now
        down = fell or (self.terminate_when_fallen and not up_now and self._state_finite())
        v = (x1 - x0) / (t1 - t0) if t1 > t0 else 0.0
        r_forward = forward_reward(self.forward_reward_weight, v, self.target_speed)
        r_energy = -self.energy_cost_weight * energy if self._accounting else 0.0
        r_healthy = self.healthy_reward if up else 0.0
        reward = r_forward + r_energy + r_healthy
        terminated = down
        # the simulator could not go on (a numerical failure, a controller error): the end
        # of an episode outside the task, Gymnasium's truncation (class docstring)
        truncated = not terminated and eng.stopped
        self._running = not (terminated or truncated)
        info = self._info_now()
        info.update(
            reward_forward=r_forward,
            reward_energy=r_energy,
            reward_healthy=r_healthy,
            x_velocity=v,
            electrical_energy=energy,
            is_healthy=up,
            numerical_failure=outcome == "numerical_failure",
        )
        if broken:
            info["failure_message"] = message
        return obs, float(reward), bool(terminated), bool(truncated), info

    def render(self):
        """The robot now (after the last :meth:`reset` or :meth:`step`) as an
        (``render_height``, ``render_width``, 3) uint8 RGB array with ``render_mode``
        "rgb_array" (see the class docstring); None with ``render_mode`` None."""
        if self.render_mode is None:
            return None
        if not self._reset_done:
            raise gymnasium.error.ResetNeeded("BoundEnv.render: call reset() before render()")
        # the drawing lives in the presentation layer (deferred: imported on first render)
        from ..presentation.frames import RobotPose, draw_pose

        eng = self._engine
        legs = (0, 1)
        pose = RobotPose.of(
            self.robot,
            eng.x,
            eng.height,
            eng.pitch,
            toes=[eng.toe_position(leg) for leg in legs],
            contact=[eng.contact_mode(leg) != ContactMode.FLIGHT for leg in legs],
            # the Table I controller's leg states ("torque": no controller runs)
            leg_states=tuple(eng.ls) if self.action_type == "setpoints" else None,
        )
        return draw_pose(pose, **self._frame_size)

    def physical_action(self, action) -> np.ndarray:
        """The physical action [N m or rad] (float64) that ``action`` (of the action space)
        stands for: ``action_center + action_half_width * clip(action, -1, 1)`` with
        normalised actions, ``action`` clipped to the physical box without."""
        a = np.asarray(action, dtype=np.float64).reshape(self.action_space.shape)
        if not np.all(np.isfinite(a)):
            raise ValueError(f"BoundEnv.step: action {a.tolist()} is not allowed: must be finite")
        if self.normalize_actions:
            return self.action_center + self.action_half_width * np.clip(a, -1.0, 1.0)
        lo, hi = (
            self.action_center - self.action_half_width,
            self.action_center + self.action_half_width,
        )
        return np.clip(a, lo, hi)

    # -- pieces -----------------------------------------------------------------------------

    def _observe(self, readings: np.ndarray) -> np.ndarray:
        """The observation of the float64 ``readings`` (kept as ``readings``): float32,
        clipped to the observation box."""
        self.readings = readings.copy()
        box = self.observation_space
        assert isinstance(box, gymnasium.spaces.Box)
        return np.clip(readings.astype(np.float32), box.low, box.high)

    def _start(self, rng):
        """The episode's start drawn with ``rng`` (None: without its draws)."""
        return start_state(
            self.start, self.reset_noise_scale, rng, robot=self.robot, controller=self.controller
        )

    def _new_engine(self, start, noise_seed: int):
        """A fresh engine for an episode from ``start`` with sensor noise seed
        ``noise_seed``."""
        self._accounting = self.energy_cost_weight != 0.0
        self._engine = start_engine(
            start,
            _ENGINE_DURATION,
            robot=self.robot,
            model=self.model,
            controller=self.controller,
            hold_commands=self.action_type == "torque",
            sensors=self.sensors.replace(seed=noise_seed),
            friction_coefficient=self.friction_coefficient,
            pitch_limit_deg=self.pitch_limit_deg,
            integrator=self.integrator,
            energy=self._accounting,
            rows=self.samples_per_step + 2,
        )
        self._running = True

    def _electrical(self) -> float:
        """Electrical energy into both legs' motor terminals since the start [J] (NaN
        without the accounting)."""
        return self._live_engine.electrical_energy()

    def _failure_message(self) -> str:
        """What stopped the simulator in the step just run (its records still in the
        engine): the diagnosis of a numerical failure
        (:func:`~scoutsim.result.failure.diagnose_failure`), or the controller's failure."""
        eng = self._live_engine
        if eng.status_name != "numerical_failure":
            return f"the controller failed at t = {eng.t_now:.6g} s (outcome {eng.status_name!r})"
        provenance = {
            "model": self.model,
            "robot": dataclasses.asdict(self.robot),
            "controller": dataclasses.asdict(self.controller),
            "integrator": dataclasses.asdict(eng.integ),
        }
        diagnosis = diagnose_failure(eng.result(provenance))
        assert diagnosis is not None  # (the run's outcome is "numerical_failure")
        return diagnosis.message()

    def _state_finite(self) -> bool:
        return bool(np.all(np.isfinite(self._live_engine.s)))

    def _is_up(self) -> bool:
        eng = self._live_engine
        (h0, h1), (p0, p1) = self.healthy_height_range, self.healthy_pitch_range
        return bool(h0 <= eng.height <= h1 and p0 <= eng.pitch <= p1)

    def _info_now(self) -> dict:
        eng = self._live_engine
        return {
            "t": eng.t_now,
            "x_position": eng.x,
            "height": eng.height,
            "pitch": eng.pitch,
            "outcome": eng.status_name,
        }
