"""A run's world at its start: the sensor with the run's noise, the disturbances and the
vehicle, all seeded from the run's seed."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ledsim.agent.autopilot import Vehicle
from ledsim.loop.build.estimation import run_noise
from ledsim.loop.run_config import RunConfig
from ledsim.physics.disturbances import parse_disturbance
from ledsim.physics.gimbal_system import GimbalSystem
from ledsim.physics.sensor import IrradianceSensor
from ledsim.physics.tick import prepare
from ledsim.physics.world import LinkWorld
from observer.noise import MeasurementNoise


class Surroundings(NamedTuple):
    """What a run's world is given at its start: the photodiodes' sensor, the
    disturbances and the vehicle (None: a scene without the vehicle's sensors, run with
    ``--no-imu``)."""

    sensor: IrradianceSensor
    disturbances: list
    vehicle: Vehicle | None


def start_world(cfg: RunConfig, system: GimbalSystem, world: LinkWorld, seed: int,
                x0: tuple[float, float] | None = None,
                noise: MeasurementNoise | None = None) -> Surroundings:
    """Put ``world`` in the scenario's initial state (or the true state ``x0``: phi
    [rad], phidot [rad/s]), ready for step 0, and give it the run's sensor (drawing
    from ``noise``; None: :func:`run_noise`), disturbances and vehicle, all seeded
    with ``seed``."""
    x0 = cfg.scenario_spec.x0 if x0 is None else x0
    phi0, phidot0 = x0  # the one axis's angle and rate
    if world.config.constants.layout.n_axes == 2:
        # A pan-tilt head: the azimuth starts where the one axis would, the tilt
        # ``initial_elevation`` off the LED's elevation (the scene's, as the vehicle's
        # navigation would put it).
        world.reset(gimbal_angle=system.home - np.array([phi0, cfg.initial_elevation]),
                    gimbal_rate=-np.array([phidot0, 0.0]))
    else:
        world.reset(gimbal_angle=system.phi_home - phi0, gimbal_rate=0.0 - phidot0)
    sensor = IrradianceSensor(world, seed=seed, measurement_noise=(
        run_noise(cfg, system) if noise is None else noise),
        channel_gains=cfg.world.channel_gains())
    disturbances = [parse_disturbance(d) for d in cfg.disturbances]
    for d in disturbances:
        d.reset(seed)
    vehicle = None
    if cfg.imu or world.ids.vehicle_sensors is not None:
        vehicle = Vehicle(world, system.Te, seed, cfg.distance, cfg.station_keeps,
                          noise=cfg.world.navigation_noise(),
                          gains=cfg.world.keeping_gains(),
                          mission=cfg.mission_plan)
    prepare(world, disturbances, world.time, vehicle)
    return Surroundings(sensor, disturbances, vehicle)
