"""What a closed-loop run is judged by: estimation error, alignment, link availability."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from ledsim.agent.laws import intensity_maximum
from ledsim.constants import LinkConstants
from ledsim.files.results import DictAccess
from ledsim.loop.losses import StepFlags, step_flags
from ledsim.radiometry.data_channel import BIT_RATE, link_budget_of
from ledsim.radiometry.optics import peak_power
from observer.metrics import pointing_loss_db, rmse
from observer.noise import MeasurementNoise

ALIGN_TOLERANCE = math.radians(1.0)  # |phi - phi_ref| below this counts as aligned [rad]
#: The link is available while P1 >= 90% of its maximum: a pointing loss of at most
#: 10 log10(1/0.9) = 0.46 dB, which the paper's main lobe (c1 = 0.30 rad) gives at a
#: pointing error of c1 sqrt(ln(1/0.9)) = 0.097 rad, several times the estimators'
#: steady RMSE: availability barely sees estimation error (pointing_loss_db does).
AVAILABILITY_LEVEL = 0.9
#: The geometry allows a link while the most P1 could receive is at least this many
#: noise standard deviations (6 dB; the peak at 0.3 m, the far end of the served range,
#: is 2.5): below it, 90% of next to nothing is not a link.
GEOMETRY_SNR = 2.0
#: Recovery: the first time after an event from which the link is available in this
#: share of a RECOVERY_WINDOW, or in 0.9 of the share it had in the second before the
#: event if that was lower (a vibrating hull never reaches 0.8, the oracle included).
RECOVERY_SHARE = 0.8
RECOVERY_WINDOW = 0.5  # [s]
RECOVERY_FLOOR = 0.2  # the least share that counts as a link back


@dataclass
class RunMetrics(DictAccess):
    """Metrics of one run.

    Attributes:
        rmse, rmse_steady: RMSE of (x1 [rad], x2 [rad/s]) over the run and from the
            scenario's steady-state start, keyed ``x1``, ``x2`` (the first axis's angle
            and rate); on a pan-tilt head also per axis, ``azimuth``, ``elevation``
            [rad], ``azimuth_rate``, ``elevation_rate`` [rad/s], and ``pointing``, the
            RMS angle between the estimated and the true direction [rad].
        alignment_time: first time |phi - phi_ref| < 1 deg for 0.5 s [s] (None: never).
        availability: share of the run with P1 >= 90% of the most it could receive at
            that moment's geometry (distance and LED angle; a perfectly pointed
            photodiode 1), counting only steps whose geometry allows a link [-].
        geometry_share: share of the run whose geometry allows a link at all: the most
            P1 could receive is at least GEOMETRY_SNR noise standard deviations [-].
        mean_power: mean noise-free P1 [W].
        recovery_time: after a transient event (an occlusion, a kick) ends, the time
            until the link is back: available in RECOVERY_SHARE of a RECOVERY_WINDOW, or
            in 0.9 of its share over the second before the event if that was lower [s];
            None without such an event or without recovery.
        lost_share: share of the run the supervisor flagged the link lost [-].
        silent_error_share: share of the run after the warm-up in which the estimate
            of phi is more than SILENT_ERROR off and the link is not flagged lost: a
            confident wrong answer [-].
        hull_error_rms: the hull's horizontal distance from its station (the true pose
            against the start's), RMS over the run [m] (None: no vehicle).
        navigation_error_rms: the navigation's horizontal error (navigated against true
            position), RMS over the run [m] (None: no vehicle).
        link_events: each loss of the link as ``[t_lost, t_recovered]`` [s]
            (``t_recovered`` None when the run ended lost).
        detection_delay: from the start of a transient event to the first loss flagged
            that is still on at its start or begins after it [s] (0 when flagged
            before the start; None: no event, or no loss flagged).
        held_delay: from the start of a transient event to the first step at which the
            loop stopped taking the powers at their word: the dropout gate withheld a
            sample (an occluder: the estimate is held on the encoder) or a loss was
            flagged [s] (0 when already so at the start; None: no event, none, or the
            gate's record not kept). An occlusion shorter than the gate's hold is never
            a loss, but is held from here.
        snr_db, ber, throughput_bps, fec_share: the link budget of on-off keyed data
            on photodiode 1 (:mod:`ledsim.radiometry.data_channel`: SNR [dB], bit error rate [-],
            bits delivered under the FEC limit per second [bit/s], share of the run
            under it [-]).
        pointing_loss_db: the mean pointing loss after the warm-up: 10 log10 of the P1
            the geometry allowed over the P1 received, each summed over the steps whose
            geometry allows a link and whose photodiode 1 no occluder shades [dB]
            (:func:`observer.metrics.pointing_loss_db`). Availability tolerates a loss
            of 10 log10(1/0.9) = 0.46 dB at a step; this one counts every step's.
        outside_domain_share: share of the run after the warm-up in which the
            estimator said its estimate or its input was outside its training box (a
            learned observer extrapolating: ``Estimator.outside_domain``) [-].
        loss_events: losses the supervisor declared after the link was first acquired
            (a run that starts lost, acquiring, does not count its start) [-].
        false_loss_events: those of them declared while the geometry allowed the link
            (:func:`availability_mask`), no occluder shaded a photodiode, and the
            estimator's own estimate of phi was within FALSE_LOSS_ERROR of the truth:
            the data still explained the estimate [-].
        reseeds: times the supervisor restarted the estimator (re-seeded it from a fix
            of the beam or handed over after an acquisition, the run's first
            included) [-].
        goodput_bits, ideal_bits, outages, outage_s, range_m: the data delivered
            through the code while the link was held, what the same path pointed
            perfectly delivers [bit], the outages after the first acquisition and their
            length [s], and the range's [nearest, farthest] [m]
            (:mod:`ledsim.radiometry.goodput`; None without a link budget).
        edge_goodput_bits, edge_ideal_bits: those bits near the edge of the range the
            ideal delivers at, where the data can be lost [bit].
    """

    rmse: dict
    rmse_steady: dict
    alignment_time: float | None
    availability: float
    mean_power: float
    recovery_time: float | None
    lost_share: float = 0.0
    link_events: list = field(default_factory=list)
    detection_delay: float | None = None
    held_delay: float | None = None
    snr_db: float | None = None
    ber: float | None = None
    throughput_bps: float | None = None
    fec_share: float | None = None
    geometry_share: float = 1.0
    silent_error_share: float = 0.0
    hull_error_rms: float | None = None
    navigation_error_rms: float | None = None
    pointing_loss_db: float | None = None
    outside_domain_share: float = 0.0
    loss_events: int = 0
    false_loss_events: int = 0
    reseeds: int = 0
    goodput_bits: float | None = None
    ideal_bits: float | None = None
    outages: int | None = None
    outage_s: float | None = None
    range_m: list | None = None
    edge_goodput_bits: float | None = None
    edge_ideal_bits: float | None = None


def link_events(lost: np.ndarray, Te: float) -> list[list]:
    """Intervals where ``lost`` holds, as ``[t_lost, t_recovered or None]`` [s]."""
    flags = np.concatenate([[False], np.asarray(lost, dtype=bool), [False]])
    edges = np.flatnonzero(np.diff(flags.astype(int)))
    n = len(lost)
    return [[float(a * Te), None if b >= n else float(b * Te)]
            for a, b in zip(edges[::2], edges[1::2], strict=True)]


def first_settled(flags: np.ndarray, Te: float, hold: float = 0.5) -> float | None:
    """First time [s] from which ``flags`` stays true for ``hold`` s (None: never)."""
    n_hold = int(round(hold / Te))
    ok = np.asarray(flags, dtype=bool)
    if len(ok) < n_hold:
        return None
    run = np.convolve(ok.astype(int), np.ones(n_hold, dtype=int), mode="valid")
    idx = np.flatnonzero(run == n_hold)
    return None if idx.size == 0 else float(idx[0] * Te)


def availability_mask(p1: np.ndarray, power_max: np.ndarray, noise_std: float | None
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Per step: whether the link is available (P1 ``p1`` [W] at least
    AVAILABILITY_LEVEL of the most it could receive, ``power_max`` [W], in a geometry
    that allows a link) and whether the geometry allows one (``power_max`` at least
    GEOMETRY_SNR noise standard deviations ``noise_std`` [W]; None: always)."""
    floor = 0.0 if noise_std is None else GEOMETRY_SNR * noise_std
    possible = power_max >= floor
    return (p1 >= AVAILABILITY_LEVEL * power_max) & possible, possible


def run_metrics(x: np.ndarray, xhat: np.ndarray, power_clean: np.ndarray, steady_from: float,
                constants: LinkConstants, event_end: float | None = None,
                lost: np.ndarray | None = None,
                event_start: float | None = None,
                power_max: np.ndarray | None = None,
                noise_std: float | None = None, warmup: float = 0.0,
                occluded: np.ndarray | None = None,
                outside: np.ndarray | None = None, noise: MeasurementNoise | None = None,
                bit_rate: float = BIT_RATE, steps: StepFlags | None = None,
                withheld: np.ndarray | None = None) -> RunMetrics:
    """Metrics of one run from its true state, estimate and noise-free powers.

    Args:
        x, xhat: true and estimated state, shape (N, 2) [rad, rad/s].
        power_clean: noise-free powers, shape (N, 2) [W].
        steady_from: start of the steady-state window [s].
        constants: the link (for the alignment target and the peak power).
        event_end: end of a transient event [s] for the recovery time.
        lost: the supervisor's lost flag per step (None: not supervised).
        event_start: start of a transient event [s] for the detection delay.
        power_max: most P1 could receive at each step [W] (None: the peak at the
            configured distance, constant).
        noise_std: the sensor's noise [W] (None: no link budget).
        warmup: the scenario's warm-up [s] (silent errors and the pointing loss are
            counted after it).
        occluded: whether an occluder shades photodiode 1 at each step (None: never);
            the pointing loss leaves those steps out.
        outside: whether the estimator was outside its training box at each step
            (None: never).
        noise: the run's noise object, for a link budget whose noise depends on the
            signal (None: ``noise_std``'s); ``bit_rate``: the data's [bit/s].
        steps: what each step was (:func:`step_flags`, which judges the losses from
            the estimator's own estimates, the shading and the re-seeds; None: from
            ``lost`` and ``xhat`` alone, unshaded, no re-seeds).
        withheld: whether the dropout gate withheld a sample at each step (None: not
            kept), for ``held_delay``.
    """
    Te = constants.Te
    e = rmse(xhat, x)
    es = rmse(xhat, x, int(round(steady_from / Te)))
    lay = constants.layout
    if lay.n_axes == 1:
        aligned = np.abs(lay.angle(x) - intensity_maximum(constants)) < ALIGN_TOLERANCE
    else:  # the data detector on the boresight: its peak is straight ahead
        aligned = lay.pointing_error(np.zeros_like(x), x) < ALIGN_TOLERANCE
    p1 = lay.reference_power(power_clean)
    best = np.full(len(p1), peak_power(constants)) if power_max is None else power_max
    available, possible = availability_mask(p1, best, noise_std)
    recovery = None
    if event_end is not None:
        recovery = _recovery(available, Te, event_end,
                             event_start if event_start is not None else event_end)
    events = [] if lost is None else link_events(lost, Te)
    delay = held = None
    if event_start is not None:
        delay = _delay_from(events, event_start)
        if withheld is not None:
            untrusted = np.asarray(withheld, dtype=bool) | (False if lost is None else lost)
            held = _delay_from(link_events(untrusted, Te), event_start)
    if noise is None and noise_std is not None:
        noise = MeasurementNoise(noise_std)
    budget = {} if noise is None else asdict(link_budget_of(p1, noise, Te, bit_rate))
    if steps is None:
        steps = step_flags(x, xhat, lay, Te, warmup, lost, possible=possible)
    after = steps.counted
    silent = float(np.mean(steps.silent[after])) if after.any() else 0.0
    pointed = after & possible & (True if occluded is None else ~np.asarray(occluded))
    loss = pointing_loss_db(best, p1, pointed)
    return RunMetrics(
        rmse=_rmse_keys(e, xhat, x, lay, 0),
        rmse_steady=_rmse_keys(es, xhat, x, lay, int(round(steady_from / Te))),
        alignment_time=first_settled(aligned, Te),
        availability=float(np.mean(available)),
        mean_power=float(np.mean(p1)),
        recovery_time=recovery,
        lost_share=0.0 if lost is None else float(np.mean(lost)),
        link_events=events, detection_delay=delay, held_delay=held,
        geometry_share=float(np.mean(possible)),
        silent_error_share=silent, pointing_loss_db=None if math.isnan(loss) else loss,
        outside_domain_share=0.0 if outside is None or not after.any()
        else float(np.mean(np.asarray(outside)[after])),
        loss_events=int(steps.onset.sum()), false_loss_events=int(steps.false_onset.sum()),
        reseeds=int(steps.reseeded.sum()), **budget)


def _rmse_keys(e: np.ndarray, xhat: np.ndarray, x: np.ndarray, lay, start: int) -> dict:
    """The RMSE ``e`` of each state by name: ``x1`` and ``x2`` the first axis's angle
    [rad] and rate [rad/s]; on a pan-tilt head also ``azimuth``, ``elevation`` [rad],
    ``azimuth_rate``, ``elevation_rate`` [rad/s] and ``pointing`` [rad], the RMS of the
    angle between the estimated and the true direction (from step ``start``)."""
    n = lay.n_axes
    keys = {"x1": float(e[0]), "x2": float(e[n])}
    if n == 2:
        keys.update(azimuth=float(e[0]), elevation=float(e[1]), azimuth_rate=float(e[2]),
                    elevation_rate=float(e[3]))
        err = lay.pointing_error(np.asarray(xhat)[start:], np.asarray(x)[start:])
        keys["pointing"] = float(np.sqrt(np.mean(np.square(err)))) if err.size else math.nan
    return keys


def _delay_from(events: list, start: float) -> float | None:
    """From ``start`` [s] to the first of ``events`` (``[t_on, t_off]``, ``t_off`` None
    while on) still on at it or after it [s]: 0 if already on before it (an occluder's
    edge dims the beam before its nominal start); None: none."""
    after = [a for a, b in events if b is None or b > start + 1e-9]
    return max(after[0] - start, 0.0) if after else None


def _recovery(available: np.ndarray, Te: float, end: float, start: float) -> float | None:
    """Time [s] from ``end`` to the first RECOVERY_WINDOW in which the link is available
    in RECOVERY_SHARE of the steps, or in 0.9 of its share over the second before
    ``start`` if that was lower, but never less than RECOVERY_FLOOR (None: never)."""
    k0, k1 = int(round(max(start - 1.0, 0.0) / Te)), int(round(start / Te))
    before = float(np.mean(available[k0:k1])) if k1 > k0 else 1.0
    share = min(RECOVERY_SHARE, max(0.9 * before, RECOVERY_FLOOR))
    n = max(1, int(round(RECOVERY_WINDOW / Te)))
    after = available[int(round(end / Te)):].astype(float)
    if len(after) < n:
        return None
    ok = np.flatnonzero(np.convolve(after, np.ones(n), mode="valid") >= share * n - 1e-9)
    return None if ok.size == 0 else float(ok[0] * Te)
