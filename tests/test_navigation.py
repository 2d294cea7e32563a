"""The vehicle's own sensors: MuJoCo's gyro, accelerometer, velocimeter, jointpos and
framepos give the truth; the noise model adds what the datasheets say."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from ledsim.constants import ConfigError, NavigationNoise
from ledsim.physics.disturbances import parse_disturbance
from ledsim.physics.nav_sensors import NavigationSensor
from ledsim.physics.scene import SCENE, WorldConfig
from ledsim.physics.tick import advance, prepare
from ledsim.physics.world import LinkWorld, WorldError


def _scene_without_sensors(tmp_path):
    spec = mujoco.MjSpec.from_file(str(SCENE))
    for s in list(spec.sensors):
        spec.delete(s)
    path = tmp_path / "no_imu.xml"
    path.write_text(spec.to_xml())
    return path


def _spin(world, steps=25, kick="kick:start=0.2,rate=2,hull=1"):
    dist = [parse_disturbance(kick)]
    for d in dist:
        d.reset(0)
    prepare(world, dist, 0.0)
    for k in range(steps):
        advance(world, dist, 0.0, (k + 1) * world.config.constants.Te)
    return world


def test_the_sensors_read_the_hull_and_the_gimbal():
    w = _spin(LinkWorld())
    truth = w.vehicle_motion()
    ang = w.hull_velocity()[:3]
    R = w.data.xmat[w.ids.hull_body].reshape(3, 3)
    np.testing.assert_allclose(truth.gyro, R.T @ ang, atol=1e-9)  # body-frame rate
    assert abs(truth.gyro[2]) > 0.5  # the hull kick turns it
    assert truth.encoder == pytest.approx(w.gimbal_angle, abs=1e-12)
    np.testing.assert_allclose(truth.position, w.hull_pos, atol=1e-9)
    # The DVL sits 0.2 m aft and below the centre, looking down: it sees the hull's
    # velocity plus the yaw rate's lever arm, in its own frame.
    local = np.zeros(6)
    mujoco.mj_objectVelocity(w.model, w.data, mujoco.mjtObj.mjOBJ_SITE,
                             w.model.site("dvl").id, local, 1)
    np.testing.assert_allclose(truth.dvl, local[3:], atol=1e-9)
    assert abs(truth.dvl[1]) > 0.05  # the turn sweeps the DVL sideways


def test_reading_the_sensors_leaves_the_dynamics_alone(tmp_path):
    a = _spin(LinkWorld())
    b = LinkWorld(WorldConfig(xml=_scene_without_sensors(tmp_path)))
    dist = [parse_disturbance("kick:start=0.2,rate=2,hull=1")]
    for d in dist:
        d.reset(0)
    prepare(b, dist, 0.0)
    for k in range(25):
        b.vehicle_motion()  # None here; and on `a` reading it changes nothing either
        advance(b, dist, 0.0, (k + 1) * b.config.constants.Te)
    np.testing.assert_array_equal(a.data.qpos, b.data.qpos)
    np.testing.assert_array_equal(a.data.qvel, b.data.qvel)


def test_the_noise_has_the_datasheet_figures():
    n = NavigationNoise()
    w = LinkWorld()
    w.reset()
    w.forward_kinematics()
    s = NavigationSensor(w, 0.01, seed=3)
    readings = [s.read() for _ in range(2000)]  # 20 s at rest
    gyro = np.array([r.gyro for r in readings])
    expected = n.gyro_noise_density * math.sqrt(1 / (2 * 0.01))
    assert np.std(gyro[:, 2]) == pytest.approx(expected, rel=0.1)
    assert abs(np.mean(gyro[:, 2])) < 5 * n.gyro_bias_instability
    accel = np.array([r.accel for r in readings])
    assert np.mean(accel[:, 2]) == pytest.approx(9.81, abs=0.01)  # gravity's specific force
    dvl = np.array([r.dvl for r in readings])
    assert len(np.unique(dvl[:, 0])) == pytest.approx(2000 / 12.5, abs=2)  # 8 Hz, held
    assert np.std(dvl[::13, 0]) == pytest.approx(n.dvl_noise, rel=0.25)
    fixes = [r.position_fix for r in readings if r.position_fix is not None]
    assert len(fixes) == 20  # 1 Hz
    # The encoder reads whole steps of 2 pi / 2^14.
    w.reset(gimbal_angle=0.123456)
    w.forward_kinematics()
    enc = NavigationSensor(w, 0.01).read().encoder
    assert enc / n.encoder_step == pytest.approx(round(enc / n.encoder_step), abs=1e-9)
    assert abs(enc - 0.123456) <= n.encoder_step / 2


def test_turning_the_imu_on_leaves_the_photodiode_noise_alone():
    from ledsim.physics.sensor import IrradianceSensor

    a, b = LinkWorld(), LinkWorld()
    pa = IrradianceSensor(a, seed=5).read().power
    NavigationSensor(b, 0.01, seed=5).read()
    pb = IrradianceSensor(b, seed=5).read().power
    np.testing.assert_array_equal(pa, pb)


def test_a_scene_without_the_sensors_is_refused_in_one_line(tmp_path):
    w = LinkWorld(WorldConfig(xml=_scene_without_sensors(tmp_path)))
    assert w.vehicle_motion() is None
    with pytest.raises(WorldError, match="--no-imu") as info:
        NavigationSensor(w, 0.01)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("bad", [dict(gyro_noise_density=-1.0),
                                 dict(gyro_bias_instability=float("nan")),
                                 dict(dvl_rate=0.0), dict(encoder_bits=0),
                                 dict(fix_noise=float("inf"))])
def test_bad_noise_settings_are_refused(bad):
    with pytest.raises(ConfigError, match=next(iter(bad))):
        NavigationNoise(**bad)


def test_the_thrusters_push_the_hull_within_their_limits():
    w = LinkWorld()
    w.reset()
    assert list(w.model.actuator_ctrlrange[list(w.ids.thrusters), 1]) == \
        [100.0, 100.0, 100.0, 25.0, 25.0]  # surge, sway, heave [N]; pitch, yaw [N m]
    assert list(w.set_thrust([1e6, 0, 0, 0, 0])) == [100.0, 0, 0, 0, 0]  # clipped
    w.step(50)  # 0.1 s
    v = w.hull_velocity()[3:]
    assert 0.05 < v[0] < 0.1 * 100 / 30 and abs(v[1]) < 1e-3  # at most F t / m, forward


def test_dead_reckoning_follows_a_drifting_turning_hull():
    from observer.navigation.dead_reckoning import DeadReckoning

    w = LinkWorld()
    w.reset()
    dist = [parse_disturbance("current:speed=0.2,heading=1.2,gust=0.05,hold=0"),
            parse_disturbance("kick:start=1,rate=0.5,hull=1")]
    for d in dist:
        d.reset(0)
    prepare(w, dist, 0.0)
    m = w.model
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, m.site_quat[m.site("dvl").id])
    nav = DeadReckoning(0.01, w.hull_pos[:2], w.hull_yaw, R.reshape(3, 3),
                        m.site_pos[m.site("dvl").id] - m.site_pos[m.site("imu").id])
    sensor = NavigationSensor(w, 0.01, seed=1)
    for k in range(1000):  # 10 s: the hull drifts about a metre and turns
        r = sensor.read()
        s = nav.update(r.gyro, r.dvl, r.position_fix)
        advance(w, dist, 0.0, (k + 1) * 0.01)
    w.forward_kinematics()
    assert np.linalg.norm(w.hull_pos[:2]) > 0.5  # it did drift (it started at the origin)
    assert np.linalg.norm(s.position - w.hull_pos[:2]) < 0.05
    assert abs(s.heading - w.hull_yaw) < 0.01
