"""A second gimbal axis as data: a pan-tilt layout with four photodiodes is built by the
run's world builder and its two motors each turn their own hinge (issue 47: the plumbing
is ready for the two-axis issue, which adds the estimators and control laws)."""

from dataclasses import replace

import numpy as np
import pytest

from ledsim.constants import LinkConstants
from ledsim.loop.build.worlds import build_worlds
from ledsim.physics import head
from ledsim.physics.layout import AZIMUTH, GimbalAxis, LayoutError, Photodiode, ReceiverLayout
from ledsim.physics.scene import WorldConfig, WorldError
from ledsim.physics.sensor import IrradianceSensor

D = 0.1  # the quad's offsets [rad]
TILT = GimbalAxis("elevation", "tilt_hinge", "tilt_motor", "tilt_encoder", angle="theta",
                  rate="thetadot", direction=(0.0, 1.0, 0.0))
QUAD = ReceiverLayout((Photodiode("pq1", "q1", D), Photodiode("pq2", "q2", -D),
                       Photodiode("pq3", "q3", 0.0, D), Photodiode("pq4", "q4", 0.0, -D)),
                      (AZIMUTH, TILT))
TORQUES = np.array([2e-5, -1e-5])  # N m: pan one way, tilt the other


def pan_tilt_world():
    constants = replace(LinkConstants(), receiver_layout=QUAD)
    (world,) = build_worlds(WorldConfig(constants=constants), 1)
    return world


def turn_for_a_second(world) -> np.ndarray:
    """Each axis's angle [rad] after 1 s of a constant torque on each motor."""
    world.reset(gimbal_angle=np.zeros(2), gimbal_rate=np.zeros(2))
    for _ in range(int(round(1.0 / world.config.constants.Te))):
        world.set_torques(TORQUES)
        world.step()
    return world.gimbal_angles


def each_motor_turns_its_own_axis(angles: np.ndarray) -> bool:
    """Both axes turned, each the way of its own motor's torque, by more than 0.02 rad."""
    return bool(np.all(np.sign(angles) == np.sign(TORQUES)) and np.all(np.abs(angles) > 0.02))


def test_a_pan_tilt_head_with_four_photodiodes_is_built_and_turns_on_both_axes():
    world = pan_tilt_world()
    assert world.n_axes == 2 and len(world.ids.photodiode_sites) == 4
    angles = turn_for_a_second(world)
    assert each_motor_turns_its_own_axis(angles), angles
    np.testing.assert_allclose(world.encoder_readings(), angles, atol=1e-12)
    np.testing.assert_array_equal(world.torques, TORQUES)
    # at rest the quad's tilts turn two photodiodes out of the pan plane, up and down
    world.reset(gimbal_angle=np.zeros(2), gimbal_rate=np.zeros(2))
    normals = np.array([world.photodiode_normal(i) for i in range(4)])
    np.testing.assert_allclose(normals[2:, 2], [-np.sin(D), np.sin(D)], atol=1e-12)


def test_the_check_fails_when_an_axis_is_wired_to_the_wrong_hinge(monkeypatch):
    """Break the wiring (the tilt motor drives the pan hinge): the same check fails."""
    built = head.add_motor
    monkeypatch.setattr(head, "add_motor",
                        lambda spec, name, joint: built(spec, name, AZIMUTH.joint))
    angles = turn_for_a_second(pan_tilt_world())
    assert not each_motor_turns_its_own_axis(angles)
    assert abs(angles[1]) < 1e-3  # only the pan's motion stirs the tilt hinge


def test_the_quad_reads_four_powers_that_differ_by_their_tilt():
    world = pan_tilt_world()
    world.reset(gimbal_angle=np.array([0.0, 0.05]), gimbal_rate=np.zeros(2))
    reading = IrradianceSensor(world, noise=False).read()
    p = np.asarray(reading.power_clean)
    assert p.shape == (4,) and np.all(p > 0)
    assert p[2] != p[3]  # tilted 0.05 rad: the up- and down-looking ones see it differently


def test_runs_still_refuse_two_axes_and_the_scene_refuses_three():
    from ledsim.physics.gimbal_system import GimbalSystem

    with pytest.raises(LayoutError, match="2 gimbal axes are not supported yet"):
        GimbalSystem(WorldConfig(constants=replace(LinkConstants(), receiver_layout=QUAD)))
    third = replace(TILT, name="roll", joint="roll_hinge", motor="roll_motor",
                    encoder="roll_encoder", direction=(1.0, 0.0, 0.0))
    three = replace(QUAD, axes=(AZIMUTH, TILT, third))
    with pytest.raises(LayoutError, match="3 gimbal axes cannot be built"):
        build_worlds(WorldConfig(constants=replace(LinkConstants(), receiver_layout=three)), 1)


def test_a_built_axis_names_sites_of_its_own():
    taken = replace(QUAD, photodiodes=(Photodiode("pd1", "p1", 0.0),
                                       *QUAD.photodiodes[1:]))
    with pytest.raises(WorldError, match="'pd1' is on the scene's pan axis"):
        build_worlds(WorldConfig(constants=replace(LinkConstants(), receiver_layout=taken)), 1)


def test_torques_are_one_per_axis_and_clipped():
    world = pan_tilt_world()
    with pytest.raises(ValueError, match=r"one per axis, shape \(2,\)"):
        world.set_torques([0.01])
    np.testing.assert_array_equal(world.set_torques([1.0, -1.0]), [0.05, -0.05])


def test_the_layout_travels_in_the_constants_metadata():
    c = replace(LinkConstants(), receiver_layout=QUAD)
    back = LinkConstants.from_dict(c.to_dict())
    assert back == c and back.layout == QUAD
    assert "receiver_layout" not in LinkConstants().to_dict()  # the paper's keys kept
