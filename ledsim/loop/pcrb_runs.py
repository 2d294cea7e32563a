"""The posterior Cramér-Rao bound of closed-loop runs (:mod:`observer.pcrb`).

The bound is computed from the model the estimators use: the identified one-step gimbal
model's f (its Jacobian along the run's true phi and phidot, with the input u the
estimator was told, the hull's part included) and its process noise Q; the photodiodes'
h with the transmitter gain and the visible share of that moment's true geometry (the
estimators track the gain, the bound is given it); the run's measurement noise R (the one
:class:`~observer.noise.MeasurementNoise`); and only the samples the dropout gate passed.

What it does not cover: the identified model's own error against MuJoCo (a bias no
estimator of that model can remove, so errors may sit above the bound for it), the
error of the hull's input (the IMU's noise enters u, not Q), and the encoder: the
supervisor carries the estimate on it through an occlusion, information the bound,
built on the photodiodes alone, does not count.
"""

from __future__ import annotations

import numpy as np

from ledsim.radiometry.optics import layout_power_jacobian, transmitter_gain
from observer.pcrb import bound_against, box_prior, process_information, trajectory_terms


def run_terms(res, u: np.ndarray, measured: np.ndarray, model, constants, noise) -> dict:
    """The bound's terms along one run (:meth:`BoundTerms.to_arrays`).

    Args:
        res: the run's :class:`~ledsim.physics.simulation.SimulationResult`.
        u: the input the estimator was told at each step [rad/s^2], (N,).
        measured: the samples the gate passed, (N, n_pd) bool.
        model: the estimators' :class:`~observer.system.DiscreteSystem` (its f and Q).
        constants: the link (the layout and the receiver's response).
        noise: the run's measurement noise.
    """
    x = res.x
    if constants.layout.n_axes == 2:
        # A pan-tilt head: its model's h along the true angles, scaled by each step's
        # transmitter gain and visible share over the model's (the distance's) gain.
        gain = transmitter_gain(res.distance, res.emission_angle, constants) * \
            res.visible_fraction
        scale = gain / float(transmitter_gain(np.array(constants.distance), 0.0, constants))
        H = model.h_jacobian(x) * scale[:, :, None]
        F = model.f_jacobian(x, u)
    else:
        # d(power_i)/d(state) at the true geometry: each photodiode's own transmitter
        # gain and visible share times the receiver's slope.
        gain = transmitter_gain(res.distance, res.emission_angle, constants) * \
            res.visible_fraction
        H = layout_power_jacobian(1.0, constants.layout.angle(x), constants) * \
            gain[:, :, None]
        F = model.f_jacobian(x, u[:, None])
    # A physical receiver's noise at each step's clean powers (the information a
    # signal-dependent variance itself carries is left out: it is small beside the mean's).
    var = noise.std_at(res.power_clean) ** 2 if noise.signal_dependent else \
        noise.std_at() ** 2
    terms = trajectory_terms(F, H, var,
                             process_information(model.process_noise_std), measured)
    # The estimators are not told the start: the prior is their training box's.
    return {**terms.to_arrays(), "prior": box_prior(model.domain_halfwidth)}


def bound_summary(outs, steady_step: int, estimates: bool = True) -> dict:
    """Over the seeds of one configuration: the root of the bound's mean over the
    steady window (``pcrb_steady_x1`` [rad], ``pcrb_steady_x2`` [rad/s]) and, when the
    runs ``estimates`` (not the oracle's, which reads the true state), the steady RMSE
    over it (``rmse_over_pcrb_x1``/``_x2``, with one Monte-Carlo standard error in
    ``rmse_over_pcrb_err_x1``/``_x2``). Empty when the runs have no bound (a model
    without process noise)."""
    kept = [o for o in outs if o.bound is not None]
    if not kept:
        return {}
    if "pointing" in kept[0].metrics.rmse_steady:
        return head_bound_summary(kept, steady_step, estimates)
    errs = np.array([[o.metrics.rmse_steady["x1"], o.metrics.rmse_steady["x2"]]
                     for o in kept], dtype=float)
    bound, ratio, err = bound_against([o.bound for o in kept], kept[0].bound["prior"],
                                      steady_step, errs)
    out = {"pcrb_steady_x1": float(bound[0]), "pcrb_steady_x2": float(bound[1])}
    if estimates and np.all(np.isfinite(ratio)):
        for i, key in enumerate(("x1", "x2")):
            out[f"rmse_over_pcrb_{key}"] = float(ratio[i])
            out[f"rmse_over_pcrb_err_{key}"] = float(err[i])
    return out


#: A pan-tilt run's states by name, in the state's order.
HEAD_STATES = ("azimuth", "elevation", "azimuth_rate", "elevation_rate")


def head_bound_summary(kept, steady_step: int, estimates: bool) -> dict:
    """:func:`bound_summary` of pan-tilt runs: the bound's steady root
    (``pcrb_steady_x1``/``_x2`` the azimuth's angle [rad] and rate [rad/s], as on one
    axis; ``pcrb_steady_azimuth``, ``_elevation``, and ``_pointing``, the root of the
    two angles' sum [rad]); with ``estimates``, the steady RMSE over each
    (``rmse_over_pcrb_<key>``; one standard error in ``rmse_over_pcrb_err_x1``/``_x2``)."""
    errs = np.array([[o.metrics.rmse_steady[k] for k in HEAD_STATES] for o in kept])
    bound, ratio, err = bound_against([o.bound for o in kept], kept[0].bound["prior"],
                                      steady_step, errs)
    pointing = float(np.hypot(bound[0], bound[1]))
    out = {"pcrb_steady_x1": float(bound[0]), "pcrb_steady_x2": float(bound[2]),
           "pcrb_steady_azimuth": float(bound[0]), "pcrb_steady_elevation": float(bound[1]),
           "pcrb_steady_pointing": pointing}
    if estimates and np.all(np.isfinite(ratio)):
        for key, i in (("x1", 0), ("x2", 2)):
            out[f"rmse_over_pcrb_{key}"] = float(ratio[i])
            out[f"rmse_over_pcrb_err_{key}"] = float(err[i])
        out["rmse_over_pcrb_azimuth"] = float(ratio[0])
        out["rmse_over_pcrb_elevation"] = float(ratio[1])
        steady = np.array([o.metrics.rmse_steady["pointing"] for o in kept])
        out["rmse_over_pcrb_pointing"] = float(np.sqrt(np.mean(steady**2)) / pointing)
    return out
