"""The closed loop's registries: its scenarios, estimators and choices.

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

import functools

from ledsim.agent.laws import AlignmentPID, Excitation, PaperRateDamping
from ledsim.constants import LinkConstants
from ledsim.experiment.estimators import (
    COMPARED_ESTIMATORS as COMPARED_ESTIMATORS,  # alias, see below
)
from ledsim.experiment.estimators import LOOP_ESTIMATORS as LOOP_ESTIMATORS
from ledsim.experiment.scenario import Scenario
from ledsim.radiometry.optics import nominal_noise_std, peak_power

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
# LOOP_ESTIMATORS and COMPARED_ESTIMATORS are the estimator registry's
# (ledsim.experiment.estimators), imported here where they were first defined.
OMEGA_MODELS = ("identified", "simulator", "none")
FILTER_DISTANCES = ("configured", "nominal")
ACQUISITIONS = ("warm-up", "minimum-time")
#: The receiver's gimbal (``--gimbal``) and its photodiodes (``--receiver``), which go
#: together: the paper's yaw gimbal with its pair, or a pan-tilt head with a quad (a data
#: detector on the boresight and four pointing photodiodes turned in azimuth and
#: elevation: ``physics/layout.py:quad_layout``). Either flag alone sets the other.
GIMBALS = {"yaw": "pair", "pan-tilt": "quad"}
RECEIVERS = {receiver: gimbal for gimbal, receiver in GIMBALS.items()}
#: The head when neither flag is given, every link alike (the pan-tilt default of a
#: physical link waits for the two-axis supervisor: see docs/two_axes.md).
DEFAULT_GIMBAL = "yaw"


def head_of(gimbal: str | None, receiver: str | None) -> tuple[str, str]:
    """(gimbal, receiver) as run from the flags given (None: not given): either one
    given sets the other; neither, :data:`DEFAULT_GIMBAL` and its receiver."""
    if gimbal is not None:
        return gimbal, receiver or GIMBALS.get(gimbal, "pair")
    if receiver is not None:
        return RECEIVERS.get(receiver, DEFAULT_GIMBAL), receiver
    return DEFAULT_GIMBAL, GIMBALS[DEFAULT_GIMBAL]


#: The estimators a pan-tilt run takes: the shipped KKL (one per axis, on its pair's
#: ratios), the four-state filters on the head's model and the oracle.
TWO_AXIS_ESTIMATORS = ("kkl", "ekf", "ukf", "pf", "oracle")
#: Largest |initial angle| [rad] a run may start at: the LED must stay in front of the
#: photodiodes (|phi| < pi/2 with the photodiodes' offset to spare).
MAX_INITIAL_ANGLE = 1.4

#: Below this peak signal-to-noise ratio (the most one photodiode can see over the
#: noise's standard deviation) the pair of powers fixes the beam too poorly for the
#: ``minimum-time`` acquisition, and a run that asks for it acquires with the warm-up:
#: on ``docs/distance_grid.md``'s grid the fix lost to the warm-up from 0.26 m
#: (peak SNR 3.4; KKL 0.663 against 0.769, EKF 0.774 against 0.840) and beat it up to
#: 0.25 m (3.7; 0.855 against 0.729, 0.962 against 0.840) [-].
MIN_FAST_PEAK_SNR = 3.5

#: Below this peak signal-to-noise ratio a run is refused: the receiver is in the dark,
#: its best sample a millionth of the noise (``luma`` at 30 m in water of c = 16/m has
#: 1e-158, and the supervisor's noise prior overflowed). Links lost at twice their FEC
#: range keep 2e-4 or more (``docs/link_table.md``'s presets, c up to 16/m) [-].
MIN_RUN_PEAK_SNR = 1e-6


@functools.lru_cache(maxsize=64)
def peak_snr(constants: LinkConstants, noise_scale: float) -> float:
    """The most one photodiode can see at the configured distance over the noise's
    standard deviation, nominal times ``noise_scale`` [-]."""
    return peak_power(constants) / (nominal_noise_std(constants) * noise_scale)
