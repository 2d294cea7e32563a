"""The one builder of a closed-loop run (issue 47): :func:`build_run` reads the run's
configuration and builds everything its seeds step, in one place.

- the model system (:class:`~ledsim.physics.gimbal_system.GimbalSystem`) and the
  identified one-step model the estimators compute with (:mod:`.estimation`);
- one world per seed, sharing one compiled scene where the run allows (:mod:`.worlds`);
- each seed's world at its start: its sensor with the run's noise, its disturbances and
  its vehicle, seeded from the seed (:mod:`.start`);
- each seed's control step: gate, estimator under its supervisor, law and motor
  (:mod:`.control`).

:class:`~ledsim.loop.closed_loop.ClosedLoop` steps what it builds; the environment's
shipped policy assembles a seed's control step with the same :mod:`.control`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from ledsim.agent.autopilot import Vehicle
from ledsim.agent.step import ControlStep
from ledsim.loop.build.control import control_step, head_control_step
from ledsim.loop.build.estimation import identified_model, run_noise
from ledsim.loop.build.start import start_world
from ledsim.loop.build.worlds import build_worlds
from ledsim.loop.outcome import Judging
from ledsim.loop.run_config import RunConfig
from ledsim.physics.disturbances import parse_disturbance
from ledsim.physics.gimbal_system import GimbalSystem, IdentifiedGimbalModel
from ledsim.physics.head_system import HeadSystem
from ledsim.physics.sensor import IrradianceSensor, SensorReading
from ledsim.physics.world import LinkWorld
from observer.noise import MeasurementNoise


class Latest:
    """A seed's last sensor reading (the oracle is handed its true state)."""

    __slots__ = ("reading",)

    def __init__(self):
        self.reading: SensorReading | None = None


@dataclass
class SeedRun:
    """One seed's built run: its world, its measurement noise, its sensor, disturbances
    and vehicle (None: run without the vehicle's sensors), its control step, the last
    reading its oracle would read, and how far off its vehicle believes the node is
    [m] (``node_error``)."""

    seed: int
    world: LinkWorld
    noise: MeasurementNoise
    sensor: IrradianceSensor
    disturbances: list
    vehicle: Vehicle | None
    step: ControlStep
    latest: Latest
    node_error: float = 0.0


@dataclass
class BuiltRun:
    """What :func:`build_run` builds: the model system and the identified model its
    estimators use, the control steps each run lasts, each seed's run, what the runs
    are judged by, the spec's flat names (a trace's header) and whether the control
    step reads the vehicle's sensors (``aided``)."""

    system: GimbalSystem
    model: IdentifiedGimbalModel
    steps: int
    seeds: list[SeedRun]
    judging: Judging
    header: dict
    aided: bool


def build_run(cfg: RunConfig, seeds: Sequence[int], record: bool = False) -> BuiltRun:
    """The runs of ``cfg`` for ``seeds`` (see the module's text); ``record``: each
    estimator keeps what it is given (to replay it)."""
    two = cfg.world.two_axes
    system = (HeadSystem if two else GimbalSystem)(cfg.world_config())
    model = identified_model(system)
    steps = int(round(cfg.run_seconds / system.Te))
    # The system's world serves the first run; the others share its model unless a
    # disturbance changes the model (a water current sets its medium velocity).
    share = not any(parse_disturbance(d).changes_model for d in cfg.disturbances)
    worlds = build_worlds(system.config, len(seeds), system.world, share)
    runs = [build_seed(cfg, system, model, int(s), w, record)
            for s, w in zip(seeds, worlds, strict=True)]
    judging = Judging(cfg.noise_scale, cfg.data_bit_rate, cfg.scenario_spec.warmup,
                      cfg.steady_from)
    return BuiltRun(system, model, steps, runs, judging, cfg.flat(), cfg.imu)


def build_seed(cfg: RunConfig, system: GimbalSystem, model, seed: int, world: LinkWorld,
               record: bool = False) -> SeedRun:
    """Seed ``seed``'s run of ``cfg`` in ``world``, started."""
    noise = run_noise(cfg, system)
    sensor, disturbances, vehicle = start_world(cfg, system, world, seed, noise=noise)
    latest = Latest()
    if isinstance(system, HeadSystem):
        step = head_control_step(cfg, system, model, seed, lambda: latest.reading.x,
                                 record, noise)
    else:
        step = control_step(cfg, system, model, seed, world.gimbal_angle,
                            lambda: latest.reading.x, record, noise)
    return SeedRun(seed, world, noise, sensor, disturbances, vehicle, step, latest,
                   cfg.node_error)
