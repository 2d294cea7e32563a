"""What each step of a run was, for judging its estimate and its losses: the silent
errors (a wrong estimate not flagged), the losses declared, the false ones (declared
while the data still explained the estimate) and the re-seeds. The whole run's metrics
(:mod:`ledsim.loop.run_metrics`) and each window's (:mod:`ledsim.loop.windows`) count them
from one :class:`StepFlags`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: An estimate of phi this far off [rad] with the lost flag down is a silent error.
SILENT_ERROR = 0.2
#: A loss declared while the estimator's own phi was within this of the truth [rad]
#: (and the link was possible and unshaded) was a false one.
FALSE_LOSS_ERROR = 0.1


@dataclass
class StepFlags:
    """What each step of a run was, for the whole run's metrics and each window's
    (arrays of the run's length).

    Attributes:
        error: the reported estimate of phi less the truth [rad].
        lost: the supervisor flagged the link lost.
        counted: after the warm-up (silent errors are counted there).
        silent: the reported phi more than SILENT_ERROR off, the flag down, counted.
        onset: a loss declared at this step (not the run's opening acquisition).
        false_onset: an onset while the geometry allowed the link, no occluder shaded a
            photodiode and the estimator's own phi was within FALSE_LOSS_ERROR.
        reseeded: the supervisor restarted the estimator at this step.
    """

    error: np.ndarray
    lost: np.ndarray
    counted: np.ndarray
    silent: np.ndarray
    onset: np.ndarray
    false_onset: np.ndarray
    reseeded: np.ndarray


def loss_onsets(lost: np.ndarray) -> np.ndarray:
    """The steps at which ``lost`` rises, but for a loss on from the first step (the
    run's opening acquisition)."""
    lost = np.asarray(lost, dtype=bool)
    onset = np.zeros(len(lost), dtype=bool)
    onset[1:] = lost[1:] & ~lost[:-1]
    return onset


def step_flags(x: np.ndarray, xhat: np.ndarray, layout, Te: float, warmup: float = 0.0,
               lost: np.ndarray | None = None, own: np.ndarray | None = None,
               possible: np.ndarray | None = None, shaded: np.ndarray | None = None,
               reseeded: np.ndarray | None = None) -> StepFlags:
    """:class:`StepFlags` of a run: true and reported states ``x``, ``xhat`` (N, n)
    [rad, rad/s] of the receiver ``layout``, step ``Te`` [s], the warm-up [s], the
    supervisor's lost flags (None: not supervised), the estimator's own estimates
    (None: the reported ones), whether the geometry allowed a link and whether an
    occluder shaded any photodiode (None: always, never), and the re-seeds (None:
    none)."""
    n = len(x)
    error = layout.pointing_error(xhat, x)
    flagged = np.zeros(n, bool) if lost is None else np.asarray(lost, dtype=bool)
    counted = np.arange(n) * Te >= warmup
    silent = (np.abs(error) > SILENT_ERROR) & ~flagged & counted
    onset = loss_onsets(flagged)
    own_error = error if own is None else layout.pointing_error(own, x)
    clear = np.ones(n, bool) if possible is None else np.asarray(possible, dtype=bool)
    if shaded is not None:
        clear = clear & ~np.asarray(shaded, dtype=bool)
    false_onset = onset & clear & (np.abs(own_error) <= FALSE_LOSS_ERROR)
    return StepFlags(error, flagged, counted, silent, onset, false_onset,
                     np.zeros(n, bool) if reseeded is None
                     else np.asarray(reseeded, dtype=bool))
