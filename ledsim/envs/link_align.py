"""``ledsim/LinkAlign-v0``: two photodiode powers in, gimbal torque out.

The receiver gimbal on the AUV starts misaligned and must be turned onto the LED beam,
under the chosen disturbances, from the photodiode powers alone. The world is
``ledsim run``'s: the same start, sensor noise, disturbances and physics tick, so with
``scenario="align"`` the episode of ``reset(seed=K)`` is seed K of
``ledsim run --scenario align`` until the actions differ.

**Observation** (``Box(low, high, (7,), float64)``; ``(2,)`` with ``imu=False``. The
powers run from 20 noise standard deviations below zero to the power at 1 cm from the
LED plus as much, so a measured power never leaves them; the vehicle's readings are
clipped to the bounds below)

===  =======================================================  =====  =============
idx  observation                                              unit   bound
===  =======================================================  =====  =============
0    measured power of photodiode 1 (with noise)              W      see above
1    measured power of photodiode 2 (with noise)              W      see above
2    the IMU's yaw rate (gyro z, with noise)                  rad/s  +-60
3    the DVL's velocity, x of its frame (with noise)          m/s    +-5
4    the DVL's velocity, y of its frame (with noise)          m/s    +-5
5    the gimbal's encoder angle (14-bit, within one turn)     rad    +-pi
6    the line-of-sight rate the vehicle measures (Vehicle)    rad/s  +-100
===  =======================================================  =====  =============

The vehicle keeps station on its thrusters by default (``station_keeping``).

**Action** (``Box(-1, 1, (1,), float32)``)

===  ===============================================  =====
idx  action                                           unit
===  ===============================================  =====
0    gimbal motor torque / ``torque_limit``           -
===  ===============================================  =====

A float64 action is applied in full precision (the shipped policy relies on it).

**Reward**, in [0, 1]: the noise-free power of photodiode 1 over the most it could
receive at that moment's geometry (the LED's distance and angle, a perfectly pointed
photodiode: what ``availability`` compares with): the share of the achievable link
received this step. Moving the vehicle closer to the LED raises both alike, so only
pointing earns reward. **Episode**: never terminates (a lost link can be found again);
truncated after 1000 steps (10 s) by ``gymnasium.make``.
``info`` holds the true state (``phi`` [rad], ``phidot`` [rad/s]), the noise-free
powers and the time [s], for evaluation only.

**Start**: the scenario's (``align``: 0.3 rad), or uniform in +-``phi0_range`` without
a scenario; ``reset(options={"initial_angle": RAD})`` starts the episode at that true
incidence angle, at rest, whatever the scenario (``ledsim run --initial-angle``).
"""

from __future__ import annotations

import math
from dataclasses import replace

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.utils import EzPickle

from ledsim.agent.laws import receiver_peak
from ledsim.constants import MIN_DISTANCE, LinkConstants
from ledsim.envs.arguments import constructor_arguments, initial_angle
from ledsim.loop.build.estimation import run_noise
from ledsim.loop.build.start import start_world
from ledsim.loop.run_config import EstimatorPart, RunConfig, TaskPart, WorldPart
from ledsim.physics.gimbal_system import GimbalSystem
from ledsim.physics.sensor import SensorReading
from ledsim.physics.world_rows import WorldRows
from ledsim.radiometry.link_presets import link_constants, preset_named
from ledsim.radiometry.optics import IMPOSSIBLE_SIGMAS, achievable_power, peak_power

#: Bounds of the vehicle's readings in the observation (indices 2-6): gyro z [rad/s],
#: DVL x, y [m/s], encoder [rad], LOS rate [rad/s].
VEHICLE_BOUND = np.array([60.0, 5.0, 5.0, math.pi, 100.0])




class LinkAlignEnv(gym.Env, EzPickle):
    """Keep the receiver aligned on the LED beam (see the module docstring).

    Args:
        scenario: a scenario of ``ledsim run`` (``align``, ...): ``reset(seed=K)`` starts
            as seed K of ``ledsim run --scenario`` does. None: the initial misalignment
            is drawn uniformly in +-``phi0_range``, and the run's seed from ``seed``.
        frame_skip: physics steps per action (the control period is frame_skip x 2 ms).
        phi0_range: initial misalignment drawn uniformly in +-phi0_range [rad].
        render_mode: None or ``"rgb_array"``.
        width, height, camera: rendered frame size [px] and camera name.
        **spec: the run's settings, by their names in ``ledsim run``'s spec
            (:data:`SPEC_NAMES`): every field of
            :class:`~ledsim.loop.run_config.WorldPart` (``distance``, ``link``,
            ``torque_limit`` (the motor torque at action 1 [N m]), ``noise_scale``,
            ``depth``, ...), the task's ``disturbances`` and ``acquisition`` (how the
            shipped policy acquires the link; the env's own dynamics do not depend on
            it), and the estimation's ``imu`` (observe the vehicle's IMU, DVL and
            encoder, indices 2-6; the shipped policy then uses them as ``ledsim run``
            does). Positional arguments keep ledsim 0.2's order (:data:`POSITIONAL`).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 100}

    def __init__(self, scenario: str | None = None, *args, frame_skip: int = 5,
                 phi0_range: float = 0.3, render_mode: str | None = None, width: int = 640,
                 height: int = 480, camera: str = "side", **spec):
        own = {"frame_skip": frame_skip, "phi0_range": phi0_range, "render_mode": render_mode,
               "width": width, "height": height, "camera": camera}
        own, spec = constructor_arguments(args, own, spec)
        frame_skip, phi0_range, render_mode, width, height, camera = own.values()
        # Pickles as its constructor arguments (MuJoCo's model does not pickle), as
        # Gymnasium's MuJoCo environments do: the copy is a new environment.
        EzPickle.__init__(self, scenario, frame_skip=frame_skip, phi0_range=phi0_range,
                          render_mode=render_mode, width=width, height=height,
                          camera=camera, **spec)
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode={render_mode!r}: use None or 'rgb_array'")
        if int(frame_skip) < 1:
            raise ValueError(f"frame_skip={frame_skip!r}: must be >= 1")
        disturbances = spec.pop("disturbances", ())
        spec["disturbances"] = (disturbances,) if isinstance(disturbances, str) \
            else tuple(disturbances)
        for flag in ("imu", "station_keeping", "receiver_dome", "transmitter_aimed"):
            if flag in spec:
                spec[flag] = bool(spec[flag])
        if "gimbal" not in spec and "receiver" not in spec:
            spec["gimbal"] = "yaw"  # v0 and v1 keep the paper's one axis on every link
        fixed = preset_named(spec.get("link", WorldPart.link)).ships_fixed_kkls
        # The env needs no estimator; its policy names its own (on a physical link the
        # shipped KKL does not serve: docs/link.md).
        self.cfg = RunConfig(scenario=scenario or TaskPart.scenario, **spec,
                             estimator=EstimatorPart.estimator if fixed else "ekf")
        self.cfg.validate()
        distance, noise_scale = self.cfg.distance, self.cfg.noise_scale
        torque_limit = self.cfg.torque_limit
        world_config = self.cfg.world_config()
        Te = world_config.timestep * int(frame_skip)
        if Te != world_config.constants.Te:
            c = self.cfg
            world_config = replace(world_config, constants=link_constants(
                c.link, distance, c.water, c.attenuation, LinkConstants(Te=Te),
                c.world.lens_field))
        self.system = self._system_of(world_config)
        self.world = self.system.world
        self.model, self.data = self.world.model, self.world.data
        self.dt = self.system.Te
        self.random_start = scenario is None
        self.noise_scale = noise_scale
        self.disturbance_specs = self.cfg.disturbances
        self.torque_limit = torque_limit
        self.phi0_range = phi0_range
        c = self.system.constants
        self.peak = peak_power(c)
        self.peak_response = receiver_peak(c)
        self.measurement_noise = run_noise(self.cfg, self.system)
        margin = IMPOSSIBLE_SIGMAS * self.measurement_noise.std
        # the observation space's upper bound: the power where the housings touch
        closest = float(achievable_power(MIN_DISTANCE, 0.0, c, self.peak_response))
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": int(round(1.0 / self.dt))}
        self._render_args = (width, height, camera)
        self._recorder = None
        low, high = np.array([-margin] * 2), np.array([closest + margin] * 2)
        if self.cfg.imu:
            low, high = np.r_[low, -VEHICLE_BOUND], np.r_[high, VEHICLE_BOUND]
        self.observation_space = spaces.Box(low, high, dtype=np.float64)
        # one duty per gimbal axis (the paper's one axis: shape (1,))
        self.action_space = spaces.Box(-1.0, 1.0, (self.world.n_axes,), np.float32)
        self.rows = WorldRows([self.world])  # the world as a row of one: the one tick
        self.sensor = None
        self.vehicle = None
        self.disturbances: list = []
        self.reading: SensorReading | None = None
        self.run_seed: int | None = None
        self.episode = 0  # resets so far (a policy restarts when it changes)
        self.k = 0  # control steps of this episode
        self.start_gimbal_angle = 0.0

    def _system_of(self, world_config):
        """The model system of the env's world (a pan-tilt's: ``envs.head_align``)."""
        return GimbalSystem(world_config)

    def _observe(self, reading=None):
        r = self.reading = self.sensor.read() if reading is None else reading
        info = {"phi": r.phi, "phidot": r.phidot, "power_clean": r.power_clean.copy(),
                "time": self.k * self.dt}
        space = self.observation_space
        obs = r.power.astype(np.float64)
        if self.cfg.imu:
            v = self.vehicle
            nav = v.reading
            encoder = math.remainder(nav.encoder, 2 * math.pi)
            obs = np.array([*obs.tolist(), nav.gyro[2], *nav.dvl[:2], encoder, v.los.rate])
        return np.minimum(np.maximum(obs, space.low), space.high), info  # np.clip, cheaper

    def share_of_achievable(self) -> float:
        """Photodiode 1's noise-free power over the most the current geometry allows
        (the reward) [-]; round-off above 1 is cut."""
        r = self.reading
        lay = self.system.constants.layout
        best = float(achievable_power(lay.reference_power(r.distance),
                                      lay.reference_power(r.emission_angle),
                                      self.system.constants, self.peak_response))
        return min(1.0, float(lay.reference_power(r.power_clean)) / best) if best > 0 else 0.0

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        x0 = None
        if self.random_start:
            x0 = (float(self.np_random.uniform(-self.phi0_range, self.phi0_range)), 0.0)
        angle = (options or {}).get("initial_angle")
        if angle is not None:  # the user's start overrides the scenario's and the random one
            x0 = (initial_angle(angle), 0.0)
        if seed is None or self.random_start:
            self.run_seed = int(self.np_random.integers(2**31))
        else:
            self.run_seed = int(seed)
        self.sensor, self.disturbances, vehicle = start_world(
            self.cfg, self.system, self.world, self.run_seed, x0, self.measurement_noise)
        (self.vehicle,) = self.rows.start([self.sensor], [self.disturbances], [vehicle])
        self.start_gimbal_angle = self.world.gimbal_angle
        self.k = 0
        self.episode += 1
        return self._observe()

    def step(self, action):
        self.command(action)
        self.rows.tick(self.k * self.dt)
        return self.observe_step()

    # The step in parts, so that a vector of these envs (envs.vector) steps the physics
    # and the vehicles of all its worlds in one pass, on its own rows: the same tick.

    def command(self, action) -> float:
        """Check ``action`` and command its torque [N m] (the physics not yet stepped);
        returns the torque applied after the motor's limit."""
        a = self.check_action(action)
        n = a.size
        if n > 1:  # one duty per axis
            self.k += 1
            return self.world.set_torques(np.clip(a, -1.0, 1.0) * self.torque_limit)
        return self.command_duty(float(a[0]))

    def check_action(self, action) -> np.ndarray:
        """``action`` as the duties [-] it commands, (n_axes,), or a one-line error
        naming it (and a RuntimeError before :meth:`reset`)."""
        if self.sensor is None:
            raise RuntimeError("call reset() before step()")
        a = np.asarray(action, dtype=float).reshape(-1)
        n = self.action_space.shape[0]
        if a.size != n or not np.isfinite(a).all():
            raise ValueError(f"action {action!r} is not allowed: "
                             + ("one finite number" if n == 1 else f"{n} finite numbers")
                             + " in [-1, 1]")
        return a

    def command_duty(self, duty: float) -> float:
        """:meth:`command` of a checked, finite duty [-] of the one axis (the vector env
        checks its whole batch of actions at once)."""
        if self.sensor is None:
            raise RuntimeError("call reset() before step()")
        self.k += 1
        return self.world.set_torque(min(max(duty, -1.0), 1.0) * self.torque_limit)

    def observe_step(self, reading=None):
        """After the next control step was prepared (its vehicle acted): observe (the
        sensor's ``reading`` read with other worlds', or now) and reward."""
        obs, info = self._observe(reading)
        reward = self.share_of_achievable()
        return obs, reward, False, False, info

    def render(self):
        if self.render_mode != "rgb_array":
            return None
        if self._recorder is None:
            from ledsim.physics.render import FrameRecorder

            w, h, cam = self._render_args
            self._recorder = FrameRecorder(self.world, w, h, self.metadata["render_fps"], cam,
                                           label="LinkAlign-v0", estimate=False)
        r = self.reading
        self._recorder.overlay.push(r.phi, np.nan, *r.power)
        return self._recorder.render(self.k * self.dt, r)

    def close(self):
        self.rows.close()
        if self._recorder is not None:
            self._recorder.close()
            self._recorder = None

