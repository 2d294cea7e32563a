"""The step's plain-float shortcuts give numpy's bits: a pan-tilt axis's ratios, the
largest angle over the axes, the thrusters' clip and the load observer's rate step,
on values that include zeros, NaN, infinities and values past the limits."""

from __future__ import annotations

import numpy as np
import pytest

from ledsim.agent.axes import magnitude
from ledsim.loop.closed_loop import ClosedLoop
from ledsim.loop.run_config import RunConfig
from observer.supervision.gimbal_load import LoadObserver
from tests.test_compiled_kkl import _axis_observer

SPECIALS = (0.0, -0.0, np.nan, np.inf, -np.inf, 5e-324, 1e308)


def test_an_axis_splits_the_powers_as_numpy_does():
    axis = _axis_observer().system
    gains = axis.head.channel_gains
    before = gains.copy()
    rng = np.random.default_rng(0)
    try:
        gains[:] = rng.uniform(0.8, 1.2, gains.size)  # a calibrated head
        for k in range(4000):
            y = rng.lognormal(size=gains.size) * 10.0 ** rng.uniform(-300, 0)
            if k % 10 == 0:
                y[rng.integers(gains.size)] = rng.choice(SPECIALS)
            with np.errstate(all="ignore"):
                g = y / gains
                ref = g[list(axis.pair)] / g[axis.reference]
                got = axis.split(y)
            assert got.tobytes() == ref.tobytes(), (y, got, ref)
        gains[axis.reference] = 0.0  # a dead channel: numpy's inf and NaN
        with np.errstate(all="ignore"):
            g = np.ones(gains.size) / gains
            assert axis.split(np.ones(gains.size)).tobytes() == \
                (g[list(axis.pair)] / g[axis.reference]).tobytes()
    finally:
        gains[:] = before


def test_magnitude_is_numpys_largest_absolute_value():
    rng = np.random.default_rng(1)
    for _ in range(2000):
        x = rng.normal(size=rng.integers(1, 4)) * 10.0 ** rng.uniform(-5, 5)
        if rng.random() < 0.3:
            x[rng.integers(x.size)] = rng.choice(SPECIALS)
        ref = float(np.max(np.abs(x)))
        got = magnitude(x)
        assert np.array_equal(got, ref, equal_nan=True), (x, got, ref)
    assert magnitude(-0.25) == 0.25


def test_the_thrusters_clip_as_numpy_does():
    world = ClosedLoop(RunConfig(scenario="align", seconds=0.1), range(1)).runs[0].world
    _, lo, hi = world._thruster_range()
    rng = np.random.default_rng(2)
    for _ in range(500):
        command = rng.normal(size=5) * 3 * np.abs(hi)
        command[rng.integers(5)] = rng.choice(SPECIALS)
        ref = np.clip(command, lo, hi)
        got = world.set_thrust(command)
        assert got.tobytes() == ref.tobytes()
        assert world.thrust.tobytes() == ref.tobytes()


def test_the_thrusters_of_many_worlds_are_each_worlds_own():
    from ledsim.physics.hull import set_thrust_rows

    worlds = [run.world for run in
              ClosedLoop(RunConfig(scenario="align", seconds=0.1), range(3)).runs]
    _, lo, hi = worlds[0]._thruster_range()
    rng = np.random.default_rng(4)
    for _ in range(200):
        command = rng.normal(size=(3, 5)) * 3 * np.abs(hi)
        command[rng.integers(3), rng.integers(5)] = rng.choice(SPECIALS)
        got = set_thrust_rows(worlds, command)
        for w, row, applied in zip(worlds, command, got, strict=True):
            ref = np.clip(row, lo, hi)
            assert applied.tobytes() == ref.tobytes()
            assert w.thrust.tobytes() == ref.tobytes()


@pytest.mark.parametrize("kind", ["identified", "axis"])
def test_the_load_observers_rate_step_is_the_models(kind):
    if kind == "axis":
        model = _axis_observer().system
    else:
        from ledsim.loop.build.estimation import identified_model
        from ledsim.physics.gimbal_system import GimbalSystem
        from ledsim.physics.scene import WorldConfig

        model = identified_model(GimbalSystem(WorldConfig()))
    obs = LoadObserver(model)
    rng = np.random.default_rng(3)
    for _ in range(2000):
        rate, u = rng.normal(scale=5.0), rng.normal(scale=50.0)
        ref = float(model.f(np.array([0.0, rate]), u)[1])
        assert obs._rate_step(rate, u) == ref


def test_the_heads_motors_clip_as_numpy_does():
    loop = ClosedLoop(RunConfig(scenario="align", seconds=0.1, link="luma"), range(1))
    world = loop.runs[0].world
    lim = world.config.torque_limit
    rng = np.random.default_rng(4)
    for _ in range(500):
        torques = rng.normal(size=world.n_axes) * 2 * lim
        torques[rng.integers(world.n_axes)] = rng.choice(SPECIALS)
        ref = np.clip(torques, -lim, lim)
        assert world.set_torques(torques).tobytes() == ref.tobytes()
        assert world.torques.tobytes() == ref.tobytes()
