"""Axes as arrays through the agent (issue 47): the control law, the motor, the slew and
the control step take a value per gimbal axis, a float for the paper's one axis; a
pan-tilt head is driven to a pointing on both axes through the one tick of the worlds.
"""

import math

import numpy as np
import pytest

from ledsim.agent.axes import angles_rates, as_axes, clip, magnitude
from ledsim.agent.laws import AlignmentPID, PaperRateDamping
from ledsim.agent.slew import TimeOptimalSlew
from ledsim.agent.step import ControlStep, GimbalMotor, Unsupervised, identity_gate
from ledsim.constants import LinkConstants
from ledsim.physics import head
from ledsim.physics.layout import AZIMUTH
from ledsim.physics.world_rows import WorldRows
from tests.test_two_axes import pan_tilt_world

GOAL = np.array([0.15, -0.08])  # encoder angles the test points the head at [rad]


def test_the_helpers_keep_a_float_a_float_and_check_lengths():
    assert clip(2.5, -1.0, 1.0) == 1.0 and isinstance(clip(0.5, -1.0, 1.0), float)
    np.testing.assert_array_equal(clip(np.array([2.0, -3.0, 0.5]), -1, 1), [1, -1, 0.5])
    assert angles_rates(np.array([0.1, 0.2])) == (0.1, 0.2)
    a, r = angles_rates(np.array([1.0, 2.0, 3.0, 4.0]))
    np.testing.assert_array_equal(a, [1, 2]) and np.testing.assert_array_equal(r, [3, 4])
    assert magnitude(np.array([0.1, -0.3])) == pytest.approx(0.3) and magnitude(-2.0) == 2
    assert as_axes(0.5, 1) == 0.5 and as_axes([0.5], 1) == 0.5
    np.testing.assert_array_equal(as_axes(0.5, 2), [0.5, 0.5])
    with pytest.raises(ValueError, match="shape \\(3,\\) for a gimbal of 2 axes"):
        as_axes([1.0, 2.0, 3.0], 2)
    with pytest.raises(ValueError, match="2 values for a gimbal of one axis"):
        as_axes([1.0, 2.0], 1)


def _states(rng, steps=200):
    """Random (phi, phidot) sequences for two axes, with some far outside the domain."""
    return rng.normal(0.0, [0.4, 0.6], size=(steps, 2, 2))  # (step, axis, (phi, rate))


def test_a_law_over_two_axes_is_each_axis_own_law_to_the_last_bit():
    """Each axis of a two-axis law runs the one-axis law's arithmetic: the same numbers
    as two one-axis laws, integral included, fed the axes' estimates one by one."""
    c = LinkConstants()
    for template in (AlignmentPID(), PaperRateDamping()):
        both = template.start(c)
        single = [template.start(c), template.start(c)]
        for k, s in enumerate(_states(np.random.default_rng(3))):
            u = both(np.r_[s[:, 0], s[:, 1]], k * c.Te)
            assert isinstance(u, np.ndarray) and u.shape == (2,)
            for axis in range(2):
                assert u[axis] == single[axis](s[axis], k * c.Te)


def test_the_motor_and_the_slew_act_per_axis():
    inertia = np.array([2.0e-4, 3.0e-4])
    both = GimbalMotor(inertia, limit=0.05)
    one = [GimbalMotor(float(i), limit=0.05) for i in inertia]
    slew = TimeOptimalSlew(inertia, 0.05, 0.01)
    slews = [TimeOptimalSlew(float(i), 0.05, 0.01) for i in inertia]
    rng = np.random.default_rng(4)
    for u, q, qdot, target in rng.normal(0, [300.0, 0.3, 1.0, 0.3], size=(100, 2, 4)) \
            .transpose(0, 2, 1):
        per_axis = range(2)
        np.testing.assert_array_equal(both.torque(u), [one[i].torque(u[i]) for i in per_axis])
        np.testing.assert_array_equal(both.applied(u),
                                      [one[i].applied(u[i]) for i in per_axis])
        np.testing.assert_array_equal(slew.command(q, qdot, target),
                                      [slews[i].command(q[i], qdot[i], target[i])
                                       for i in per_axis])
    assert both.n_axes == 2 and one[0].n_axes == 1


class EncoderEstimator:
    """A test's stand-in for the two-axis estimators of the next issue: it reads each
    axis's encoder, phi = goal - q (so the law's target phi = 0 points at ``GOAL``),
    phidot = -qdot. The test is of the plumbing from the world to the motor."""

    outside_domain = False

    def __init__(self, world):
        self.world = world

    def update(self, y):
        q = self.world.encoder_readings()
        return np.r_[GOAL - q, -self.world.gimbal_rates]

    def predict(self, u):
        pass


def point_pan_tilt(world, seconds: float = 4.0) -> np.ndarray:
    """Run the control step on both axes of a pan-tilt world; the encoder angles [rad]
    at the end."""
    world.reset(gimbal_angle=np.zeros(2), gimbal_rate=np.zeros(2))
    inertia = np.array([world.hinge_inertia(axis) for axis in range(2)])
    c = world.config.constants
    limit = world.config.torque_limit
    step = ControlStep(identity_gate, Unsupervised(EncoderEstimator(world)),
                       AlignmentPID(phi_ref=0.0), c, GimbalMotor(inertia, limit=limit))
    with WorldRows([world]) as rows:
        rows.start(None, [[]], [None])
        for k in range(int(round(seconds / c.Te))):
            torque = step(np.zeros(4), k * c.Te, world.gimbal_angles, world.gimbal_rates)
            assert isinstance(torque, np.ndarray) and torque.shape == (2,)
            (applied,) = rows.tick((k + 1) * c.Te, torques=[torque])
            assert np.all(np.abs(applied) <= limit)
    assert step.u.shape == (2,)
    return world.encoder_readings()


def test_the_control_step_points_a_pan_tilt_head_on_both_axes():
    q = point_pan_tilt(pan_tilt_world())
    np.testing.assert_allclose(q, GOAL, atol=2e-4)


def test_the_pointing_fails_when_the_tilt_motor_drives_the_pan_hinge(monkeypatch):
    built = head.add_motor
    monkeypatch.setattr(head, "add_motor",
                        lambda spec, name, joint: built(spec, name, AZIMUTH.joint))
    q = point_pan_tilt(pan_tilt_world())
    assert not np.allclose(q, GOAL, atol=2e-4)
    assert abs(q[1] - GOAL[1]) > 0.05  # the tilt never got there


def test_a_one_axis_step_keeps_floats_and_refuses_los_with_several_axes():
    c = LinkConstants()
    motor = GimbalMotor(2.0e-4, limit=0.05)

    class Fixed:
        outside_domain = False

        def update(self, y):
            return np.array([0.1, 0.0])

        def predict(self, u):
            pass

    step = ControlStep(identity_gate, Unsupervised(Fixed()), AlignmentPID(), c, motor)
    torque = step(np.zeros(2), 0.0, 0.0, 0.0)
    assert isinstance(torque, float) and math.isfinite(torque)
    with pytest.raises(ValueError, match="line of sight turns one axis"):
        step(np.zeros(2), 0.01, np.zeros(2), np.zeros(2), los=object())


def test_the_env_has_one_duty_per_axis():
    from ledsim.envs import LinkAlignEnv

    env = LinkAlignEnv("align")
    try:
        assert env.action_space.shape == (env.world.n_axes,) == (1,)
        env.reset(seed=0)
        with pytest.raises(ValueError, match="one finite number"):
            env.step(np.array([0.1, 0.2]))
    finally:
        env.close()
