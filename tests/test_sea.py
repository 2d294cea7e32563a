"""The real sea: linear waves against the textbook, strip forces on the hull, the depth
of the vehicles, and the light around the receiver (flicker, scintillation)."""

import math
import re

import numpy as np
import pytest

from ledsim.constants import GRAVITY
from ledsim.physics.disturbances import DisturbanceError, parse_disturbance
from ledsim.physics.linear_waves import RegularWave, wavenumber
from ledsim.physics.scene import WorldConfig, WorldError
from ledsim.physics.world import LinkWorld
from ledsim.radiometry.link_presets import link_constants


def test_dispersion_relation_in_deep_and_finite_water():
    T = 8.0
    w = 2 * math.pi / T
    assert wavenumber(T) == pytest.approx(w * w / GRAVITY, rel=1e-12)
    for h in (2.0, 10.0, 50.0):
        k = wavenumber(T, h)
        assert GRAVITY * k * math.tanh(k * h) == pytest.approx(w * w, rel=1e-10)
    # shallow water: the wave runs at sqrt(g h)
    celerity = 2 * math.pi / 30.0 / wavenumber(30.0, 1.0)
    assert celerity == pytest.approx(math.sqrt(GRAVITY * 1.0), rel=0.01)


@pytest.mark.parametrize("h", [math.inf, 15.0])
def test_orbital_velocity_amplitude_and_decay_match_linear_theory(h):
    """Dean and Dalrymple's formulas, sampled over a period at several depths."""
    H, T = 1.5, 6.0
    wave = RegularWave(H, T, heading=0.3, water_depth=h)
    w, k = 2 * math.pi / T, wave.k
    t = np.linspace(0, T, 400, endpoint=False)
    for s in (0.0, 3.0, 10.0):
        pairs = [wave.kinematics(np.array([2.0, -1.0, -s]), s, ti) for ti in t]
        vel, acc = np.stack([p[0] for p in pairs]), np.stack([p[1] for p in pairs])
        if math.isinf(h):
            horizontal = vertical = 0.5 * H * w * math.exp(-k * s)
        else:
            horizontal = 0.5 * H * w * math.cosh(k * (h - s)) / math.sinh(k * h)
            vertical = 0.5 * H * w * math.sinh(k * (h - s)) / math.sinh(k * h)
        along = vel[:, 0] * math.cos(0.3) + vel[:, 1] * math.sin(0.3)
        assert np.abs(along).max() == pytest.approx(horizontal, rel=1e-3)
        assert np.abs(vel[:, 2]).max() == pytest.approx(vertical, rel=1e-3)
        across = -vel[:, 0] * math.sin(0.3) + vel[:, 1] * math.cos(0.3)
        assert np.abs(across).max() < 1e-12
        # the acceleration is the velocity's time derivative
        dv = np.gradient(vel[:, 2], t)
        assert np.abs(dv - acc[:, 2]).max() < 2e-3 * vertical * w
    surface = wave.elevation(np.array([[0.0, 0.0, 0.0]]), 0.0)
    assert surface[0] == pytest.approx(0.5 * H)


def test_a_free_neutrally_buoyant_hull_follows_the_water_in_a_long_wave():
    """A body much smaller than the wave, as heavy as its water, moves with it: its
    surge and heave follow the orbit (a strip model that lost the depth decay, the
    inertia force or the drag's flow would not)."""
    from ledsim.physics.wave_response import free_hull_response

    ahead = free_hull_response(8.0, 5.0, 0.0, seconds=40.0)
    assert 0.8 < ahead.surge < 1.1 and 0.8 < ahead.heave < 1.1 and ahead.sway < 0.02
    assert 0.2 * ahead.slope < ahead.pitch < 2 * ahead.slope  # of the wave's slope
    beam = free_hull_response(8.0, 5.0, math.pi / 2, seconds=40.0)
    assert 0.8 < beam.sway < 1.1 and 0.8 < beam.heave < 1.1 and beam.surge < 0.05


def test_the_bench_keeps_its_uniform_wave_flow_and_a_physical_link_gets_strips():
    waves = parse_disturbance("waves:height=1,period=6")
    bench = LinkWorld(WorldConfig())
    assert waves.strips_in(bench) == 0
    physical = LinkWorld(WorldConfig(constants=link_constants("luma", 30.0)))
    assert waves.strips_in(physical) == 12
    assert parse_disturbance("waves:strips=0").strips_in(physical) == 0


@pytest.mark.parametrize("text", ["waves:strips=-1", "waves:strips=65", "waves:strips=1.5",
                                  "waves:sea_depth=-1", "waves:depth=10,sea_depth=5"])
def test_bad_wave_keys_are_refused(text):
    with pytest.raises(DisturbanceError):
        parse_disturbance(text)


@pytest.mark.parametrize("spec,needle", [
    ("waves:height=20,period=3", "H/L = 1.42 > 1/7 (L = 14.1 m)"),
    ("waves:height=2.1,period=3", "the height is at most 2.01 m"),
    ("waves:height=10,period=12,sea_depth=12", "Miche's limit over sea_depth=12 m"),
])
def test_a_wave_steeper_than_it_can_stand_is_refused(spec, needle):
    """H/L at most 1/7 in deep water (L from the dispersion relation), Miche's
    tanh(k h)/7 over a finite sea; one line naming the value, L and the limit."""
    with pytest.raises(DisturbanceError) as exc:
        parse_disturbance(spec)
    assert needle in str(exc.value) and "\n" not in str(exc.value)


def test_the_steepest_wave_that_stands_is_accepted():
    from ledsim.physics.flow import BREAKING_STEEPNESS

    for sea in (0.0, 12.0, 200.0):
        wave = parse_disturbance(f"waves:period=5,sea_depth={sea:g}").wave
        limit = BREAKING_STEEPNESS * (math.tanh(wave.k * sea) if sea else 1.0)
        height = 0.999 * limit * wave.wavelength
        assert parse_disturbance(f"waves:height={height!r},period=5,sea_depth={sea:g}")
        assert limit <= BREAKING_STEEPNESS


@pytest.mark.parametrize("settings,needle", [
    (dict(depth=3.0, disturbances=("waves:height=10",)), "too near the vehicle at --depth 3 m"),
    (dict(depth=3.0, disturbances=("waves:height=5.8",)), "at most 5.7 m"),
    (dict(disturbances=("waves:height=4,depth=2",)), "vehicle at waves.depth=2 m"),
    (dict(link="luma", distance=20.0, depth=3.0, transmitter_depth=1.0,
          disturbances=("waves:height=2",)), "too near the LED at 1 m"),
    (dict(link="luma", distance=20.0, depth=3.0, transmitter_depth=5.0,
          disturbances=("waves:sea_depth=4.5",)), "deeper than the LED's 5 m"),
])
def test_a_trough_below_the_vehicle_or_the_led_is_refused_up_front(settings, needle):
    from ledsim.errors import LedsimError
    from ledsim.loop.run_config import RunConfig

    with pytest.raises(LedsimError, match=re.escape(needle)):
        RunConfig(estimator="ekf", seconds=1.0, **settings).validate()


def test_a_trough_that_passes_over_both_vehicles_is_accepted():
    from ledsim.loop.run_config import RunConfig

    RunConfig(estimator="ekf", seconds=1.0, depth=3.0,
              disturbances=("waves:height=5.7,period=12",)).validate()
    RunConfig(estimator="ekf", link="luma", distance=20.0, depth=3.0, transmitter_depth=1.0,
              disturbances=("waves:height=1.9,period=8",)).validate()


def test_the_clearances_are_the_tops_of_the_hull_and_the_led_in_the_scene():
    """HULL_CLEARANCE and LED_CLEARANCE cover the highest point of the receiver vehicle
    (hull, fin, mast, gimbal) and of the LED's housing (not its mast, which hangs below)
    above their centres in the shipped scene, and by no more than a centimetre and a
    half."""
    import mujoco

    from ledsim.physics.flow import HULL_CLEARANCE, LED_CLEARANCE

    world = LinkWorld(WorldConfig())
    m, d = world.model, world.data
    mujoco.mj_forward(m, d)

    def top(*bodies):
        ids = [m.body(b).id for b in bodies]
        tops = []
        for g in range(m.ngeom):
            if m.geom_bodyid[g] in ids:
                r = d.geom_xmat[g].reshape(3, 3)[2]
                tops.append(d.geom_xpos[g, 2] + r @ m.geom_aabb[g, :3]
                            + np.abs(r) @ m.geom_aabb[g, 3:])
        return max(tops)

    hull = top("auv", "gimbal") - d.xpos[m.body("auv").id][2]
    led = top("transmitter") - d.site_xpos[m.site("led").id][2]
    assert hull <= HULL_CLEARANCE < hull + 0.015
    assert led <= LED_CLEARANCE < led + 0.015


@pytest.mark.parametrize("command,args", [
    ("run", ["--depth", "3", "--disturbance", "waves:height=10"]),
    ("simulate", ["--depth", "3", "--disturbance", "waves:height=10"]),
    ("run", ["--disturbance", "waves:height=20,period=3"]),
])
def test_impossible_seas_exit_2_in_one_line_before_any_work(tmp_path, command, args):
    from conftest import assert_user_error, run_cli

    out = tmp_path / "o"
    r = run_cli(command, *args, "--out", str(out))
    assert_user_error(r, "waves: height=")
    assert not out.exists()


def test_depths_place_the_led_above_the_receiver_at_the_same_slant_distance():
    c = link_constants("luma", 20.0)
    world = LinkWorld(WorldConfig(constants=c, depth=10.0, transmitter_depth=7.0))
    rise = world.led_pos - world.photodiode_pos(0)
    assert np.linalg.norm(rise) == pytest.approx(20.0, abs=0.01)
    assert rise[2] == pytest.approx(3.0, abs=0.01)
    with pytest.raises(WorldError, match="transmitter_depth"):
        LinkWorld(WorldConfig(constants=c, depth=10.0, transmitter_depth=40.0))
    with pytest.raises(Exception, match="depth"):
        WorldConfig(constants=c, depth=0.2)


def test_scintillation_fades_the_power_log_normally_with_its_index():
    from ledsim.physics.light import Scintillation, window_share

    world = LinkWorld(WorldConfig(constants=link_constants("luma", 30.0)))
    fade = Scintillation(index=0.3, time=0.05, correlation=0.5, seed=3)
    Te = world.config.constants.Te
    gains = []
    for k in range(40_000):
        fade.apply(world, k * Te)
        gains.append(world.light_gain.copy())
    g = np.array(gains)
    share = window_share(0.05, Te)
    assert g.mean() == pytest.approx(1.0, abs=0.02)
    assert g.var() / g.mean() ** 2 == pytest.approx(0.3 * share, rel=0.1)
    logs = np.log(g)
    assert np.corrcoef(logs[:, 0], logs[:, 1])[0, 1] == pytest.approx(0.5, abs=0.05)
    assert np.corrcoef(logs[1:, 0], logs[:-1, 0])[0, 1] == pytest.approx(
        math.exp(-Te / 0.05), abs=0.03)


def test_flicker_adds_daylight_shot_noise_that_falls_with_depth():
    from ledsim.physics.light import SunlightFlicker

    var, background = {}, {}
    for depth in (3.0, 20.0):
        world = LinkWorld(WorldConfig(constants=link_constants("luma", 30.0), depth=depth))
        flicker = SunlightFlicker(seed=1, contrast=0.3)
        noise = []
        for k in range(20_000):
            flicker.apply(world, k * 0.01)
            noise.append(world.light_noise.copy())
        var[depth], background[depth] = float(np.var(noise)), flicker.background_power
    # the shot noise's variance follows the daylight, which Kirk's K_d dims with depth
    assert background[3.0] > background[20.0] > 0
    assert var[3.0] / var[20.0] == pytest.approx(background[3.0] / background[20.0], rel=0.15)
    with pytest.raises(DisturbanceError, match="physical link"):
        SunlightFlicker().apply(LinkWorld(WorldConfig()), 0.0)


@pytest.mark.parametrize("text", ["scintillation:index=0", "scintillation:index=2",
                                  "scintillation:time=0", "scintillation:correlation=1.5",
                                  "flicker:irradiance=-1", "flicker:contrast=9",
                                  "flicker:frequency=0"])
def test_bad_light_keys_are_refused(text):
    with pytest.raises(DisturbanceError):
        parse_disturbance(text)


def test_a_fade_is_not_a_pointing_loss():
    """The oracle points perfectly: fades leave its availability as it was."""
    from ledsim.loop.report import run_many
    from ledsim.loop.run_config import RunConfig

    def availability(*disturbances):
        cfg = RunConfig(estimator="oracle", link="luma", seconds=3.0,
                        disturbances=disturbances)
        return run_many(cfg, progress=False)[0].availability.mean

    assert availability("scintillation:index=0.5") == pytest.approx(availability(), abs=0.01)


@pytest.mark.parametrize("distance", [8.0, 30.0, 60.0])
def test_the_overview_camera_sees_both_vehicles_under_the_surface(distance):
    """Both ends of the link project inside the overview camera's frame, and the camera
    is under the surface (a physical link's scene scales with its distance)."""
    import mujoco

    depth = 3.0
    world = LinkWorld(WorldConfig(constants=link_constants("luma", distance), depth=depth))
    m, d = world.model, world.data
    mujoco.mj_forward(m, d)
    cam = m.camera("overview").id
    pos, R = d.cam_xpos[cam], d.cam_xmat[cam].reshape(3, 3)
    tan_y = math.tan(math.radians(m.cam_fovy[cam]) / 2)
    tan_x = tan_y * 640 / 480
    for point in (world.hull_pos, world.led_pos):
        local = R.T @ (point - pos)  # MuJoCo cameras look along -z
        assert local[2] < 0
        assert abs(local[0] / -local[2]) < tan_x and abs(local[1] / -local[2]) < tan_y
    assert pos[2] < world.initial_hull_pos[2] + depth
    assert m.vis.map.fogend == pytest.approx(
        3.0 / world.config.constants.link.water_at_led.attenuation)
    # the occluder grows with the link, and the bench keeps its own scene
    assert m.geom("occluder_plate").size[1] >= 0.01 * distance
    bench = LinkWorld(WorldConfig()).model
    assert bench.geom("occluder_plate").size[1] == pytest.approx(0.03)
    assert bench.vis.map.fogend == pytest.approx(7.0)


def test_a_frame_of_the_sea_draws_the_surface_and_the_beam():
    from ledsim.physics.render import FrameRecorder
    from ledsim.physics.sea_render import CONE_SLICES, SURFACE_TILES
    from ledsim.physics.sensor import IrradianceSensor

    world = LinkWorld(WorldConfig(constants=link_constants("luma", 20.0), depth=3.0))
    waves = parse_disturbance("waves:height=1.5,period=6,heading=0")
    rec = FrameRecorder(world, 320, 240, 10.0, "overview", waves=[waves.wave])
    try:
        reading = IrradianceSensor(world).read()
        frame = rec.render(0.5, reading)
        assert rec.renderer.scene.ngeom >= SURFACE_TILES**2 + CONE_SLICES
        assert frame.shape == (240, 320, 3) and frame.std() > 5
    finally:
        rec.close()


def test_the_receiver_dome_takes_the_head_out_of_the_flow():
    c = link_constants("luma", 30.0)
    open_head = LinkWorld(WorldConfig(constants=c)).model
    dome = LinkWorld(WorldConfig(constants=c, receiver_dome=True)).model
    g = open_head.geom("gimbal_housing").id
    assert open_head.geom_fluid[g, 0] > 0 and dome.geom_fluid[g, 0] == 0
    # the hinge's inertia is the same: only the water's torque goes
    assert dome.body_mass[dome.body("gimbal").id] == open_head.body_mass[
        open_head.body("gimbal").id]


def test_the_run_reports_its_depths():
    from ledsim.files.results import to_jsonable
    from ledsim.loop.report import run_many
    from ledsim.loop.run_config import RunConfig

    cfg = RunConfig(estimator="ekf", link="luma", seconds=1.0, seeds=1, depth=3.0,
                    transmitter_depth=2.5, receiver_dome=True)
    cfg.validate()
    summary = to_jsonable(run_many(cfg, progress=False)[0])
    assert (summary["depth"], summary["transmitter_depth"], summary["receiver_dome"]) == \
        (3.0, 2.5, True)


def test_the_env_and_the_sweep_refuse_an_impossible_sea(tmp_path):
    from ledsim.envs.link_align import LinkAlignEnv
    from ledsim.loop.run_config import RunConfig
    from ledsim.loop.sweep import SweepGrid

    with pytest.raises(DisturbanceError, match="steeper than a wave can stand"):
        LinkAlignEnv(disturbances=("waves:height=20,period=3",))
    with pytest.raises(DisturbanceError, match="too near the vehicle at --depth 2 m"):
        LinkAlignEnv(depth=2.0, disturbances=("waves:height=4",))
    grid = SweepGrid(["ekf"], ["none", "current+waves:height=4"], [0.085], [1.0], 1,
                     RunConfig(seconds=1.0, depth=2.0))
    with pytest.raises(DisturbanceError, match="too near the vehicle"):
        grid.validate()
