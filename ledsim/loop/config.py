"""What a closed-loop run in MuJoCo is: its scenarios and its configuration.

==================  ==========================================================
scenario            what happens
==================  ==========================================================
align               start misaligned (phi0 = 0.3 rad); cascade PI control to the peak
open-loop           start at phi0 = 0.3 rad; no input
if1, if2            start aligned; the paper's input functions as u [rad/s^2]
paper-closed-loop   start at 0.2 rad; the paper's u = -0.001 phidot_hat
==================  ==========================================================
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..config import LinkConstants
from ..control import AlignmentPID, Excitation, PaperRateDamping
from ..errors import LedsimError
from ..estimators import ESTIMATORS
from ..physics.disturbances import check_timing, parse_disturbance
from ..physics.scene import WorldConfig
from ..scenario import Scenario

PHYSICS_SCENARIOS = {
    s.name: s for s in (
        Scenario("align", (0.3, 0.0), AlignmentPID(), 10.0, 5.0, warmup=1.0,
                 description="start 0.3 rad off; cascade PI control to the intensity peak"),
        Scenario("open-loop", (0.3, 0.0), Excitation(), 10.0, 5.0,
                 description="start 0.3 rad off; no input"),
        Scenario("if1", (0.0, 0.0), Excitation(cos_amp=0.1), 10.0, 5.0,
                 description="start aligned; u = 0.1 cos(5 t)"),
        Scenario("if2", (0.0, 0.0), Excitation(cos_amp=0.1, sin_amp=0.2), 10.0, 5.0,
                 description="start aligned; u = 0.1 cos(5 t) + 0.2 sin(5 t)"),
        Scenario("paper-closed-loop", (0.2, 0.0), PaperRateDamping(), 10.0, 5.0,
                 description="start 0.2 rad off; u = -0.001 phidot_hat"),
    )
}
#: Estimators of the MuJoCo loop (``kkl-paper`` and ``kkl-handover`` exist for the
#: closed-form model only).
LOOP_ESTIMATORS = tuple(n for n in ESTIMATORS if n not in ("kkl-paper", "kkl-handover"))
OMEGA_MODELS = ("identified", "simulator", "none")


@dataclass
class RunConfig:
    """Everything one ``ledsim run`` needs (all plain data, so it pickles to workers).

    Attributes:
        scenario: a key of :data:`PHYSICS_SCENARIOS`.
        estimator: a key of :data:`LOOP_ESTIMATORS`.
        disturbances: disturbance specs ``name[:key=value,...]``.
        distance: link distance d [m].
        torque_limit: gimbal motor torque limit [N m].
        noise_scale: multiplies the measurement-noise standard deviation [-].
        seeds: Monte-Carlo runs (seeds 0..seeds-1).
        particles: particle-filter size.
        checkpoint: KKL checkpoint (None: the shipped one for the distance).
        omega_model: f of the KKL's Omega correction: the identified one-step model,
            the simulator itself, or none.
        workers: processes.
        seconds: length of a run [s] (None: the scenario's).
        scene: MJCF scene file (None: the shipped one).
        integrator: MuJoCo integrator of the world (``implicitfast`` or ``euler``, ...).
        supervision: watch the estimate, flag a lost link and reacquire it with a scan
            (:mod:`ledsim.loop.supervisor`); off: the estimator alone drives the motor.
    """

    scenario: str = "align"
    estimator: str = "kkl"
    disturbances: tuple[str, ...] = ()
    distance: float = 0.085
    torque_limit: float = 0.05
    noise_scale: float = 1.0
    seeds: int = 4
    particles: int = 2000
    checkpoint: str | None = None
    omega_model: str = "identified"
    workers: int = 2
    seconds: float | None = None
    scene: str | None = None
    supervision: bool = True
    integrator: str = "implicitfast"

    def validate(self) -> None:
        for flag, value, registry in (("scenario", self.scenario, PHYSICS_SCENARIOS),
                                      ("estimator", self.estimator, LOOP_ESTIMATORS),
                                      ("--omega-model", self.omega_model, OMEGA_MODELS)):
            if value not in registry:
                raise LedsimError(f"unknown {flag.lstrip('-')} {value!r}: choose one of "
                                  f"{', '.join(registry)}")
        checks = [("--distance", self.distance, self.distance > 0, "> 0 m"),
                  ("--torque-limit", self.torque_limit, self.torque_limit > 0, "> 0 N m"),
                  ("--seeds", self.seeds, self.seeds >= 1, ">= 1"),
                  ("--noise-scale", self.noise_scale, self.noise_scale > 0, "> 0"),
                  ("--particles", self.particles, self.particles >= 1, ">= 1")]
        if self.seconds is not None:
            checks.append(("--seconds", self.seconds, self.seconds > 0, "> 0 s"))
        for flag, value, ok, allowed in checks:
            if not (ok and math.isfinite(value)):
                raise LedsimError(f"{flag} {value!r} is not allowed: must be {allowed}")
        check_timing([parse_disturbance(d) for d in self.disturbances], self.run_seconds)

    @property
    def scenario_spec(self) -> Scenario:
        return PHYSICS_SCENARIOS[self.scenario]

    @property
    def run_seconds(self) -> float:
        return self.scenario_spec.seconds if self.seconds is None else self.seconds

    def world_config(self, distance: float | None = None) -> WorldConfig:
        """The MuJoCo world of the run (at ``distance`` [m] instead, when given)."""
        extra = {} if self.scene is None else {"xml": self.scene}
        d = self.distance if distance is None else distance
        return WorldConfig(constants=LinkConstants(distance=d),
                           torque_limit=self.torque_limit, integrator=self.integrator,
                           **extra)
