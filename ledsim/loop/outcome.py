"""What one closed-loop run gives back: its trace and its :class:`RunOutcome`."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import NamedTuple

import numpy as np

from ledsim.agent.laws import receiver_peak
from ledsim.constants import LinkConstants
from ledsim.files.results import DictAccess
from ledsim.loop.pcrb_runs import run_terms
from ledsim.loop.run_metrics import RunMetrics, availability_mask, run_metrics, step_flags
from ledsim.loop.windows import WindowMetrics, horizontal_rms, window_metrics
from ledsim.physics.layout import ReceiverLayout
from ledsim.radiometry import optics
from ledsim.radiometry.goodput import goodput
from observer.pcrb import BoundError


@dataclass
class Trace(DictAccess):
    """Time series of one run, one row per control step.

    Attributes:
        t [s]; x, xhat: true and estimated (phi [rad], phidot [rad/s]); power,
        power_clean (N, n_pd) [W]; torque [N m]; occluded (N, n_pd): any aperture ray
        blocked; lost (N,): the supervisor did not trust the estimate; acquiring (N,):
        its acquisition scan had the motor; given: what the estimator was given (None:
        not kept; :mod:`ledsim.loop.given`), series by name; layout: the receiver that
        names the state's and the powers' series (None: the paper's); own: the
        estimator's own estimate where ``xhat`` holds the held one while lost, and
        xhat_std the reported estimate's standard deviation (NaN: unknown) (None: not
        kept).
    """

    t: np.ndarray
    x: np.ndarray
    xhat: np.ndarray
    power: np.ndarray
    power_clean: np.ndarray
    torque: np.ndarray
    occluded: np.ndarray
    lost: np.ndarray | None = None
    acquiring: np.ndarray | None = None
    given: dict | None = None
    layout: ReceiverLayout | None = None
    own: np.ndarray | None = None
    xhat_std: np.ndarray | None = None

    def series(self) -> dict[str, np.ndarray]:
        """The trace as 1-D arrays in SI units, one row per control step: ``t`` [s],
        ``phi``, ``phi_hat`` [rad], ``phidot``, ``phidot_hat`` [rad/s], ``p1``, ``p2``
        (measured powers [W]), ``torque`` [N m], ``lost`` (bool); when kept, the
        estimator's own estimates ``phi_own``, ``phidot_own`` and the reported ones'
        standard deviations ``phi_hat_std``, ``phidot_hat_std`` (NaN: unknown); and what
        the estimator was given (:meth:`ledsim.loop.given.GivenRecord.series`)."""
        n = len(self.t)
        lost = np.zeros(n, dtype=bool) if self.lost is None else np.asarray(self.lost)
        lay = LinkConstants().layout if self.layout is None else self.layout
        extra = {}
        if self.own is not None:
            extra.update(lay.state_columns(self.own, "_own"))
        if self.xhat_std is not None:
            extra.update(lay.state_columns(self.xhat_std, "_hat_std"))
        return {"t": self.t, **lay.state_columns(self.x), **lay.state_columns(self.xhat, "_hat"),
                **lay.power_columns(self.power), "torque": self.torque,
                "lost": lost, **extra, **(self.given or {})}


@dataclass
class RunOutcome(DictAccess):
    """One seed: its metrics, the estimator's cost [us per step], the loop's real-time
    factor [-], the trace when asked for, the metrics of each window when asked for
    (:class:`~ledsim.loop.windows.WindowMetrics`), and whether the vehicle kept station
    (False: it drifted, or the scene has no vehicle), and the terms of its posterior
    Cramér-Rao bound (:func:`ledsim.loop.pcrb_runs.run_terms`; None: the model has no process
    noise)."""

    metrics: RunMetrics
    us_per_step: float
    realtime_factor: float
    trace: Trace | None = None
    windows: list[WindowMetrics] | None = None
    station_keeping: bool | None = None
    bound: dict | None = None


class Navigation(NamedTuple):
    """A run's vehicle, step by step: the true hull position (N, 3) [m], its station
    (3,) [m] and the navigated position (N, 3) [m]."""

    hull: np.ndarray
    station: np.ndarray
    navigated: np.ndarray


def achievable_power(res, c) -> np.ndarray:
    """Most the reference photodiode could receive at each step of ``res`` [W]: the
    transmitter gain of that moment's distance and LED angle, times the receiver's peak
    response."""
    lay = c.layout
    return optics.achievable_power(lay.reference_power(res.distance),
                                   lay.reference_power(res.emission_angle), c,
                                   receiver_peak(c))


@dataclass
class RunRecord:
    """What one closed-loop run recorded, for its :func:`outcome`.

    Attributes:
        result: the world's series (:class:`~ledsim.physics.simulation.SimResult`).
        xhat: the estimate the run reports each step (held while lost), ``(T, n)``.
        flags: (lost, acquiring) per step, ``(T, 2)``.
        disturbances: the run's disturbances (the first transient one times the event).
        supervised: whether a supervisor flagged losses.
        spent: seconds spent controlling [s].
        navigation: the vehicle's :class:`Navigation` (None: no vehicle).
        station_keeping: whether the vehicle kept station (None: no vehicle).
        given: what the estimator was given, per series (None: not kept).
        noise: the run's measurement noise (None: the link's at the run's noise scale).
        bound_inputs: (the estimators' model, the input u each step told them
            [rad/s^2], the samples the gate passed) for the bound (None: none).
        outside: the steps whose estimator was outside its training box (None: none).
        medium: the water's factor on the reference photodiode's power each step
            (scintillation; None: 1).
        own: the estimator's own estimates where ``xhat`` holds the held ones while lost
            (None: ``xhat``).
        reseeded: the steps the supervisor restarted the estimator (None: none).
        xhat_std: the reported estimate's standard deviation per step (NaN where
            unknown; None: not kept).
    """

    result: object
    xhat: np.ndarray
    flags: np.ndarray
    disturbances: list
    supervised: bool
    spent: float
    navigation: Navigation | None = None
    station_keeping: bool | None = None
    given: dict | None = None
    noise: object = None
    bound_inputs: tuple | None = None
    outside: np.ndarray | None = None
    medium: np.ndarray | None = None
    own: np.ndarray | None = None
    reseeded: np.ndarray | None = None
    xhat_std: np.ndarray | None = None


class Judging(NamedTuple):
    """What a run is judged by, beyond its record: the measurement noise's scale [-],
    the data's bit rate [bit/s], the warm-up [s] and the start of the steady window
    [s] (the builder takes them from the run's spec)."""

    noise_scale: float
    bit_rate: float
    warmup: float
    steady_from: float


def outcome(record: RunRecord, judging: Judging, constants, wall: float, keep_trace: bool,
            window: float | None = None) -> RunOutcome:
    """A run's :class:`RunOutcome` from its :class:`RunRecord`, what it is ``judging``
    by, its link ``constants``, the wall time it took [s], whether to keep its trace,
    and the window [s] of per-window metrics (None: none)."""
    r = record
    res, xhat, disturbances, supervised = r.result, r.xhat, r.disturbances, r.supervised
    navigation, given, noise, bound_inputs = r.navigation, r.given, r.noise, r.bound_inputs
    outside, medium, own, reseeded = r.outside, r.medium, r.own, r.reseeded
    flags, spent, station_keeping, xhat_std = r.flags, r.spent, r.station_keeping, r.xhat_std
    events = [d for d in disturbances if d.event_end is not None]
    flags = flags.reshape(-1, 2)
    best = achievable_power(res, constants)
    if medium is not None:  # the medium's fading (scintillation) is not a pointing loss
        best = best * medium
    noise = constants.measurement_noise(judging.noise_scale) if noise is None else noise
    bound = None
    if bound_inputs is not None and len(res.t):
        model, u, measured = bound_inputs
        try:
            bound = run_terms(res, u, measured, model, constants, noise)
        except BoundError:
            bound = None  # no process noise: the bound is not defined
    noise_model, bit_rate = noise, judging.bit_rate
    noise = noise.std
    lay, warmup = constants.layout, judging.warmup
    _, possible = availability_mask(lay.reference_power(res.power_clean), best, noise)
    steps = step_flags(res.x, xhat, lay, constants.Te, warmup,
                       flags[:, 0] if supervised else None, own, possible,
                       np.asarray(res.occluded).reshape(len(res.t), -1).any(axis=1),
                       reseeded)
    metrics = run_metrics(res.x, xhat, res.power_clean, judging.steady_from,
                          constants, events[0].event_end if events else None,
                          lost=flags[:, 0] if supervised else None,
                          event_start=events[0].start if events else None,
                          power_max=best, noise_std=noise,
                          warmup=warmup,
                          occluded=constants.layout.reference_power(res.occluded),
                          outside=outside, noise=noise_model, bit_rate=bit_rate,
                          steps=steps,
                          withheld=None if bound_inputs is None else
                          ~np.asarray(bound_inputs[2]).reshape(len(res.t), -1).all(axis=1))
    if len(res.t):  # the data delivered, on the data detector
        held = ~flags.any(axis=1) if supervised else None
        delivered = goodput(lay.reference_power(res.power_clean), best, noise_model,
                            constants.Te, bit_rate, held, lay.reference_power(res.distance))
        for key, value in asdict(delivered).items():
            setattr(metrics, key, value)
    nav = navigation
    if nav is not None and len(res.t):
        metrics.hull_error_rms = horizontal_rms(nav.hull, nav.station)
        metrics.navigation_error_rms = horizontal_rms(nav.navigated, nav.hull)
    windows = None if window is None else window_metrics(
        constants.layout.reference_power(res.power_clean), best, noise, constants.Te, window,
        *(() if nav is None else nav), noise=noise_model, bit_rate=bit_rate, steps=steps)
    trace = Trace(res.t, res.x, xhat, res.power, res.power_clean, res.torque,
                  res.occluded, flags[:, 0], flags[:, 1], given,
                  constants.layout, own, xhat_std) if keep_trace else None
    return RunOutcome(metrics, 1e6 * spent / len(res.t) if len(res.t) else 0.0,
                      res.t[-1] / wall if len(res.t) else 0.0, trace, windows,
                      station_keeping, bound)
