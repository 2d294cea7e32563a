"""The seabed at the sea's depth (issue 48): the LED can stand anywhere in the water, and a
line of sight the scene cuts, grazing included, is refused naming what cuts it."""

import json

import numpy as np
import pytest
from conftest import assert_user_error, run_cli

from ledsim.physics.flow import Waves
from ledsim.physics.scene import ConfigError, WorldConfig
from ledsim.physics.sensor import IrradianceSensor
from ledsim.physics.world import LinkWorld, WorldError
from ledsim.radiometry.link_presets import link_constants

LUMA = link_constants("luma", 30.0)


def seabed_z(world) -> float:
    return float(world.model.geom("seabed").pos[2])


def test_the_default_seabed_stays_under_a_level_link_and_goes_under_a_deeper_led():
    level = LinkWorld(WorldConfig(constants=LUMA, depth=10.0))
    assert seabed_z(level) == -2.5  # the scene's, 2.5 m under the receiver
    # The case: an LED 3 m below the receiver stood under the seabed and was
    # refused; at 2.5 m below, its beam grazed the seabed and the run went on blind.
    for tx in (12.5, 13.0, 25.0):
        world = LinkWorld(WorldConfig(constants=LUMA, depth=10.0, transmitter_depth=tx))
        assert seabed_z(world) == pytest.approx(-2.5 - (tx - 10.0))
        reading = IrradianceSensor(world, noise=False).read()
        np.testing.assert_array_equal(reading.visible_fraction, 1.0)


def test_sea_depth_puts_the_seabed_under_the_surface_and_must_lie_below_both_ends():
    world = LinkWorld(WorldConfig(constants=LUMA, depth=20.0, transmitter_depth=25.0,
                                  sea_depth=40.0))
    hull = float(world.initial_hull_pos[2])
    assert hull + 20.0 - seabed_z(world) == pytest.approx(40.0)  # 40 m under the surface
    with pytest.raises(ConfigError, match=r"sea_depth=25.3 is not allowed: must be in "
                       r"\[25.5, 11000\] m: the seabed lies at least 0.5 m below both ends "
                       r"\(depth 20 m, transmitter_depth 25 m\)"):
        WorldConfig(constants=LUMA, depth=20.0, transmitter_depth=25.0, sea_depth=25.3)


def _sensor_with_the_seabed_at(z: float):
    world = LinkWorld(WorldConfig(constants=LUMA, depth=10.0, transmitter_depth=14.0))
    world.model.geom("seabed").pos[2] = z  # a seabed that rises between the two ends
    return IrradianceSensor(world, noise=False)


def test_a_beam_the_seabed_cuts_is_refused_naming_the_seabed():
    with pytest.raises(WorldError, match=r"the LED, 14 m deep, is hidden from photodiode "
                       r"'pd1' by the seabed"):
        _sensor_with_the_seabed_at(-1.0)


def test_a_grazing_beam_is_refused_too():
    """The LED's aperture (3 mm) half below the seabed: some rays pass, some do not."""
    world = LinkWorld(WorldConfig(constants=LUMA, depth=10.0, transmitter_depth=14.0))
    led_z = float(world.led_pos[2])
    # the plane through the LED's centre at the LED, sloping with the beam, cuts the
    # rays to the lower half of the aperture: put a flat seabed just under the centre
    with pytest.raises(WorldError, match=r"% hidden from photodiode 'pd1' by the seabed"):
        _sensor_with_the_seabed_at(led_z + 0.0005)


def test_the_waves_stand_in_the_worlds_sea_unless_they_name_their_own():
    waves = Waves(height=1.0, period=8.0)
    waves.check_sea(10.0, None, 30.0)
    assert waves.sea_depth == 30.0 and waves.wave.water_depth == 30.0
    own = Waves(height=1.0, period=8.0, sea_depth=50.0)
    own.check_sea(10.0, None, 30.0)
    assert own.sea_depth == 50.0
    steep = Waves(height=4.0, period=6.0)  # stands in deep water, breaks over 5 m
    steep.check_sea(3.0, None, None)
    from ledsim.physics.disturbances import DisturbanceError
    with pytest.raises(DisturbanceError, match="steeper|Miche"):
        Waves(height=4.0, period=6.0).check_sea(3.0, None, 5.0)


def test_the_command_line_takes_sea_depth_and_refuses_a_seabed_above_an_end(tmp_path):
    out = tmp_path / "bad"
    r = run_cli("run", "--link", "luma", "--depth", "10", "--transmitter-depth", "13",
                "--sea-depth", "12", "--seeds", "1", "--seconds", "0.5", "--out", str(out))
    assert_user_error(r, "--sea-depth 12.0 is not allowed")
    assert "transmitter-depth 13" in r.stderr and not out.exists()
    out = tmp_path / "ok"
    r = run_cli("run", "--link", "luma", "--depth", "10", "--transmitter-depth", "13",
                "--sea-depth", "30", "--estimator", "oracle", "--seeds", "1",
                "--seconds", "0.5", "--out", str(out))
    assert r.returncode == 0, r.stderr
    results = json.loads((out / "results.json").read_text())
    assert results["sea_depth"] == 30.0 and results["spec"]["sea_depth"] == 30.0
