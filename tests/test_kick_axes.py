"""Kicks take an axis (issue 48): the hull struck in yaw, pitch or roll turns about that
axis of its own frame, and a roll kick, which barely moves the line of sight, raises no
false loss."""

import numpy as np
import pytest

from ledsim.loop.closed_loop import run_once
from ledsim.loop.run_config import RunConfig
from ledsim.physics.disturbances import DisturbanceError, parse_disturbance
from ledsim.physics.scene import WorldConfig
from ledsim.physics.world import LinkWorld
from ledsim.radiometry.link_presets import link_constants


@pytest.mark.parametrize("axis,column", [("roll", 0), ("pitch", 1), ("yaw", 2)])
def test_a_hull_kick_turns_the_hull_about_its_own_axis(axis, column):
    world = LinkWorld(WorldConfig(constants=link_constants("luma", 30.0)))
    kick = parse_disturbance(f"kick:start=0,rate=2,hull=1,axis={axis}")
    kick.reset(0)
    before = world.data.qvel[world._hull_dof + 3:world._hull_dof + 6].copy()
    kick.apply(world, 0.0)
    turned = world.data.qvel[world._hull_dof + 3:world._hull_dof + 6] - before
    np.testing.assert_array_equal(turned, 2.0 * np.eye(3)[column])


def test_the_axis_is_a_word_and_the_gimbal_kick_is_yaw_only():
    assert parse_disturbance("kick:hull=1").axis == "yaw"  # ledsim 0.2's kick, as it was
    with pytest.raises(DisturbanceError, match="choose one of yaw, pitch, roll"):
        parse_disturbance("kick:hull=1,axis=heave")
    with pytest.raises(DisturbanceError, match="hull=0: the gimbal's hinge turns in yaw"):
        parse_disturbance("kick:axis=roll")


def test_a_roll_kick_raises_no_false_loss():
    out = run_once(RunConfig(link="luma", estimator="kkl", seconds=6.0,
                             disturbances=("kick:start=3,rate=3,hull=1,axis=roll",)), seed=0)
    m = out.metrics
    assert m.false_loss_events == 0 and m.loss_events == 0
    assert m.availability > 0.99
