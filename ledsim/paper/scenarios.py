"""Paper section 4 scenarios on the closed-form model, and the loop that runs them.

Inputs are read as angular accelerations [rad/s^2] with t = k Te [s] (``docs/model.md``):

==============  ======================================  ===================
scenario        input u_k                               initial state x0
==============  ======================================  ===================
open-loop       0                                       (-0.2 rad, 0.02 rad/s)
if1             0.1 cos(5 t)                            (-0.2 rad, 0.02 rad/s)
if2             0.1 cos(5 t) + 0.2 sin(5 t)             (-0.2 rad, -0.02 rad/s) [#]_
closed-loop     -0.001 x_hat2                           (0.2 rad, 0 rad/s): the reference
==============  ======================================  ===================

Every run lasts 20 s (2000 steps); the steady-state window starts at 10 s.

.. [#] the sine term adds a mean rate of 0.2/5 = 0.04 rad/s; starting at -0.02 rad/s
   keeps the mean rate at +0.02 rad/s as in the other scenarios, inside the domain.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ledsim.agent.laws import Excitation, PaperRateDamping
from ledsim.agent.step import ControlStep, DirectInput, Unsupervised, identity_gate
from ledsim.errors import LedsimError
from ledsim.experiment.scenario import Scenario
from ledsim.files.results import DictAccess
from observer.estimator import Estimator
from observer.system import DiscreteSystem

# Paper Table 1 / Table 2 RMSE: (x1 [rad], x2 [rad/s], y1 [W], y2 [W]).
PAPER_TABLE1 = {
    "open-loop": (5.2e-3, 19.2e-3, 8.8e-3, 13.6e-3),
    "if1": (7.2e-3, 51.8e-3, 11.6e-3, 19.3e-3),
    "if2": (5.7e-3, 50.3e-3, 1.73e-3, 2.5e-3),
    "closed-loop": (6.3e-3, 22e-3, 8.4e-3, 16.7e-3),
}
PAPER_TABLE2 = {
    ("if1", 0.085): (7.4e-3, 51.7e-3, 11.6e-3, 19.3e-3),
    ("if1", 0.1): (6.9e-3, 45.6e-3, 7.8e-3, 13.4e-3),
    ("if1", 0.2): (5.7e-3, 50.3e-3, 1.73e-3, 2.54e-3),
    ("if2", 0.085): (6.64e-3, 40.1e-3, 13.0e-3, 15.6e-3),
    ("if2", 0.1): (5.7e-3, 31.5e-3, 6.8e-3, 10.9e-3),
    ("if2", 0.2): (7.3e-3, 24.7e-3, 2.2e-3, 3.1e-3),
    ("closed-loop", 0.085): (6.3e-3, 22.0e-3, 8.4e-3, 16.7e-3),
    ("closed-loop", 0.1): (4.9e-3, 43.3e-3, 5.1e-3, 9.5e-3),
    ("closed-loop", 0.2): (5.4e-3, 30.9e-3, 1.6e-3, 2.5e-3),
}

PAPER_SCENARIOS = {
    s.name: s for s in (
        Scenario("open-loop", (-0.2, 0.02), Excitation(), 20.0, 10.0,
                 description="no input"),
        Scenario("if1", (-0.2, 0.02), Excitation(cos_amp=0.1), 20.0, 10.0,
                 description="u = 0.1 cos(5 t)"),
        Scenario("if2", (-0.2, -0.02), Excitation(cos_amp=0.1, sin_amp=0.2), 20.0, 10.0,
                 description="u = 0.1 cos(5 t) + 0.2 sin(5 t)"),
        Scenario("closed-loop", (0.2, 0.0), PaperRateDamping(0.001), 20.0, 10.0,
                 description="u = -0.001 phidot_hat"),
    )
}
#: Former name of the registry.
SCENARIOS = PAPER_SCENARIOS


def get_scenario(name: str) -> Scenario:
    if name not in PAPER_SCENARIOS:
        raise LedsimError(f"unknown scenario {name!r}: choose one of "
                          f"{', '.join(PAPER_SCENARIOS)}")
    return PAPER_SCENARIOS[name]


@dataclass
class Noise:
    """Pre-drawn noise of one seed, shared by every estimator run on that seed."""

    process: np.ndarray  # (N, n)
    measurement: np.ndarray  # (N, p)

    @classmethod
    def draw(cls, system: DiscreteSystem, n_steps: int, seed: int) -> Noise:
        rng = np.random.default_rng(seed)
        return cls(rng.standard_normal((n_steps, system.n_state)) * system.process_noise_std,
                   rng.standard_normal((n_steps, system.n_output)) * system.measurement_noise_std)


@dataclass
class Trajectory(DictAccess):
    """One closed-form run. Arrays have one row per step.

    Attributes:
        x: true state (rad, rad/s); xhat: estimate; y: measured powers [W];
        y_clean: noise-free h(x) [W]; yhat: h(x_hat) [W]; u: input [rad/s^2];
        seconds: wall time spent in the estimator [s].
    """

    x: np.ndarray
    xhat: np.ndarray
    y: np.ndarray
    y_clean: np.ndarray
    yhat: np.ndarray
    u: np.ndarray
    seconds: float


def run(system: DiscreteSystem, scenario: Scenario, estimator: Estimator, noise: Noise,
        x0_guess=None, dropout: np.ndarray | None = None) -> Trajectory:
    """Simulate the closed-form plant with ``estimator`` in the loop.

    ``dropout``: optional boolean (N, p) mask of measurements replaced by NaN.
    """
    N = scenario.n_steps(system.Te)
    if len(noise.measurement) < N:
        raise LedsimError(f"noise has {len(noise.measurement)} steps, the scenario {N}")
    n, p = system.n_state, system.n_output
    x = np.asarray(scenario.x0, dtype=float)
    xs, xhats = np.empty((N, n)), np.empty((N, n))
    ys, us = np.empty((N, p)), np.empty(N)
    estimator.reset(x0_guess)
    step = ControlStep(identity_gate, Unsupervised(estimator), scenario.law,
                       system.constants, DirectInput(), scenario.warmup)
    spent = 0.0
    for k in range(N):
        xs[k] = x
        y = system.h(x) + noise.measurement[k]
        if dropout is not None:
            y = np.where(dropout[k], np.nan, y)
        ys[k] = y
        t0 = time.perf_counter()
        u = float(step(y, k * system.Te))
        spent += time.perf_counter() - t0
        xhats[k] = step.decision.xhat
        us[k] = u
        x = system.f(x, u) + noise.process[k]
    return Trajectory(xs, xhats, ys, system.h(xs), system.h(xhats), us, spent)
