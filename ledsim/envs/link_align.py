"""``ledsim/LinkAlign-v0``: two photodiode powers in, gimbal torque out.

The receiver gimbal on the AUV starts misaligned by up to ``phi0_range`` and must be
turned onto the LED beam, under the chosen disturbances, from the photodiode powers alone.

**Observation** (``Box(-inf, inf, (2,), float64)``)

===  ===============================================  =====
idx  observation                                      unit
===  ===============================================  =====
0    measured power of photodiode 1 (with noise)      W
1    measured power of photodiode 2 (with noise)      W
===  ===============================================  =====

**Action** (``Box(-1, 1, (1,), float32)``)

===  ===============================================  =====
idx  action                                           unit
===  ===============================================  =====
0    gimbal motor torque / ``torque_limit``           -
===  ===============================================  =====

**Reward**: the noise-free power of photodiode 1 divided by its peak (0..1): the share of
the best possible link quality received this step. **Episode**: never terminates (a lost
link can be found again); truncated after 1000 steps (10 s) by ``gymnasium.make``.
``info`` holds the true state (``phi`` [rad], ``phidot`` [rad/s]) and the noise-free
powers, for evaluation only.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from observer.supervision import ResidualMonitor

from ..config import LinkConstants
from ..optics import peak_power
from ..physics.disturbances import parse_disturbance
from ..physics.scene import WorldConfig
from ..physics.sensor import IrradianceSensor
from ..physics.system import GimbalSystem


class LinkAlignEnv(gym.Env):
    """Keep the receiver aligned on the LED beam (see the module docstring).

    Args:
        distance: link distance d [m].
        noise_scale: multiplies the measurement-noise standard deviation [-].
        disturbances: disturbance specs ``name[:key=value,...]`` (``ledsim run`` syntax).
        torque_limit: motor torque at action 1 [N m].
        frame_skip: physics steps per action (the control period is frame_skip x 2 ms).
        phi0_range: initial misalignment drawn uniformly in +-phi0_range [rad].
        render_mode: None or ``"rgb_array"``.
        width, height, camera: rendered frame size [px] and camera name.
        integrator: MuJoCo integrator (``implicitfast``, ``euler``, ...; see
            docs/integrators.md).
        scene: MJCF scene file (None: the shipped one).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 100}

    def __init__(self, distance: float = 0.085, noise_scale: float = 1.0,
                 disturbances: tuple[str, ...] = (), torque_limit: float = 0.05,
                 frame_skip: int = 5, phi0_range: float = 0.3, render_mode: str | None = None,
                 width: int = 640, height: int = 480, camera: str = "side",
                 integrator: str = "implicitfast", scene: str | None = None):
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode={render_mode!r}: use None or 'rgb_array'")
        if int(frame_skip) < 1:
            raise ValueError(f"frame_skip={frame_skip!r}: must be >= 1")
        constants = LinkConstants(distance=distance, Te=0.002 * int(frame_skip))
        extra = {} if scene is None else {"xml": scene}
        self.system = GimbalSystem(WorldConfig(constants=constants, torque_limit=torque_limit,
                                               integrator=integrator, **extra))
        self.world = self.system.world
        self.noise_scale = noise_scale
        self.disturbance_specs = tuple(disturbances)
        self.disturbances = [parse_disturbance(d) for d in self.disturbance_specs]
        self.torque_limit = torque_limit
        self.phi0_range = phi0_range
        self.peak = peak_power(constants)
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": int(round(1.0 / constants.Te))}
        self._render_args = (width, height, camera)
        self._recorder = None
        self.observation_space = spaces.Box(-np.inf, np.inf, (2,), np.float64)
        self.action_space = spaces.Box(-1.0, 1.0, (1,), np.float32)
        self.sensor = None
        self._reading = None

    def _observe(self):
        self.world.forward_kinematics()
        self._reading = self.sensor.read()
        r = self._reading
        info = {"phi": r.phi, "phidot": r.phidot, "power_clean": r.power_clean.copy(),
                "time": self.world.time}
        return r.power.astype(np.float64), info

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        phi0 = float(self.np_random.uniform(-self.phi0_range, self.phi0_range))
        self.world.reset(gimbal_angle=self.system.phi_home - phi0)
        run_seed = int(self.np_random.integers(2**31))
        self.sensor = IrradianceSensor(self.world, seed=run_seed, noise_scale=self.noise_scale)
        for d in self.disturbances:
            d.reset(run_seed)
        return self._observe()

    def step(self, action):
        if self.sensor is None:
            raise RuntimeError("call reset() before step()")
        a = float(np.clip(np.asarray(action, dtype=float).reshape(-1)[0], -1.0, 1.0))
        t = self.world.time
        self.world.clear_hull_wrench()
        for d in self.disturbances:
            d.apply(self.world, t)
        self.world.set_torque(a * self.torque_limit)
        self.world.step()
        obs, info = self._observe()
        reward = float(self._reading.power_clean[0] / self.peak)
        return obs, reward, False, False, info

    def render(self):
        if self.render_mode != "rgb_array":
            return None
        if self._recorder is None:
            from ..physics.render import FrameRecorder

            w, h, cam = self._render_args
            self._recorder = FrameRecorder(self.world, w, h, self.metadata["render_fps"], cam,
                                           label="LinkAlign-v0")
        r = self._reading
        self._recorder.overlay.push(r.phi, r.phi, r.power[0], r.power[1])
        return self._recorder.render(self.world.time, r)

    def close(self):
        if self._recorder is not None:
            self._recorder.close()
            self._recorder = None


class EstimatorObservation(gym.ObservationWrapper):
    """Adds an estimator's output to the observation: (P1 [W], P2 [W], phi_hat [rad],
    phidot_hat [rad/s]), and with ``lost_flag`` a fifth entry, 1.0 when the residual
    monitor of ``ledsim run`` (:class:`observer.supervision.ResidualMonitor`) does not
    trust the estimate, else 0.0. The estimator runs behind the same dropout gate as
    ``ledsim run``, and is told the applied acceleration each step."""

    def __init__(self, env: LinkAlignEnv, estimator: str = "kkl", lost_flag: bool = False):
        super().__init__(env)
        self.policy = ShippedAlignmentPolicy(env.unwrapped, estimator)
        self.lost_flag = lost_flag
        self.observation_space = spaces.Box(-np.inf, np.inf, (5 if lost_flag else 4,),
                                            np.float64)

    def reset(self, **kw):
        self.policy.reset()
        return super().reset(**kw)

    def step(self, action):
        self.policy.last_action = float(np.asarray(action).reshape(-1)[0])
        return super().step(action)

    def observation(self, obs):
        parts = [obs, self.policy.estimate(obs)]
        if self.lost_flag:
            parts.append([float(self.policy.lost)])
        return np.concatenate(parts)


class ShippedAlignmentPolicy:
    """The shipped observer and alignment controller of ``ledsim run`` as a policy:
    ``action = policy(observation)`` on :class:`LinkAlignEnv` (default frame_skip)."""

    def __init__(self, env: LinkAlignEnv, estimator: str = "kkl"):
        from ..control import AlignmentPID
        from ..estimators import build_estimator
        from ..loop.closed_loop import identified_model
        from ..loop.gate import DropoutGate
        from ..resources import require_shipped_checkpoint

        system = env.system
        c = system.constants
        ckpt = require_shipped_checkpoint(c.distance, "mujoco") if estimator == "kkl" else None
        self.env = env
        # Fitted on a world of its own: fitting sets and steps MuJoCo's state.
        model = identified_model(GimbalSystem(system.config))
        self.estimator = build_estimator(estimator, system, model=model, checkpoint=ckpt)
        self.law_template = AlignmentPID()
        self.gate = DropoutGate(c)
        self.monitor = ResidualMonitor(model)
        self.warmup_steps = int(round(1.0 / c.Te))
        self.reset()

    def reset(self) -> None:
        self.estimator.reset()
        self.gate.reset()
        self.monitor = ResidualMonitor(self.monitor.system)
        self.lost = False
        self.law = self.law_template.start(self.env.system.constants)
        self.k = 0
        self.last_action = 0.0
        self._xhat = None

    def estimate(self, obs) -> np.ndarray:
        """Take the measurement of this step; returns x_hat (phi [rad], phidot [rad/s])."""
        if self._xhat is not None:  # the previous step's input moves the estimator on
            u = -self.last_action * self.env.torque_limit / self.env.system.inertia
            self.estimator.predict(u)
        y = self.gate(np.asarray(obs, dtype=float)[:2])
        self._xhat = self.estimator.update(y)
        self.lost = self.monitor.update(y, self._xhat)
        return self._xhat

    def __call__(self, obs) -> np.ndarray:
        xhat = self.estimate(obs)
        self.k += 1
        if self.k <= self.warmup_steps:  # let the estimator forget its initial guess
            action = 0.0
        else:
            u = self.law(xhat, self.k * self.env.system.constants.Te)
            torque = float(self.env.system.torque_for(u))
            action = float(np.clip(torque / self.env.torque_limit, -1.0, 1.0))
        self.last_action = action
        return np.array([action], dtype=np.float32)
