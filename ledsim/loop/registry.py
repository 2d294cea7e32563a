"""The closed loop's registries: its scenarios, estimators and choices.

==================  ==========================================================
scenario            what happens
==================  ==========================================================
align               start misaligned (phi0 = 0.3 rad); cascade PI control to the peak
open-loop           start at phi0 = 0.3 rad; no input
if1, if2            start aligned; the paper's input functions as u [rad/s^2]
paper-closed-loop   start at 0.2 rad; the paper's u = -0.001 phidot_hat
flyby, flyby-5,     the vehicle flies past a seabed node, docks, or surveys over
flyby-15, dock,     it, under the alignment's control (physical links;
survey              :mod:`ledsim.loop.mission_scenarios`)
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
from ledsim.loop.mission_scenarios import MISSION_SCENARIOS
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
# The missions past a node: the alignment's law, the head pointed where the navigation
# puts the node; their length is the path's and its hold (RunSpec.run_seconds).
PHYSICS_SCENARIOS.update({
    name: Scenario(name, (0.0, 0.0), AlignmentPID(), 10.0, 5.0, warmup=1.0,
                   description=m.description)
    for name, m in MISSION_SCENARIOS.items()})
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
#: The head when neither flag is given on the paper's bench (``--link paper``), whose
#: photodiodes see no tilt: the paper's yaw gimbal with its pair.
DEFAULT_GIMBAL = "yaw"
#: The head when neither flag is given on a physical link: the pan-tilt with its quad,
#: which points at an LED above or below the receiver (docs/two_axes.md), unless the
#: run asks for what only the yaw gimbal runs (:func:`yaw_only`).
PHYSICAL_GIMBAL = "pan-tilt"


def default_gimbal(link: str) -> str:
    """The gimbal a run on ``link`` points when neither ``--gimbal`` nor ``--receiver``
    is given: :data:`DEFAULT_GIMBAL` on the paper's bench, :data:`PHYSICAL_GIMBAL` on a
    physical link."""
    return DEFAULT_GIMBAL if link == "paper" else PHYSICAL_GIMBAL


def head_of(gimbal: str | None, receiver: str | None,
            link: str = "paper") -> tuple[str, str]:
    """(gimbal, receiver) as run from the flags given (None: not given): either one
    given sets the other; neither, :func:`default_gimbal` of ``link`` and its receiver."""
    if gimbal is not None:
        return gimbal, receiver or GIMBALS.get(gimbal, "pair")
    if receiver is not None:
        return RECEIVERS.get(receiver, DEFAULT_GIMBAL), receiver
    default = default_gimbal(link)
    return default, GIMBALS[default]


def yaw_only(estimator: str, checkpoint: str | None) -> str | None:
    """Why a run with these choices needs the yaw gimbal (None: the pan-tilt takes
    them): an estimator the pan-tilt head does not run, or a KKL checkpoint that is not
    a pan-tilt pair's name (no NAME_azimuth and NAME_elevation beside it: a one-axis
    KKL). A physical-link run that names no head and asks for one of them runs the yaw
    gimbal (so every command of ledsim before the pan-tilt default still runs as it
    did)."""
    if estimator in LOOP_ESTIMATORS and estimator not in PAN_TILT_ESTIMATORS:
        return f"estimator {estimator} is one-axis"
    if checkpoint:
        from ledsim.files.resources import pair_paths

        if not all(p.is_file() for p in pair_paths(checkpoint).values()):
            return f"--checkpoint {checkpoint} is not a pan-tilt pair"
    return None


#: The estimators a pan-tilt run takes: the shipped KKL (one per axis, on its pair's
#: ratios), the four-state filters on the head's model and the oracle.
TWO_AXIS_ESTIMATORS = ("kkl", "ekf", "ukf", "pf", "oracle")
#: The field's one-photodiode baselines, which scan the head (pan-tilt runs only; not
#: among the estimators ``ledsim demo`` compares).
SCANNING_ESTIMATORS = ("es", "scan-ekf")
#: Every estimator a pan-tilt run takes.
PAN_TILT_ESTIMATORS = TWO_AXIS_ESTIMATORS + SCANNING_ESTIMATORS
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
