"""``gym.make_vec("ledsim/LinkAlign-v0", num_envs=N)``: N worlds stepped in one call.

:class:`LinkAlignVectorEnv` is the native vector environment of both LinkAlign ids
(their ``vector_entry_point``). Each of its N sub-environments is a
:class:`~ledsim.envs.link_align.LinkAlignEnv`, and one ``step`` runs the tick of
:mod:`ledsim.physics.tick` over all of them: every torque commanded, the physics of all
N worlds in one pass (:class:`~ledsim.physics.tick.PhysicsPass`, split over ``threads``,
MuJoCo stepping without the GIL), every world prepared, observed and rewarded, with no
wrapper per sub-environment. Sub-environment i of ``reset(seed=S)`` is the single
environment of ``reset(seed=S + i)``, step for step, bit for bit, whatever N.

**Autoreset** (``metadata["autoreset_mode"]``): ``next-step`` by default, Gymnasium's
own: the step after a sub-environment's episode ended resets it (its action is ignored,
its reward is 0, and it is neither terminated nor truncated). ``same-step`` resets it in
the step that ends the episode: the observation returned is the new episode's first,
and ``info["final_obs"]`` and ``info["final_info"]`` hold the last of the old one (what
stable-baselines3 expects: :class:`~ledsim.envs.sb3.VectorEnvForSB3`).

Episodes are truncated after ``max_episode_steps`` (``make_vec`` passes the id's 1000)
and never terminate. ``info`` holds each key of the single environment's ``info``
stacked over the sub-environments, with Gymnasium's ``_key`` masks.
"""

from __future__ import annotations

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from ledsim.envs.link_align import LinkAlignEnv
from ledsim.envs.observe_rows import observe_rows
from ledsim.physics.world_rows import WorldRows

#: The autoreset modes by name (the enum's values are spelt too: ``"NextStep"``).
AUTORESET_MODES = {"next-step": AutoresetMode.NEXT_STEP,
                   "same-step": AutoresetMode.SAME_STEP}


def parse_autoreset_mode(value) -> AutoresetMode:
    """``value`` as a supported :class:`AutoresetMode` (the enum, its value, or its name
    in :data:`AUTORESET_MODES`)."""
    spelt = {m.value: m for m in AUTORESET_MODES.values()}
    mode = value if value in spelt.values() else \
        AUTORESET_MODES.get(value) or spelt.get(value)
    if mode is None:
        raise ValueError(f"autoreset_mode {value!r} is not allowed: use one of "
                         f"{sorted(AUTORESET_MODES)}")
    return mode


class LinkAlignVectorEnv(VectorEnv):
    """N :class:`~ledsim.envs.link_align.LinkAlignEnv` worlds stepped together (see the
    module docstring).

    Args:
        num_envs: N, the sub-environments.
        max_episode_steps: truncate each episode after this many steps (None: never).
        autoreset_mode: ``"next-step"`` (default) or ``"same-step"``.
        threads: threads stepping the physics (1: the calling thread).
        **kwargs: :class:`~ledsim.envs.link_align.LinkAlignEnv`'s arguments, the same for
            every sub-environment (``render_mode`` must stay None).
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(self, num_envs: int = 1, max_episode_steps: int | None = None,
                 autoreset_mode: str | AutoresetMode = AutoresetMode.NEXT_STEP,
                 threads: int = 1, **kwargs):
        if isinstance(num_envs, bool) or not isinstance(num_envs, int | np.integer) \
                or num_envs < 1:
            raise ValueError(f"num_envs {num_envs!r} is not allowed: an integer >= 1")
        if max_episode_steps is not None and int(max_episode_steps) < 1:
            raise ValueError(f"max_episode_steps {max_episode_steps!r} is not allowed: "
                             "an integer >= 1, or None")
        if kwargs.get("render_mode") is not None:
            raise ValueError(f"render_mode {kwargs['render_mode']!r} is not allowed in the "
                             "vector env: render one LinkAlignEnv instead")
        self.mode = parse_autoreset_mode(autoreset_mode)
        self.metadata = {**self.metadata, "autoreset_mode": self.mode}
        self.num_envs = int(num_envs)
        self.envs = [LinkAlignEnv(**kwargs) for _ in range(self.num_envs)]
        self.max_episode_steps = None if max_episode_steps is None else int(max_episode_steps)
        e0 = self.envs[0]
        self.single_observation_space = e0.observation_space
        self.single_action_space = e0.action_space
        self.observation_space = batch_space(e0.observation_space, self.num_envs)
        self.action_space = batch_space(e0.action_space, self.num_envs)
        self.render_mode = None
        self._rows = WorldRows([e.world for e in self.envs], threads)
        self._elapsed = np.zeros(self.num_envs, dtype=np.int64)
        self._ended = np.zeros(self.num_envs, dtype=bool)  # next-step: reset at this step

    def reset(self, *, seed: int | list | None = None, options: dict | None = None):
        """Reset every sub-environment: ``seed`` S gives sub-environment i the seed
        S + i (or one seed each, as a list); ``options`` as
        :meth:`LinkAlignEnv.reset`, for all of them."""
        super().reset(seed=seed)
        if seed is None or isinstance(seed, int | np.integer):
            seeds = [None if seed is None else int(seed) + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"seed {seed!r} is not allowed: one per sub-environment "
                                 f"({self.num_envs}), or one integer")
        firsts = [e.reset(seed=s, options=options) for e, s in zip(self.envs, seeds,
                                                                    strict=True)]
        self._elapsed[:] = 0
        self._ended[:] = False
        # The sub-environments as rows that tick together: sensors read in one pass,
        # vehicles (each started as its own) stepped as one; each reads its row.
        vehicles = self._rows.start([e.sensor for e in self.envs],
                                    [e.disturbances for e in self.envs],
                                    [e.vehicle for e in self.envs])
        for e, vehicle in zip(self.envs, vehicles, strict=True):
            e.vehicle = vehicle
        return self._stack_obs([o for o, _ in firsts]), self._stack_info([i for _, i in firsts])

    def _reset_one(self, i: int):
        """Sub-environment ``i`` anew (its next episode), its vehicle back in its row."""
        e = self.envs[i]
        first = e.reset()
        self._elapsed[i] = 0
        vehicle = self._rows.put(i, e.sensor, e.disturbances, e.vehicle)
        if vehicle is not None:
            e.vehicle = vehicle
        return first

    def step(self, actions):
        """One control step of every sub-environment: ``actions`` (N, n_axes), each the
        single env's action (n_axes = 1 for the paper's gimbal). Returns the batched
        (obs, reward, terminated, truncated, info) of Gymnasium's vector API, with the
        autoreset of the module docstring."""
        actions = np.asarray(actions)
        if actions.shape[:1] != (self.num_envs,):
            raise ValueError(f"actions of shape {actions.shape} are not allowed: one row "
                             f"per sub-environment, ({self.num_envs}, "
                             f"{self.single_action_space.shape[0]})")
        envs, n = self.envs, self.num_envs
        stepping = ~self._ended if self.mode == AutoresetMode.NEXT_STEP else \
            np.ones(n, dtype=bool)
        duties = self._duties(actions)
        if duties is None:  # a bad action is refused before any env is commanded
            for i in np.flatnonzero(stepping).tolist():
                envs[i].check_action(actions[i])
        for i in np.flatnonzero(stepping).tolist():
            if duties is None:
                envs[i].command(actions[i])
            else:
                envs[i].command_duty(duties[i])
        # Every vehicle row steps (a resetting one is put back below).
        self._rows.tick(np.array([e.k * e.dt for e in envs]), stepping)
        obs, infos = [None] * n, [None] * n
        reward = np.zeros(n)
        truncated = np.zeros(n, dtype=bool)
        # Every world's sensor in one pass (a world about to reset reads its old sensor,
        # which the reset replaces with a fresh one).
        readings = self._rows.read()
        terminated = np.zeros(n, dtype=bool)
        if stepping.all():  # every row observed and rewarded at once
            return self._observed(readings, terminated)
        for i in range(n):
            if stepping[i]:
                obs[i], reward[i], _, _, infos[i] = envs[i].observe_step(readings[i])
                self._elapsed[i] += 1
                truncated[i] = self.max_episode_steps is not None and \
                    self._elapsed[i] >= self.max_episode_steps
            else:  # next-step autoreset of an episode that ended last step
                obs[i], infos[i] = self._reset_one(i)
        if self.mode == AutoresetMode.NEXT_STEP:
            self._ended = truncated.copy()
            return self._stack_obs(obs), reward, terminated, truncated, self._stack_info(infos)
        return self._same_step_resets(obs, reward, terminated, truncated, infos)

    def _duties(self, actions: np.ndarray) -> list[float] | None:
        """Every row's duty of a one-axis env's ``actions`` (N, 1) when all are finite
        (checked at once; None: let each env check its own and name the bad one)."""
        if self.single_action_space.shape != (1,) or actions.shape != (self.num_envs, 1):
            return None
        duties = actions.astype(float, copy=False).reshape(-1)
        return duties.tolist() if np.isfinite(duties).all() else None

    def _observed(self, readings, terminated):
        """:meth:`step`'s return when every row stepped (no next-step reset due): the
        rows observed and rewarded together (:func:`~ledsim.envs.observe_rows.observe_rows`)."""
        obs, reward, info = observe_rows(self.envs, readings, self._rows.vehicles)
        self._elapsed += 1
        truncated = np.zeros(self.num_envs, dtype=bool) if self.max_episode_steps is None \
            else self._elapsed >= self.max_episode_steps
        if self.mode == AutoresetMode.NEXT_STEP:
            self._ended = truncated.copy()
        if self.mode == AutoresetMode.NEXT_STEP or not truncated.any():
            stacked = {}  # each key then its mask, in _stack_info's (Gymnasium's) order
            for key, value in info.items():
                stacked[key], stacked[f"_{key}"] = value, np.ones(self.num_envs, dtype=bool)
            return obs, reward, terminated, truncated, stacked
        rows = [{k: v[i].copy() if v.ndim > 1 else v[i].item() for k, v in info.items()}
                for i in range(self.num_envs)]
        return self._same_step_resets(list(obs), reward, terminated, truncated, rows)

    def _same_step_resets(self, obs, reward, terminated, truncated, infos):
        """:meth:`step`'s return in same-step mode: each truncated row reset now, its
        last observation and info in ``final_obs`` and ``final_info``."""
        n = self.num_envs
        final = np.flatnonzero(truncated)
        info = {}
        if final.size:  # same-step: the new episode's first observation, the old's last
            final_obs = np.empty(n, dtype=object)
            final_info = np.empty(n, dtype=object)
            for i in final:
                final_obs[i], final_info[i] = obs[i], infos[i]
                obs[i], infos[i] = self._reset_one(i)
            info = {"final_obs": final_obs, "_final_obs": truncated.copy(),
                    "final_info": final_info, "_final_info": truncated.copy()}
        return (self._stack_obs(obs), reward, terminated, truncated,
                {**self._stack_info(infos), **info})

    def _stack_obs(self, obs: list) -> np.ndarray:
        return np.stack(obs)

    def _stack_info(self, infos: list[dict]) -> dict:
        out = {}
        for key in infos[0]:
            out[key] = np.stack([np.asarray(i[key]) for i in infos])
            out[f"_{key}"] = np.ones(self.num_envs, dtype=bool)
        return out

    def close_extras(self, **kwargs) -> None:
        self._rows.close()
        for e in self.envs:
            e.close()
