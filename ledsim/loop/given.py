"""What the estimator of a closed-loop run was given, kept with its trace so that the
run can be replayed (``ledsim replay``, :mod:`ledsim.loop.replay`).

Per control step: which samples the dropout gate withheld, the input u [rad/s^2] the
estimator was told (the motor's, the load's and the hull's parts), the hull's part of it,
whether the supervisor re-seeded the estimator, and the gain the powers were divided by.
With them, every call the estimator received (:mod:`observer.recording`) and the run's
configuration: enough to give a fresh estimator of the same kind the same calls.
"""

from __future__ import annotations

import json

import numpy as np

from observer.recording import RecordingEstimator


class GivenRecord:
    """The per-step part of the record, for a run of ``steps`` steps."""

    def __init__(self, steps: int):
        self.u_hull = np.zeros(steps)
        self.reseeded = np.zeros(steps, dtype=bool)
        self.gain = np.ones(steps)

    def take(self, k: int, step, los) -> None:
        """Step ``k`` of the :class:`~ledsim.agent.step.ControlStep` ``step`` (``los``: the
        vehicle's line of sight, None without the IMU)."""
        # the hull's part of u on one axis (a pan-tilt's loads are in its u already)
        self.u_hull[k] = getattr(los, "acceleration", 0.0)
        self.reseeded[k] = step.decision.reseeded
        self.gain[k] = step.supervisor.gain_ratio

    def series(self, estimator, header: dict, layout, u: np.ndarray, measured: np.ndarray
               ) -> dict[str, np.ndarray]:
        """The trace's series of what was given: the per-step ones (with the input ``u``
        [rad/s^2] and the samples the gate passed, ``measured``, that the run keeps for
        every run; ``layout``: the receiver's), the estimator's calls (when it recorded
        them: not the oracle's) and ``config``, the run's spec by its flat names
        (``header``) as JSON."""
        out = {**layout.power_columns(~measured, prefix="withheld_"),
               "u": u, "u_hull": self.u_hull, "reseeded": self.reseeded,
               "gain": self.gain, "config": np.array(json.dumps(header))}
        if isinstance(estimator, RecordingEstimator):
            out.update(estimator.record.arrays())
        return out
