"""The closed-form tables against the posterior Cramér-Rao bound (:mod:`observer.pcrb`),
and the pointing loss of a receiver pointed by the estimate."""

from __future__ import annotations

import numpy as np

from ledsim.agent.laws import intensity_maximum, receiver_peak
from ledsim.paper.model import LEDLinkModel
from ledsim.paper.scenarios import Trajectory
from ledsim.radiometry.optics import receiver_response
from observer.metrics import pointing_loss_db
from observer.pcrb import (
    BoundTerms,
    bound_against,
    box_prior,
    process_information,
    trajectory_terms,
)

#: The tables' two state keys.
STATE_KEYS = ("x1", "x2")


def pointing_loss(system: LEDLinkModel, x: np.ndarray, xhat: np.ndarray) -> float:
    """The mean pointing loss [dB] of a receiver pointed by the estimate: the gimbal
    turned so that the estimated phi sits at the intensity maximum phi* leaves the true
    phi at phi* + phi - phi_hat, and photodiode 1 receives g(phi* + phi - phi_hat)
    where g(phi*) was possible. (In the open-loop scenarios nothing is pointed: this is
    what the estimate would cost a receiver that were.)"""
    c = system.constants
    lay = c.layout
    received = receiver_response(intensity_maximum(c) + lay.angle(x) - lay.angle(xhat),
                                 c.receiver)
    return pointing_loss_db(np.full(len(received), receiver_peak(c)), received)


def bound_terms(system: LEDLinkModel, out: Trajectory) -> BoundTerms:
    """The PCRB's terms along one closed-form run's true trajectory and inputs."""
    return trajectory_terms(system.f_jacobian(out.x, out.u[:, None]), system.h_jacobian(out.x),
                            system.measurement_noise_std**2,
                            process_information(system.process_noise_std))


def bound_stats(seed_metrics: list[dict], system, steady: int) -> dict:
    """The bound's steady root and the estimator's RMSE over it, from its seeds' metrics
    (each with its ``bound`` terms and ``rmse_steady``)."""
    bound, ratio, err = bound_against([m["bound"] for m in seed_metrics],
                                      box_prior(system.domain_halfwidth), steady,
                                      [m["rmse_steady"][:2] for m in seed_metrics])
    return {"pcrb_steady_x1": float(bound[0]), "pcrb_steady_x2": float(bound[1]),
            "rmse_over_pcrb": dict(zip(STATE_KEYS, ratio.tolist(), strict=True)),
            "rmse_over_pcrb_err": dict(zip(STATE_KEYS, err.tolist(), strict=True))}


