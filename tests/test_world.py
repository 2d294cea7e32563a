import math

import numpy as np
import pytest

from ledsim.constants import ConfigError, LinkConstants
from ledsim.physics.disturbances import DisturbanceError, parse_disturbance
from ledsim.physics.sensor import IrradianceSensor
from ledsim.physics.simulation import simulate
from ledsim.physics.world import SCENE, LinkWorld, WorldConfig, WorldError

HINGE = np.array([0.89, 0.0, 0.0])  # receiver centre = gimbal hinge, from the MJCF


@pytest.fixture(scope="module")
def world():
    return LinkWorld()


def paper_power(c, d, theta, phi):
    """eq. (pow-d-theta-phi) written out again, independently of ledsim.radiometry.optics."""
    r = c.receiver
    m = math.log(0.5) / math.log(math.cos(c.led_half_angle))
    g = (r.a1 * math.exp(-(((phi - r.b1) / r.c1) ** 2))
         + r.a2 * math.exp(-(((phi + r.b2) / r.c2) ** 2)))
    return c.power_scale * math.exp(-c.attenuation * d) / d**2 * math.cos(theta) ** m * g


def test_sensor_matches_the_paper_formula_at_a_known_geometry(world):
    c = world.config.constants
    q = 0.13
    world.reset(gimbal_angle=q)
    reading = IrradianceSensor(world, noise=False).read(noise=False)
    led = HINGE + [c.distance, 0.0, 0.0]
    for i, (z, offset) in enumerate([(0.003, 0.0), (-0.003, -c.dphi)]):
        pd = HINGE + [0.0, 0.0, z]
        los = led - pd
        d = np.linalg.norm(los)
        theta = math.acos(los[0] / d)  # LED axis is -x
        normal_angle = q + offset
        phi = math.atan2(los[1], los[0]) - normal_angle  # about +z, in the x-y plane
        expected = paper_power(c, d, theta, phi)
        assert reading.power_clean[i] == pytest.approx(expected, rel=1e-9)
        assert reading.incidence_angle[i] == pytest.approx(phi, abs=1e-12)


def test_blocking_the_line_of_sight_zeroes_only_the_blocked_photodiode(world):
    world.reset()
    sensor = IrradianceSensor(world, noise=False)
    # Plate 5 mm in front of the receiver with its lower edge at z = 0: it covers the
    # rays of photodiode 1 (z = +3 mm) and none of photodiode 2's (z = -3 mm).
    world.set_occluder(HINGE + [0.005, 0.0, 0.03])

    world.forward_kinematics()
    r = sensor.read(noise=False)
    assert r.power_clean[0] == 0.0 and r.visible_fraction[0] == 0.0
    assert r.power_clean[1] > 0.5 and r.visible_fraction[1] == 1.0
    world.set_occluder(HINGE + [0.005, 0.0, 0.03 + 0.0029])  # edge between the rays
    world.forward_kinematics()
    partial = sensor.read(noise=False).visible_fraction[0]
    assert 0.0 < partial < 1.0
    world.reset()


def test_power_falls_with_distance_as_exp_over_d_squared():
    c = LinkConstants()
    r = {}
    for d in (0.085, 0.17):
        w = LinkWorld(WorldConfig(constants=c.with_(distance=d)))
        r[d] = IrradianceSensor(w, noise=False).read(noise=False)
    a, b = r[0.085], r[0.17]
    assert b.distance[0] == pytest.approx(math.hypot(0.17, 0.003), rel=1e-12)
    m = c.lambertian_order
    law = (math.exp(-c.attenuation * b.distance[0]) / b.distance[0] ** 2
           * math.cos(b.emission_angle[0]) ** m) / (
        math.exp(-c.attenuation * a.distance[0]) / a.distance[0] ** 2
        * math.cos(a.emission_angle[0]) ** m)
    assert b.power_clean[0] / a.power_clean[0] == pytest.approx(law, rel=1e-9)
    assert b.power_clean[0] / a.power_clean[0] < 0.26


def test_turning_the_gimbal_by_dphi_puts_photodiode_2_where_photodiode_1_was(world):
    c = world.config.constants
    sensor = IrradianceSensor(world, noise=False)
    world.reset(gimbal_angle=0.05)
    before = sensor.read(noise=False)
    world.reset(gimbal_angle=0.05 + c.dphi)
    after = sensor.read(noise=False)
    assert after.incidence_angle[1] == pytest.approx(before.incidence_angle[0], abs=1e-12)
    assert after.power_clean[1] == pytest.approx(before.power_clean[0], rel=1e-9)
    world.reset()


def test_true_rate_matches_the_finite_difference_of_phi(world):
    sensor = IrradianceSensor(world, noise=False)
    world.reset(gimbal_angle=0.1, gimbal_rate=0.7)
    res = simulate(world, sensor, 0.2)
    fd = np.gradient(res.phi, res.t)
    np.testing.assert_allclose(res.phidot[5:-5], fd[5:-5], atol=0.02)
    world.reset()


def spin_down(density, viscosity):
    w = LinkWorld(WorldConfig(water_density=density, water_viscosity=viscosity))
    w.reset(gimbal_rate=5.0)
    simulate(w, IrradianceSensor(w), 1.0)
    return abs(w.gimbal_rate)


def test_water_damps_a_free_spinning_gimbal_more_than_air():
    in_water = spin_down(1000.0, 0.00089)
    in_air = spin_down(1.2, 1.8e-5)
    assert in_water < 0.7 * in_air


def test_neutrally_buoyant_hull_drifts_less_than_a_centimetre_in_ten_seconds():
    w = LinkWorld()
    w.reset()
    res = simulate(w, IrradianceSensor(w), 10.0)
    assert np.linalg.norm(res.hull_pos[-1] - res.hull_pos[0]) < 0.01
    # and the check can fail: without buoyancy the same hull sinks
    w.reset()
    w.set_hull_buoyancy(0.0)
    res = simulate(w, IrradianceSensor(w), 1.0)
    assert np.linalg.norm(res.hull_pos[-1] - res.hull_pos[0]) > 0.01


def test_occlusion_disturbance_blocks_for_about_its_duration(world):
    world.reset()
    sensor = IrradianceSensor(world)
    res = simulate(world, sensor, 2.0, disturbances=[parse_disturbance(
        "occlusion:start=0.5,duration=0.5")])
    blocked = (res.visible_fraction == 0).all(axis=1).mean() * 2.0  # both fully blocked [s]
    assert 0.4 < blocked < 0.6
    assert np.all(res.power_clean[res.visible_fraction == 0] == 0)
    assert res.occluded.all(axis=1).sum() > 40
    world.reset()


def test_transmitter_motion_moves_the_link_and_current_moves_a_drifting_hull(world):
    world.reset()
    res = simulate(world, IrradianceSensor(world), 2.0, disturbances=[
        parse_disturbance("transmitter:sway=0.01,frequency=1")])
    assert np.ptp(res.phi) > 0.05
    world.reset()
    drift = simulate(world, IrradianceSensor(world), 2.0, disturbances=[
        parse_disturbance("current:speed=0.3,hold=0")])
    assert np.linalg.norm(drift.hull_pos[-1] - drift.hull_pos[0]) > 0.1
    world.reset()
    from ledsim.agent.autopilot import Vehicle

    keeper = Vehicle(world, world.config.constants.Te, 0, world.config.constants.distance)
    held = simulate(world, IrradianceSensor(world), 2.0, disturbances=[
        parse_disturbance("current:speed=0.3")], vehicle=keeper)
    # Station keeping from its own navigation: a few cm while its disturbance observer
    # takes up the current's onset (the drifting hull goes more than 10 cm).
    assert np.abs(held.hull_pos - held.hull_pos[0]).max() < 0.03
    world.reset()


def test_missing_and_malformed_scene_files(tmp_path):
    with pytest.raises(WorldError, match="does not exist"):
        LinkWorld(WorldConfig(xml=tmp_path / "nope.xml"))
    bad = tmp_path / "bad.xml"
    bad.write_text("<mujoco><worldbody><body></mujoco>")
    with pytest.raises(WorldError, match="not valid MJCF"):
        LinkWorld(WorldConfig(xml=bad))
    no_pd2 = tmp_path / "no_pd2.xml"
    no_pd2.write_text(SCENE.read_text().replace('name="pd2"', 'name="pdX"'))
    with pytest.raises(WorldError, match="'pd2'"):
        LinkWorld(WorldConfig(xml=no_pd2))


@pytest.mark.parametrize("kwargs,name", [({"torque_limit": 0.0}, "torque_limit"),
                                         ({"torque_limit": -1.0}, "torque_limit"),
                                         ({"timestep": 0.003}, "timestep"),
                                         ({"integrator": "leapfrog"}, "integrator")])
def test_bad_world_knobs_are_named(kwargs, name):
    with pytest.raises(ConfigError, match=name):
        WorldConfig(**kwargs)


def test_led_without_line_of_sight_is_refused():
    w = LinkWorld(WorldConfig(led_yaw=math.pi))
    with pytest.raises(WorldError, match="no line of sight"):
        IrradianceSensor(w)


def test_bad_disturbances_are_named():
    with pytest.raises(DisturbanceError, match="tornado"):
        parse_disturbance("tornado")
    with pytest.raises(DisturbanceError, match="colour"):
        parse_disturbance("vibration:colour=3")
    with pytest.raises(DisturbanceError, match="frequency"):
        parse_disturbance("vibration:frequency=0")


def test_scene_file_loads_as_plain_mjcf():
    """What `python -m mujoco.viewer --mjcf assets/led_link.xml` does first."""
    import mujoco

    model = mujoco.MjModel.from_xml_path(str(SCENE))
    assert model.nbody == 5 and model.nsite >= 3 and model.ncam == 3


def test_euler_world_follows_the_implicitfast_one():
    """The cheaper integrator keeps the fluid damping stable and the motion the same to
    a few mrad over 5 s of torque (docs/integrators.md compares whole tables)."""
    import mujoco

    phis = {}
    for integ in ("implicitfast", "euler"):
        w = LinkWorld(WorldConfig(integrator=integ))
        assert w.model.opt.integrator == getattr(
            mujoco.mjtIntegrator, f"mjINT_{integ.upper()}")
        w.reset(0.1)
        phis[integ] = simulate(w, IrradianceSensor(w), 5.0, torque=lambda t: 0.002).phi
    assert np.all(np.isfinite(phis["euler"]))
    assert np.max(np.abs(phis["euler"] - phis["implicitfast"])) < 5e-3
    assert np.ptp(phis["euler"]) > 0.5  # the torque did move the gimbal


def test_knobs_reach_the_compiled_model():
    w = LinkWorld(WorldConfig(hull_mass=40.0, water_density=1025.0, water_viscosity=0.0011,
                              torque_limit=0.02, constants=LinkConstants(dphi=0.2)))
    assert w.model.body("auv").mass[0] > 40.0  # hull geom plus fins
    assert w.model.opt.density == 1025.0 and w.model.opt.viscosity == 0.0011
    np.testing.assert_allclose(w.model.actuator("gimbal_motor").forcerange, [-0.02, 0.02])
    n1, n2 = w.photodiode_normal(0), w.photodiode_normal(1)
    assert math.acos(n1 @ n2) == pytest.approx(0.2, abs=1e-12)
    assert w.set_torque(1.0) == 0.02  # clipped at the limit


def test_unstable_physics_is_an_error_and_leaves_no_log_file(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    w = LinkWorld()
    w.reset()
    w.add_hull_wrench(force=(1e300, 0.0, 0.0))
    with pytest.raises(WorldError, match="unstable"):
        w.step()
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()


def _without_trim(tmp_path):
    """The scene with every eye-only (class "trim") geom deleted, through MjSpec."""
    import mujoco

    spec = mujoco.MjSpec.from_file(str(SCENE))
    trims = [g for g in spec.geoms if g.classname.name == "trim"]
    assert len(trims) >= 10  # yoke, hubs, head face, pointer, thruster, ...
    for g in trims:
        spec.delete(g)
    path = tmp_path / "bare.xml"
    path.write_text(spec.to_xml())
    return WorldConfig(xml=path)


def test_eye_only_geoms_change_neither_inertia_nor_light_nor_motion(tmp_path):
    dressed, bare = LinkWorld(), LinkWorld(_without_trim(tmp_path))
    for name in ("auv", "gimbal"):
        a, b = dressed.model.body(name), bare.model.body(name)
        np.testing.assert_allclose(a.mass, b.mass, rtol=1e-12)
        np.testing.assert_allclose(a.inertia, b.inertia, rtol=1e-12)
        np.testing.assert_allclose(a.ipos, b.ipos, atol=1e-12)
    for q in np.linspace(-1.2, 1.2, 13):
        powers = []
        for w in (dressed, bare):
            w.reset(gimbal_angle=q)
            powers.append(IrradianceSensor(w, noise=False).read(noise=False).power)
        np.testing.assert_allclose(powers[0], powers[1], rtol=1e-12)
    # Same torque, same motion through the water (fluid forces included).
    traj = []
    for w in (dressed, bare):
        w.reset(gimbal_angle=0.2, gimbal_rate=1.0)
        for _ in range(200):
            w.set_torque(0.01)
            w.step()
        traj.append((w.gimbal_angle, w.hull_yaw))
    np.testing.assert_allclose(traj[0], traj[1], rtol=0, atol=1e-12)


def test_per_step_float_optics_match_the_array_formulas(world):
    """The plain-float twins on the loop's hot path compute the same powers."""
    from ledsim.radiometry.optics import (
        receiver_response,
        receiver_response_at,
        transmitter_gain,
        transmitter_gain_at,
    )

    c = world.config.constants
    for phi in np.linspace(-1.2, 1.2, 25):
        assert receiver_response_at(float(phi), c.receiver) == pytest.approx(
            float(receiver_response(phi, c.receiver)), rel=1e-14)
    for d, theta in [(0.05, 0.0), (0.085, 0.3), (0.3, 1.4), (0.2, 2.0)]:
        assert transmitter_gain_at(d, theta, c) == pytest.approx(
            float(transmitter_gain(d, theta, c)), rel=1e-14, abs=0.0)
    sensor = IrradianceSensor(world, noise=False)
    reading = sensor.read(noise=False)
    np.testing.assert_allclose(reading.power_clean, sensor.clean_power(
        reading.distance, reading.emission_angle, reading.incidence_angle,
        reading.visible_fraction), rtol=1e-14)
