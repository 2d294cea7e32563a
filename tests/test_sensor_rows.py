"""The sensors of many worlds read in one pass (SensorRows) give each world the bits of
its own sensor's reading: through occlusion (rays cast only where a geom can shadow),
a physical link's elevation, light and signal noise, worlds with models of their own,
and the vector env's autoresets; the row kernels give each element one world's float."""

from __future__ import annotations

import copy
import math
import warnings

import gymnasium as gym
import numpy as np
import pytest

import ledsim.envs  # noqa: F401 (registers the ids)
import ledsim.physics.sensor_rows as sensor_rows
from ledsim.loop.closed_loop import ClosedLoop
from ledsim.loop.run_config import RunConfig
from ledsim.physics.incidence import incidence_geometry, incidence_rate
from ledsim.physics.sensor_rows import SensorRows
from ledsim.physics.tick import prepare
from ledsim.radiometry.optics import receiver_response_at, transmitter_gain_at
from observer.rowops import ARRAYS, FLOATS

warnings.filterwarnings("ignore", message=".*out of date.*")
FIELDS = ("power", "power_clean", "incidence_angle", "emission_angle", "distance",
          "visible_fraction", "phi", "phidot", "gimbal_angle", "gimbal_rate", "hull_pos")


def _same(a, b) -> bool:
    return all(np.asarray(getattr(a, f)).tobytes() == np.asarray(getattr(b, f)).tobytes()
               for f in FIELDS)


@pytest.mark.parametrize("kw,rays", [
    (dict(), False),
    (dict(disturbances=("occlusion:start=0.1,duration=0.5",)), True),
    (dict(link="luma", water="coastal", distance=11,
          disturbances=("flicker", "current:speed=0.15,heading=2.4")), False),
], ids=["clear", "occlusion", "luma-flicker-current"])
def test_rows_give_each_world_its_own_sensors_reading(kw, rays, monkeypatch):
    cast = []
    needs = sensor_rows.needs_rays
    monkeypatch.setattr(sensor_rows, "needs_rays",
                        lambda *a: cast.append(needs(*a).any()) or needs(*a))
    loop = ClosedLoop(RunConfig(scenario="align", seconds=1, **kw), range(5))
    rows = SensorRows([r.sensor for r in loop.runs])
    for k in range(80):
        rngs = [copy.deepcopy(r.sensor.rng.bit_generator.state) for r in loop.runs]
        together = rows.read()
        for r, state in zip(loop.runs, rngs, strict=True):
            r.sensor.rng.bit_generator.state = state
        for i, (r, got) in enumerate(zip(loop.runs, together, strict=True)):
            assert _same(got, r.sensor.read()), f"world {i}, step {k}"
        for i, r in enumerate(loop.runs):  # on to the next step, each world its own way
            r.world.set_torque(0.002 * math.sin(0.05 * k + i))
            r.world.step()
            prepare(r.world, r.disturbances, (k + 1) * loop.Te)
    assert any(cast) == rays


def test_row_kernels_give_each_element_one_worlds_floats():
    rng = np.random.default_rng(3)
    n = 2000
    vec = [rng.normal(size=(3, n)) for _ in range(5)]
    unit = [v / np.sqrt((v * v).sum(axis=0)) for v in vec[1:]]
    led, axis, hinge, pd, normal = vec[0], unit[0], unit[1], vec[1], unit[2]
    rows = incidence_geometry(ARRAYS, led, axis, hinge, pd, normal)
    rate_args = (vec[2], rng.normal(size=(6, n)), vec[3], hinge)
    rate = incidence_rate(*rate_args)
    c = RunConfig(link="luma", distance=5).world_config().constants
    d, theta = rng.uniform(0.05, 30, n), rng.uniform(0, 2.0, n)
    phi = rng.uniform(-1.5, 1.5, n)
    gain = transmitter_gain_at(d, theta, c, ARRAYS)
    response = receiver_response_at(phi, c.receiver, ARRAYS)
    for j in range(n):
        one = incidence_geometry(FLOATS, *([float(x) for x in v[:, j]]
                                           for v in (led, axis, hinge, pd, normal)))
        assert tuple(float(q[j]) for q in rows) == one
        assert float(rate[j]) == incidence_rate(*([float(x) for x in v[:, j]]
                                                  for v in rate_args))
        assert float(gain[j]) == transmitter_gain_at(float(d[j]), float(theta[j]), c)
        assert float(response[j]) == receiver_response_at(float(phi[j]), c.receiver)


@pytest.mark.parametrize("mode", ["next-step", "same-step"])
def test_vector_env_reads_each_world_as_alone_across_autoresets(mode, monkeypatch):
    def run():
        venv = gym.make_vec("ledsim/LinkAlign-v0", num_envs=3, max_episode_steps=4,
                            autoreset_mode=mode, disturbances=("current:speed=0.05",))
        obs, _ = venv.reset(seed=5)
        seen = [obs]
        actions = np.random.default_rng(1).uniform(-1, 1, (11, 3, 1)).astype(np.float32)
        for a in actions:
            obs, reward, *_ = venv.step(a)
            seen += [obs, reward[:, None]]
        venv.close()
        return np.concatenate(seen, axis=1)

    together = run()
    # No reading in one pass: each sub-env reads its own sensor, as one env does.
    monkeypatch.setattr(SensorRows, "read", lambda self: [None] * len(self.sensors))
    np.testing.assert_array_equal(together, run())
