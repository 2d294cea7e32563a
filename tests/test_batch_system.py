"""GimbalSystem's batched f and h (rollout + WorldBatch) are its one-at-a-time f and h."""

from __future__ import annotations

import numpy as np
import pytest

from ledsim.physics.gimbal_system import GimbalSystem
from ledsim.physics.world import WorldError


@pytest.fixture(scope="module")
def system():
    s = GimbalSystem(threads=2)
    yield s
    s.close()


def test_batched_transitions_are_the_single_ones(system):
    rng = np.random.default_rng(3)
    n = 150  # three blocks of the world batch, the last padded
    assert n >= system.BATCH_MIN
    x = system.sample_domain(rng, n)
    u = rng.uniform(-60, 60, n)  # some torques beyond the limit: clipped the same way
    batched = system.f(x, u)
    one = np.array([system.f(xk, uk) for xk, uk in zip(x, u, strict=True)])
    np.testing.assert_allclose(batched, one, rtol=0, atol=1e-12)
    assert np.abs(batched - x).max() > 1e-4  # the transitions do move the state


def test_batched_outputs_are_the_single_ones(system):
    rng = np.random.default_rng(4)
    x = system.sample_domain(rng, 40)
    batched = system.h(x)
    one = np.array([system.h(xk) for xk in x])
    np.testing.assert_allclose(batched, one, rtol=1e-12, atol=0)
    assert batched.shape == (40, 2) and np.ptp(batched[:, 0]) > 0.1


def test_batched_shapes_follow_the_input(system):
    x = np.zeros((4, 10, 2))
    assert system.f(x, np.zeros((4, 10))).shape == (4, 10, 2)
    assert system.h(x).shape == (4, 10, 2)


def test_unstable_transition_is_a_world_error(system):
    x = np.zeros((system.BATCH_MIN, 2))
    x[5, 1] = 1e30
    with pytest.raises(WorldError, match="unstable"):
        system.f(x, 0.0)


def test_threads_must_be_positive():
    with pytest.raises(ValueError, match="threads=0"):
        GimbalSystem(threads=0)
