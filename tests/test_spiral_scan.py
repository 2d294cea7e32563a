"""Finding the beam from outside the field of view in two dimensions (issue 48): a
spiral scan of the pan-tilt head until the data detector sees the beam, then the EKF in
four states takes over and points; acquired from (1.0, 0.5) rad off and elsewhere."""

import numpy as np
import pytest

from ledsim.agent.laws import AlignmentPID
from ledsim.agent.spiral import SpiralScan
from ledsim.agent.step import ControlStep, GimbalMotor, Unsupervised, identity_gate
from ledsim.physics.head_model import HeadModel
from ledsim.physics.sensor import IrradianceSensor
from ledsim.physics.world_rows import WorldRows
from observer.baselines.ekf import ExtendedKalmanFilter
from tests.test_two_axis_tracking import quad_world, truth

#: The data detector's share of its best at which the beam counts as seen [-].
SEEN = 0.2


@pytest.fixture(scope="module")
def model():
    return HeadModel.fit(quad_world())


def acquire(model, start, seed: int = 0, seconds: float = 10.0):
    """(time the spiral saw the beam, time the head first pointed within 0.01 rad) [s]
    from encoder angles ``start``, the beam outside the field of view (None: never)."""
    world = quad_world()
    world.reset(gimbal_angle=np.array(start), gimbal_rate=np.zeros(2))
    sensor = IrradianceSensor(world, seed=seed)
    c = world.config.constants
    motor = GimbalMotor(model.inertia, limit=world.config.torque_limit)
    spiral = SpiralScan(c.Te)
    spiral.start(world.gimbal_angles)
    step, seen, pointed = None, None, None
    with WorldRows([world]) as rows:
        rows.start([sensor], [[]], [None])
        for k in range(int(round(seconds / c.Te))):
            t, r = k * c.Te, sensor.read()
            q, qdot = world.gimbal_angles, world.gimbal_rates
            if step is None and r.power[0] > SEEN * model.power_gain:
                seen = t
                spiral.stop()
                step = ControlStep(identity_gate, Unsupervised(ExtendedKalmanFilter(model)),
                                   AlignmentPID(phi_ref=0.0), c, motor)
            torque = motor.torque(spiral.command(q, qdot)) if step is None else \
                step(r.power, t, q, qdot)
            rows.tick(t + c.Te, torques=[torque])
            if step is not None and np.all(np.abs(truth(sensor)) < 0.01):
                pointed = t + c.Te
                break
    return seen, pointed


def test_the_spiral_covers_the_sky_at_its_speed_and_pitch():
    spiral = SpiralScan(0.01, pitch=0.3, speed=1.0)
    spiral.start([0.2, -0.1])
    points = []
    for _ in range(1000):  # 10 s
        points.append(spiral.reference()[0])
        spiral.command(points[-1], np.zeros(2))
    points = np.array(points)
    steps = np.linalg.norm(np.diff(points, axis=0), axis=1)
    np.testing.assert_allclose(steps[100:], 0.01, rtol=0.02)  # 1 rad/s along the path
    radius = np.linalg.norm(points - [0.2, -0.1], axis=1)
    # 10 rad of path at 0.3 rad a turn covers pi r^2 = 10 x 0.3: r = 0.98
    assert radius.max() == pytest.approx(np.sqrt(10 * 0.3 / np.pi), rel=0.02)


@pytest.mark.parametrize("start", [(1.0, 0.5), (-1.2, -0.4), (0.8, -0.6)])
def test_the_beam_is_found_from_outside_the_field_of_view_and_pointed_at(model, start):
    seen, pointed = acquire(model, start)
    assert seen is not None and pointed is not None, (seen, pointed)
    assert pointed < 8.0  # 4.7, 6.1 and 2.4 s measured
