"""The posterior Cramér-Rao bound (PCRB) of filtering, along the runs of one configuration.

For the plant of :class:`~observer.system.DiscreteSystem`,

    x_{k+1} = f(x_k, u_k) + w_k,  w_k ~ N(0, Q),     y_k = h(x_k) + v_k,  v_k ~ N(0, R_k),

the Fisher information J_k of x_k given y_0..y_k follows Tichavsky, Muravchik and
Nehorai's recursion (IEEE Trans. Signal Processing 46(5), 1998, eq. 21):

    J_{k+1} = D22_k - D12_k^T (J_k + D11_k)^{-1} D12_k,
    D11_k = E[F_k^T Q^-1 F_k],   D12_k = -E[F_k]^T Q^-1,
    D22_k = Q^-1 + E[H_{k+1}^T R_{k+1}^-1 H_{k+1}],

with F_k = df/dx at (x_k, u_k) and H_k = dh/dx at x_k; J_0 is the prior's information
plus that of y_0. Any estimator of x_k from y_0..y_k has a mean-square error matrix at
least J_k^{-1} (in the positive semi-definite order): this is the yardstick of
:func:`posterior_crb`.

The expectations are over the true trajectories. Here they are means over the seeds of
one configuration, whose true trajectories (with their inputs) are draws of it: a
Monte-Carlo PCRB. One seed gives the bound along that one trajectory. A sample that was
withheld (a dropout, an occlusion) carries no information: its rows of H drop out.

All arrays are float64; ``N`` steps, ``n`` states, ``p`` outputs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


class BoundError(ValueError):
    """Inputs the bound cannot be computed from."""


@dataclass
class BoundTerms:
    """The recursion's expectations, summed over ``count`` trajectories.

    Attributes:
        ftqf: sum of F_k^T Q^-1 F_k, shape (N, n, n).
        f: sum of F_k, shape (N, n, n).
        info: sum of the measurement information H_k^T R_k^-1 H_k of y_k, (N, n, n).
        q_inv: Q^-1, shape (n, n).
        count: how many trajectories were summed.
    """

    ftqf: np.ndarray
    f: np.ndarray
    info: np.ndarray
    q_inv: np.ndarray
    count: int = 1

    def __add__(self, other: BoundTerms) -> BoundTerms:
        if self.info.shape != other.info.shape or not np.array_equal(self.q_inv, other.q_inv):
            raise BoundError(f"cannot pool trajectories of shapes {self.info.shape} and "
                             f"{other.info.shape} (or of different Q): the bound averages "
                             "runs of one configuration")
        return BoundTerms(self.ftqf + other.ftqf, self.f + other.f, self.info + other.info,
                          self.q_inv, self.count + other.count)

    @classmethod
    def pooled(cls, terms) -> BoundTerms:
        """The terms of several trajectories of one configuration, summed."""
        terms = list(terms)
        if not terms:
            raise BoundError("no trajectories to pool")
        out = terms[0]
        for t in terms[1:]:
            out = out + t
        return out

    def to_arrays(self) -> dict[str, np.ndarray]:
        """Plain arrays (to pass between processes or save)."""
        return {"ftqf": self.ftqf, "f": self.f, "info": self.info, "q_inv": self.q_inv,
                "count": np.array(self.count)}

    @classmethod
    def from_arrays(cls, a: dict) -> BoundTerms:
        return cls(a["ftqf"], a["f"], a["info"], a["q_inv"], int(a["count"]))


def process_information(process_noise_std) -> np.ndarray:
    """Q^-1 from the per-step standard deviations of w_k [state units]; refuses a zero."""
    std = np.asarray(process_noise_std, dtype=float)
    if not (np.all(std > 0) and np.all(np.isfinite(std))):
        raise BoundError(f"process_noise_std={std.tolist()!r}: the bound needs every "
                         "component > 0 and finite (with none, the information of a "
                         "noise-free model grows without end)")
    return np.diag(1.0 / std**2)


def box_prior(halfwidth) -> np.ndarray:
    """Prior information on x_0 of an estimator that knows only the box it was trained
    on: a Gaussian with the spread of a uniform draw from it (variance halfwidth^2 / 3
    per state), (n, n)."""
    return np.diag(3.0 / np.asarray(halfwidth, dtype=float) ** 2)


def trajectory_terms(f_jacobian: np.ndarray, h_jacobian: np.ndarray, noise_var,
                     q_inv: np.ndarray, measured: np.ndarray | None = None) -> BoundTerms:
    """The terms of one trajectory.

    Args:
        f_jacobian: F_k = df/dx along the true trajectory and inputs, (N, n, n).
        h_jacobian: H_k = dh/dx along the true trajectory, (N, p, n) [output unit/state
            unit].
        noise_var: variance of each output sample, (p,) or (N, p) [output unit^2].
        q_inv: Q^-1 (:func:`process_information`), (n, n).
        measured: which samples the estimator was given, (N, p) bool (None: all).
    """
    F = np.asarray(f_jacobian, dtype=float)
    H = np.asarray(h_jacobian, dtype=float)
    if F.ndim != 3 or H.ndim != 3 or len(F) != len(H) or F.shape[1:] != (H.shape[2],) * 2:
        raise BoundError(f"f_jacobian {F.shape} and h_jacobian {H.shape} must be (N, n, n) "
                         "and (N, p, n)")
    var = np.broadcast_to(np.asarray(noise_var, dtype=float), H.shape[:2])
    if not np.all(var > 0):
        raise BoundError("noise_var must be > 0 for every output")
    weight = 1.0 / var
    if measured is not None:
        weight = np.where(np.asarray(measured, dtype=bool), weight, 0.0)
    info = np.einsum("kpi,kp,kpj->kij", H, weight, H)
    ftqf = np.einsum("kai,ab,kbj->kij", F, q_inv, F)
    return BoundTerms(ftqf, F.copy(), info, np.asarray(q_inv, dtype=float))


def posterior_crb(terms: BoundTerms, prior_information: np.ndarray) -> np.ndarray:
    """The bound J_k^{-1} on the filtering MSE matrix at each step, (N, n, n).

    ``prior_information``: J of the prior on x_0 before y_0 (for a Gaussian prior, the
    inverse of its covariance), (n, n).
    """
    c = terms.count
    ftqf, fbar, info = terms.ftqf / c, terms.f / c, terms.info / c
    q_inv = terms.q_inv
    N, n = len(info), q_inv.shape[0]
    out = np.empty((N, n, n))
    J = np.asarray(prior_information, dtype=float) + info[0]
    for k in range(N):
        out[k] = np.linalg.inv(J)
        if k + 1 < N:
            d12 = -fbar[k].T @ q_inv
            J = q_inv + info[k + 1] - d12.T @ np.linalg.solve(J + ftqf[k], d12)
            J = 0.5 * (J + J.T)
    return out


def steady_bound(bound: np.ndarray, start: int) -> np.ndarray:
    """Root of the bound's mean over steps ``start`` onwards, per state (n,): the least
    steady RMSE any estimator can reach [state units]."""
    diag = np.diagonal(np.asarray(bound)[start:], axis1=1, axis2=2)
    if len(diag) == 0:
        return np.full(np.shape(bound)[-1], np.nan)
    return np.sqrt(diag.mean(axis=0))


def ratio_to_bound(steady_rmse, bound_rmse) -> tuple[np.ndarray, np.ndarray]:
    """An estimator's steady RMSE over the bound's, per state, with one Monte-Carlo
    standard error.

    ``steady_rmse``: per seed, (S, n). The ratio compares like with like: the root of
    the seeds' mean square error over the root of the mean bound. Its standard error is
    half the relative standard error of that mean square error (S >= 2; else NaN).
    """
    mse = np.asarray(steady_rmse, dtype=float) ** 2
    mean = mse.mean(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.sqrt(mean) / np.asarray(bound_rmse, dtype=float)
    if len(mse) < 2:
        return ratio, np.full_like(ratio, np.nan)
    with np.errstate(invalid="ignore", divide="ignore"):  # no error at all: NaN
        rel = mse.std(axis=0, ddof=1) / np.sqrt(len(mse)) / mean
    return ratio, 0.5 * rel * ratio


def bound_against(terms, prior_information, steady: int, steady_rmse):
    """The steady bound of pooled runs and each run's estimator against it.

    Args:
        terms: each run's :class:`BoundTerms` (or its :meth:`~BoundTerms.to_arrays`).
        prior_information: J before the first sample, (n, n).
        steady: first step of the steady window.
        steady_rmse: each run's steady RMSE, (S, n).

    Returns:
        (the bound's steady root (n,), the RMSE over it (n,), its standard error (n,)):
        :func:`steady_bound` and :func:`ratio_to_bound`.
    """
    pooled = BoundTerms.pooled(t if isinstance(t, BoundTerms) else BoundTerms.from_arrays(t)
                               for t in terms)
    bound = steady_bound(posterior_crb(pooled, prior_information), steady)
    ratio, err = ratio_to_bound(steady_rmse, bound)
    return bound, ratio, err
