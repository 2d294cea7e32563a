"""``ledsim run``'s stack on :class:`~ledsim.envs.link_align.LinkAlignEnv`: the shipped
policy, and a wrapper that adds an estimator's output to the observation."""

from __future__ import annotations

from dataclasses import replace

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from ledsim.agent.step import GimbalMotor
from ledsim.envs.link_align import LinkAlignEnv
from ledsim.loop.build.control import control_step, dropout_gate, run_supervisor
from ledsim.loop.build.estimation import identified_model_of


def torque_action(torque: float, limit: float) -> float:
    """The action in [-1, 1] whose ``action * limit`` is ``torque`` [N m] to the last
    bit where one exists (so the environment applies what ``ledsim run`` applies)."""
    a = torque / limit
    # A torque that is some duty times the limit (GimbalMotor's) is within two ulps.
    up, down = [a], [a]
    for _ in range(2):
        up.append(float(np.nextafter(up[-1], np.inf)))
        down.append(float(np.nextafter(down[-1], -np.inf)))
    for cand in (a, up[1], down[1], up[2], down[2]):
        if float(cand) * limit == torque:
            a = float(cand)
            break
    return min(max(a, -1.0), 1.0)


class ShippedAlignmentPolicy:
    """``ledsim run``'s stack as a policy on :class:`LinkAlignEnv`: the dropout gate, the
    estimator under link supervision (the gain-scheduled KKL, acquisition scans), the scenario's
    control law and the warm-up hold, through the same
    :class:`~ledsim.agent.step.ControlStep`. ``action = policy(observation)``; it starts
    afresh with each episode of the environment.

    Args:
        env: the (unwrapped) environment.
        estimator: ``kkl``, ``ekf``, ``ukf``, ``pf`` or ``oracle``.
    """

    def __init__(self, env: LinkAlignEnv, estimator: str = "kkl"):
        self.env = env.unwrapped if hasattr(env, "unwrapped") else env
        self.cfg = replace(self.env.cfg, estimator=estimator)
        self.cfg.validate()
        self.step = None
        self._episode = None

    def reset(self) -> None:
        """Start afresh at the next call (the policy also does so by itself when the
        environment starts a new episode)."""
        self._episode = None

    def _start(self) -> None:
        env = self.env
        model = identified_model_of(env.system.config)
        self.step = control_step(self.cfg, env.system, model, env.run_seed,
                                 env.start_gimbal_angle, lambda: env.reading.x,
                                 noise=env.measurement_noise)
        self._episode = env.episode

    @property
    def lost(self) -> bool:
        """The supervisor does not trust the estimate (last step)."""
        return bool(self.step is not None and self.step.decision.lost)

    def __call__(self, obs) -> np.ndarray:
        env = self.env
        if self._episode != env.episode:
            self._start()
        r = env.reading
        los = env.vehicle.los if self.cfg.imu else None
        torque = self.step(np.asarray(obs, dtype=float)[:2], env.k * env.dt,
                           r.gimbal_angle, r.gimbal_rate, los)
        return np.array([torque_action(torque, env.torque_limit)])


#: The estimate's part of the observation is clipped to this (phi [rad], phidot [rad/s]):
#: beyond any angle or rate the gimbal reaches (the largest kick is 50 rad/s).
ESTIMATE_BOUND = np.array([np.pi, 100.0])


class EstimatorObservation(gym.ObservationWrapper, gym.utils.RecordConstructorArgs):
    """Adds an estimator's output to the observation: (P1 [W], P2 [W], phi_hat [rad],
    phidot_hat [rad/s], the estimate clipped to :data:`ESTIMATE_BOUND`), and with
    ``lost_flag`` a fifth entry, 1.0 when the link supervisor of ``ledsim run`` does not
    trust the estimate, else 0.0. The estimator
    runs behind the same dropout gate and supervisor as in ``ledsim run`` (without the
    acquisition scan: the agent has the motor), and is told the acceleration the
    agent's torque commands each step."""

    def __init__(self, env, estimator: str = "kkl", lost_flag: bool = False):
        gym.utils.RecordConstructorArgs.__init__(self, estimator=estimator,
                                                 lost_flag=lost_flag)
        gym.ObservationWrapper.__init__(self, env)
        base = env.unwrapped
        self.cfg = replace(base.cfg, estimator=estimator)
        self.cfg.validate()
        self.lost_flag = lost_flag
        low, high = env.observation_space.low, env.observation_space.high
        low, high = np.r_[low, -ESTIMATE_BOUND], np.r_[high, ESTIMATE_BOUND]
        if lost_flag:
            low, high = np.r_[low, 0.0], np.r_[high, 1.0]
        self.observation_space = spaces.Box(low, high, dtype=np.float64)
        self.supervisor = None
        self.decision = None

    @property
    def lost(self) -> bool:
        return bool(self.decision is not None and self.decision.lost)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        obs, info = self.env.reset(seed=seed, options=options)
        base = self.env.unwrapped
        model = identified_model_of(base.system.config)
        self.motor = GimbalMotor(base.system.inertia)
        self.supervisor = run_supervisor(self.cfg, base.system, model, base.run_seed,
                                         lambda: base.reading.x, reacquire=False,
                                         noise=base.measurement_noise)
        self.gate = dropout_gate(base.system.constants, self.supervisor)
        return self.observation(obs), info

    def step(self, action):
        base = self.env.unwrapped
        a = min(max(float(np.asarray(action, dtype=float).reshape(-1)[0]), -1.0), 1.0)
        hull = base.vehicle.los.acceleration if base.cfg.imu else 0.0
        self.supervisor.predict(self.motor.acceleration(a * base.torque_limit) + hull)
        return super().step(action)

    def observation(self, obs):
        base = self.env.unwrapped
        r = base.reading
        self.decision = self.supervisor.step(base.k * base.dt, self.gate(obs[:2]),
                                             r.gimbal_angle, r.gimbal_rate)
        parts = [obs, np.clip(self.decision.xhat, -ESTIMATE_BOUND, ESTIMATE_BOUND)]
        if self.lost_flag:
            parts.append([float(self.decision.lost)])
        return np.concatenate(parts)
