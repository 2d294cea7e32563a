"""What a closed-loop run in MuJoCo is: its configuration, in four parts (the scenarios
and the other choices are in :mod:`ledsim.loop.registry`)."""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

from ledsim.experiment.scenario import Scenario
from ledsim.loop.mission_scenarios import MISSION_SCENARIOS, placed
from ledsim.loop.registry import (  # noqa: F401 (aliases: the choices where ledsim 0.2 had them)
    ACQUISITIONS,
    COMPARED_ESTIMATORS,
    FILTER_DISTANCES,
    LOOP_ESTIMATORS,
    MAX_INITIAL_ANGLE,
    MIN_FAST_PEAK_SNR,
    OMEGA_MODELS,
    PHYSICS_SCENARIOS,
    peak_snr,
    yaw_only,
)
from ledsim.loop.validation import (
    run_from_dict,
    validate_run,
)
from ledsim.loop.world_part import WorldPart
from ledsim.physics.disturbances import parse_disturbance
from ledsim.physics.scene import WorldConfig
from ledsim.radiometry.link_presets import preset_named


@dataclass(frozen=True)
class TaskPart:
    """What an experiment asks of the loop.

    Attributes:
        scenario: a key of :data:`PHYSICS_SCENARIOS`.
        disturbances: disturbance specs ``name[:key=value,...]``.
        seconds: length of a run [s] (None: the scenario's).
        supervision: watch the estimate, flag a lost link and reacquire it with a scan
            (:mod:`ledsim.agent.supervisor`); off: the estimator alone drives the motor.
        acquisition: how the link is acquired, at the start and after a loss:
            ``warm-up`` holds the gimbal for the scenario's warm-up while the estimator
            converges, then slews under the control law at its rate limit, and scans
            for a lost beam; ``minimum-time`` fixes the beam from the pair of powers and
            slews there at the torque limit, carried on the encoder, with no warm-up
            (:mod:`ledsim.agent.slew`; supervised runs; the default).
        initial_angle: the true incidence angle phi at the start [rad], at rest (None:
            the scenario's); |phi| <= :data:`MAX_INITIAL_ANGLE`. Beyond about 0.6 rad the
            LED is outside the receiver's field of view.
        initial_elevation: on a pan-tilt head, the true elevation of the LED from the
            boresight at the start [rad] (0: the tilt starts pointed at the LED's
            elevation, as the vehicle's navigation would put it).
    """

    scenario: str = "align"
    disturbances: tuple[str, ...] = ()
    seconds: float | None = None
    supervision: bool = True
    initial_angle: float | None = None
    initial_elevation: float = 0.0
    acquisition: str = "minimum-time"


@dataclass(frozen=True)
class EstimatorPart:
    """The estimator of an experiment.

    Attributes:
        estimator: a key of :data:`LOOP_ESTIMATORS`.
        particles: particle-filter size.
        checkpoint: KKL checkpoint (None: the shipped one for the distance).
        omega_model: f of the KKL's Omega correction: the identified one-step model,
            the simulator itself, or none.
        filter_distance: what the EKF, UKF and particle filter know of the distance:
            ``configured`` (their model is the configured distance's) or ``nominal``
            (the paper distance's model, rescaled by the supervisor's gain tracker: what
            the KKL knows).
        imu: the control step uses the vehicle's IMU, DVL and encoder (line-of-sight
            feed-forward, the hull's motion as a known input of the estimator); off: the
            photodiodes and the gimbal torque only, as in the paper.
    """

    estimator: str = "kkl"
    particles: int = 2000
    checkpoint: str | None = None
    omega_model: str = "identified"
    filter_distance: str = "configured"
    imu: bool = True


@dataclass(frozen=True)
class ExecutionPart:
    """How an experiment is run: Monte-Carlo runs (seeds 0..seeds-1) on ``workers``
    processes, and the window [s] of the per-window metrics it also reports (None:
    none; :mod:`ledsim.loop.windows`). It never changes a seed's numbers."""

    seeds: int = 4
    workers: int = 2
    window: float | None = None


#: How long a mission's run holds its last waypoint when no ``seconds`` is given [s].
MISSION_HOLD = 5.0

PARTS = {"world": WorldPart, "task": TaskPart, "estimation": EstimatorPart,
         "execution": ExecutionPart}


#: The part each flat name belongs to: ``RunConfig(estimator="ekf")`` sets the
#: estimation part's ``estimator``.
FLAT = {f.name: part for part, kind in PARTS.items() for f in fields(kind)}


@dataclass(frozen=True, init=False)
class RunSpec:
    """Everything one ``ledsim run`` needs, in four frozen parts: :attr:`world`
    (:class:`WorldPart`), :attr:`task` (:class:`TaskPart`), :attr:`estimation`
    (:class:`EstimatorPart`) and :attr:`execution` (:class:`ExecutionPart`).

    Built from parts (``RunSpec(world=WorldPart(link="luma"))``, or :meth:`of`), from
    the parts' flat names (``RunSpec(estimator="ekf", seconds=5)``: each sets its part's
    field; the parts not named keep their defaults), or both. Every flat name reads back
    as an attribute (``spec.estimator``), and ``dataclasses.replace(spec,
    estimator="ukf")`` takes flat names too. :data:`RunConfig` is its former name.
    """

    world: WorldPart
    task: TaskPart
    estimation: EstimatorPart
    execution: ExecutionPart

    def __init__(self, world: WorldPart | None = None, task: TaskPart | None = None,
                 estimation: EstimatorPart | None = None,
                 execution: ExecutionPart | None = None, **flat):
        given = {"world": world, "task": task, "estimation": estimation,
                 "execution": execution}
        changes: dict[str, dict] = {}
        for name, value in flat.items():
            if name not in FLAT:
                raise TypeError(f"{type(self).__name__}() got an unexpected keyword "
                                f"argument {name!r}")
            changes.setdefault(FLAT[name], {})[name] = value
        for part, kind in PARTS.items():
            own = changes.get(part, {})
            value = kind(**own) if given[part] is None else replace(given[part], **own)
            object.__setattr__(self, part, value)
        w, e = self.world, self.estimation
        if w.gimbal is None and w.receiver is None and w.link != "paper" and \
                yaw_only(e.estimator, e.checkpoint):
            # a physical link's default head is the pan-tilt, but for what only the yaw
            # gimbal runs (every command before that default still runs as it did)
            object.__setattr__(self, "world", replace(w, gimbal="yaw"))
        scenario = MISSION_SCENARIOS.get(self.task.scenario)
        if scenario is not None and self.world.link != "paper":
            # a mission past a node: the node where the scenario puts it, from 0.9 of
            # the link's reach unless a distance is given (a part given gives its own)
            given = world is not None or flat.get("distance") is not None
            object.__setattr__(self, "world", placed(self.world, scenario, given,
                                                     self.data_bit_rate))

    @classmethod
    def of(cls, world: WorldPart = WorldPart(), task: TaskPart = TaskPart(),  # noqa: B008
           estimation: EstimatorPart = EstimatorPart(),
           execution: ExecutionPart = ExecutionPart()) -> RunSpec:
        """The run made of these parts."""
        return cls(world, task, estimation, execution)

    @classmethod
    def from_dict(cls, saved: dict) -> RunSpec:
        """The run a saved configuration describes (``asdict`` of one through JSON:
        nested by parts, or flat as ledsim 0.2 saved it), checked in one line
        (:func:`~ledsim.loop.validation.run_from_dict`)."""
        return run_from_dict(cls, saved)

    def flat(self) -> dict:
        """Every flat name and its value (the results' and the sweep's columns). On a
        physical link the head is saved as run (a saved config with no head there is
        one of ledsim before the pan-tilt default: :meth:`from_dict` reads it as the
        yaw gimbal)."""
        out = {name: getattr(getattr(self, part), name) for name, part in FLAT.items()}
        if self.link != "paper":
            out["gimbal"], out["receiver"] = self.world.head
        return out

    def _same_run(self) -> tuple:
        """What makes two specs the same run: every flat name, the head as run."""
        flat = {**self.flat(), "gimbal": self.world.head[0], "receiver": self.world.head[1]}
        return tuple(sorted(flat.items()))

    def __eq__(self, other) -> bool:
        """Two specs are equal when they are the same run: a head left to its default
        equals that head named (``RunSpec(link="luma")`` is the pan-tilt's)."""
        return isinstance(other, RunSpec) and self._same_run() == other._same_run()

    def __hash__(self) -> int:
        return hash(self._same_run())

    def validate(self) -> None:
        """Raise :class:`LedsimError` naming the first choice or value not allowed."""
        validate_run(self)

    @property
    def data_bit_rate(self) -> float:
        """The data's bit rate [bit/s]: ``bit_rate``, or the link preset's."""
        return preset_named(self.link).bit_rate if self.bit_rate is None else self.bit_rate

    @property
    def scenario_spec(self) -> Scenario:
        """The scenario, started at ``initial_angle`` (at rest) when one is set, and
        without a warm-up under the ``minimum-time`` acquisition."""
        spec = PHYSICS_SCENARIOS[self.scenario]
        if self.initial_angle is not None:
            spec = replace(spec, x0=(float(self.initial_angle), 0.0))
        if self.fast_acquisition:
            spec = replace(spec, warmup=0.0)
        return spec

    @property
    def fast_acquisition(self) -> bool:
        """The ``minimum-time`` acquisition runs: asked for, supervised, the law tracks
        the beam, and peak SNR >= :data:`MIN_FAST_PEAK_SNR` (but for the oracle)."""
        return (self.acquisition == "minimum-time" and self.supervision
                and PHYSICS_SCENARIOS[self.scenario].law.tracks_beam
                and (self.estimator == "oracle" or peak_snr(
                    self.world_config().constants, self.noise_scale) >= MIN_FAST_PEAK_SNR))

    @property
    def steady_from(self) -> float:
        """Start of the steady-state window [s]: the scenario's, or the second half of a
        run too short for it (so its RMSE is not empty)."""
        spec = self.scenario_spec
        return spec.steady_from if self.run_seconds > spec.steady_from else \
            0.5 * self.run_seconds

    @property
    def station_keeps(self) -> bool:
        """The vehicle keeps station: asked for, and no current says ``hold=0``."""
        return self.station_keeping and not any(
            getattr(parse_disturbance(d), "hold", 1.0) == 0.0 for d in self.disturbances)

    @property
    def run_seconds(self) -> float:
        """The run's length [s]: ``seconds``, or the scenario's; with a mission, long
        enough to fly it and hold the last waypoint :data:`MISSION_HOLD`."""
        if self.seconds is not None:
            return self.seconds
        mission = self.mission_plan
        if mission is not None:
            hold = self._plan.hold if self._plan is not None else MISSION_HOLD
            return max(self.scenario_spec.seconds, mission.duration + hold)
        return self.scenario_spec.seconds

    @property
    def mission_plan(self):
        """The path the receiver's vehicle flies (:class:`~ledsim.agent.guidance.
        Mission`): a mission scenario's, or the ``mission`` file's (None: it keeps
        station)."""
        if self._plan is not None:
            return self._plan.mission
        if self.mission is not None:
            from ledsim.agent.guidance import Mission

            return Mission.from_file(self.mission)
        return None

    @property
    def _plan(self):
        """A mission scenario's node and path on a physical link (None: not one)."""
        scenario = MISSION_SCENARIOS.get(self.scenario)
        if scenario is None or self.link == "paper":
            return None
        return scenario.plan(self.distance, self.seconds)

    def world_config(self, distance: float | None = None) -> WorldConfig:
        """The MuJoCo world of the run (at ``distance`` [m] instead, when given)."""
        plan = self._plan
        led = None if plan is None else (plan.led_yaw, plan.led_pitch)
        return self.world.world_config(distance, led=led)


def _flat_reader(part: str, name: str) -> property:
    def read(self):
        return getattr(getattr(self, part), name)

    return property(read, doc=f"``{part}.{name}`` (see :class:`{PARTS[part].__name__}`)")


for _name, _part in FLAT.items():
    setattr(RunSpec, _name, _flat_reader(_part, _name))

#: The former name of :class:`RunSpec` (an alias: ``RunConfig(estimator="ekf")``).
RunConfig = RunSpec
