"""Learning the gain-scheduled KKL's maps T(x; w) and T*(z; w, s): Algorithm 1 on a grid
of gains, with random tanh features and exact least-squares output layers
(``docs/observer.md``, :mod:`observer.kkl.gainmaps`).

* T: one hidden layer phi(x) for every gain. For z component i (rate r_i, output j) at
  gain w, ``T_i(f(x)) = l T_i(x) + (1 - l) y_j`` with ``l = 1 - Te r_i(w)`` is linear in
  the output weights: ``c (phi(f(x)) - phi(x)) / Te + phi(x)`` times them equals y_j,
  with ``c = 1 / r_i(w)`` (the residual divided by 1 - l, so an error of T weighs the
  same at every gain). Three Gram matrices, shared by every component and every gain,
  give each grid point's weights by one small solve.
* T*: per grid point (w, s), x from ``T(x; w) + e`` with e the stationary noise of z at
  that gain and noise level (noise-aware), on one hidden layer shared by all.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass

import numpy as np
from tqdm.auto import tqdm

from observer.exceptions import ObserverError
from observer.kkl.fitting import ridge_solve
from observer.kkl.fixed_gain import stationary_noise_covariance
from observer.kkl.gainmaps import GainTableMap
from observer.kkl.scheduled import GainSchedule, ScheduledDesign, ScheduledKKL
from observer.system import DiscreteSystem


@dataclass
class ScheduledTrainingConfig:
    """Hyper-parameters (defaults: the shipped observer)."""

    hidden: int = 1000  # random tanh features of T
    decoder_hidden: int = 750  # ... of T*
    feature_scale: float = 4.0  # std x sqrt(n_in) of T's hidden weights
    decoder_feature_scale: float = 2.0
    gains: int = 16  # grid points of w (geometric over the design's range)
    noise_levels: int = 4  # grid points of s (geometric over the design's range)
    decoder_samples: int = 100_000  # training states of T* per grid point
    ridge: float = 1e-9  # relative Tikhonov term of the output solves
    u_bar: float = 0.0
    seed: int = 0
    chunk: int = 25_000  # rows per Gram-matrix block (memory)

    def __post_init__(self):
        for name in ("hidden", "decoder_hidden", "chunk", "gains", "noise_levels",
                     "decoder_samples"):
            if getattr(self, name) < 1:
                raise ObserverError(f"{name}={getattr(self, name)!r}: must be >= 1")


def random_hidden(low, high, hidden: int, scale: float, rng: np.random.Generator):
    """(W1, b1) of tanh features spanning the box low..high (normalisation folded in)."""
    low, high = np.asarray(low, float), np.asarray(high, float)
    shift, half = 0.5 * (low + high), np.maximum(0.5 * (high - low), 1e-12)
    W = rng.standard_normal((hidden, low.size)) * scale / math.sqrt(low.size)
    b = (rng.random(hidden) * 2 - 1) * scale
    W1 = W / half
    return W1, b - W1 @ shift


def stationary_z_noise(design: ScheduledDesign, Te: float, w: float, s: float,
                       noise_std: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """n samples of z's stationary response to white measurement noise at gain w and
    noise s x nominal: per output j, z_i' = l_i z_i + (1 - l_i) v_j, so
    P_ik = (1 - l_i)(1 - l_k) sigma_j^2 s^2 / (1 - l_i l_k) within one output's bank."""
    a = Te * design.rates(w)
    P = stationary_noise_covariance(1.0 - a, a[:, None], [[1.0]])  # unit noise, one bank
    L = np.linalg.cholesky(P + 1e-14 * np.eye(a.size))
    nr = a.size
    out = np.empty((n, design.q))
    for j in range(design.n_output):
        out[:, j * nr:(j + 1) * nr] = rng.standard_normal((n, nr)) @ L.T * (noise_std[j] * s)
    return out


def learn_encoder(system: DiscreteSystem, design: ScheduledDesign, x, xk, y, log_w,
                  cfg: ScheduledTrainingConfig, rng, progress: bool) -> GainTableMap:
    """T(x; w) on the grid ``log_w``: one Gram pass, then a solve per gain and component."""
    W1, b1 = random_hidden(system.domain_low, system.domain_high, cfg.hidden,
                           cfg.feature_scale, rng)
    probe = GainTableMap(W1, b1, np.zeros((1, 1, 1, cfg.hidden + 1)), [0.0], [0.0])
    H = cfg.hidden + 1
    DD, DP, PP = (np.zeros((H, H)) for _ in range(3))
    rD, rP = np.zeros((H, design.n_output)), np.zeros((H, design.n_output))
    bar = tqdm(total=len(x), desc="learn T(x; w)", disable=not progress, leave=False)
    for i in range(0, len(x), cfg.chunk):
        sl = slice(i, i + cfg.chunk)
        P0 = probe.features(x[sl])
        D = (probe.features(xk[sl]) - P0) / system.Te
        DD += D.T @ D
        DP += D.T @ P0
        PP += P0.T @ P0
        rD += D.T @ y[sl]
        rP += P0.T @ y[sl]
        bar.update(len(P0))
    bar.close()
    coef = np.empty((log_w.size, 1, design.q, H))
    for g, lw in enumerate(log_w):
        rates = design.rates(math.exp(lw))
        for i in range(design.q):
            j, r = divmod(i, design.n_rates)
            c = 1.0 / rates[r]
            A = c * c * DD + c * (DP + DP.T) + PP
            coef[g, 0, i] = ridge_solve(A, c * rD[:, j] + rP[:, j], cfg.ridge)
    return GainTableMap(W1, b1, coef, log_w, [0.0])


def _encode_each(encoder: GainTableMap, x: np.ndarray, log_w: np.ndarray) -> np.ndarray:
    """T(x_n; w_n) for per-sample gains (the grid's linear interpolation, in log w)."""
    F = encoder.features(x)
    grid = encoder.log_w
    i = np.clip(np.searchsorted(grid, log_w, side="right") - 1, 0, max(grid.size - 2, 0))
    if grid.size == 1:
        return F @ encoder.coef[0, 0].T
    t = np.clip((log_w - grid[i]) / (grid[i + 1] - grid[i]), 0.0, 1.0)[:, None]
    C = encoder.coef[:, 0]
    return (1 - t) * np.einsum("nh,nqh->nq", F, C[i]) + t * np.einsum("nh,nqh->nq", F, C[i + 1])


def learn_decoder(system: DiscreteSystem, design: ScheduledDesign, encoder: GainTableMap,
                  x, log_s, cfg: ScheduledTrainingConfig, rng, progress: bool,
                  box: float = 1.0):
    """T*(z; w, s) on the grid (encoder's gains) x ``log_s``, noise-aware, with a hidden
    layer per grid gain spanning the z that gain's prior gives. The prior: x uniform
    on ``box`` times the domain, around its centre."""
    log_w = encoder.log_w
    H = cfg.decoder_hidden
    # One draw of random directions for every gain (each scaled to its own input box).
    W0 = rng.standard_normal((H, design.q)) * cfg.decoder_feature_scale / math.sqrt(design.q)
    b0 = (rng.random(H) * 2 - 1) * cfg.decoder_feature_scale
    W1, b1 = np.empty((log_w.size, H, design.q)), np.empty((log_w.size, H))
    coef = np.empty((log_w.size, log_s.size, system.n_state, H + 1))
    err = np.empty((log_w.size, log_s.size, system.n_state))
    bar = tqdm(total=coef.shape[0] * coef.shape[1], desc="learn T*(z; w, s)",
               disable=not progress, leave=False)
    for g, lw in enumerate(log_w):
        # The gains whose interpolation leans on this grid point (a hat around it): the
        # decoder is then right for z from any gain between grid points, not only on them.
        lo_w, hi_w = log_w[max(g - 1, 0)], log_w[min(g + 1, log_w.size - 1)]
        lws = rng.triangular(lo_w, lw, hi_w, len(x)) if hi_w > lo_w else np.full(len(x), lw)
        xg = system.domain_center + (x - system.domain_center) * box
        Z = np.empty((len(x), design.q))
        for i in range(0, len(x), 512):
            Z[i:i + 512] = _encode_each(encoder, xg[i:i + 512], lws[i:i + 512])
        noisy = [Z + stationary_z_noise(design, system.Te, math.exp(lw), math.exp(ls),
                                        system.measurement_noise_std, len(x), rng)
                 for ls in log_s]
        lo = np.percentile(noisy[0], 0.5, axis=0)
        hi = np.percentile(noisy[0], 99.5, axis=0)
        shift, half = 0.5 * (lo + hi), np.maximum(0.5 * (hi - lo), 1e-12)
        W1[g] = W0 / half
        b1[g] = b0 - W1[g] @ shift
        probe = GainTableMap(W1[g], b1[g], np.zeros((1, 1, 1, H + 1)), [0.0], [0.0])
        for k, Zin in enumerate(noisy):
            F = probe.features(Zin)
            coef[g, k] = ridge_solve(F.T @ F, F.T @ xg, cfg.ridge).T
            err[g, k] = np.sqrt(((F @ coef[g, k].T - xg) ** 2).mean(axis=0))
            bar.update()
    bar.close()
    return GainTableMap(W1, b1, coef, log_w, log_s), err


def train_scheduled_kkl(system: DiscreteSystem, design: ScheduledDesign, data,
                        config: ScheduledTrainingConfig | None = None,
                        schedule: GainSchedule | None = None,
                        progress: bool = True) -> tuple[ScheduledKKL, dict]:
    """Learn T(x; w) and T*(z; w, s) from transitions ``data = (x, f(x, u_bar), h(x))``.

    Returns the observer and a report: the dynamics residual relative to z's spread
    (over the grid), the reconstruction RMSE per state at each grid point [state
    units], and the seconds it took.
    """
    cfg = config or ScheduledTrainingConfig()
    design.check_stable(system.Te)
    t0 = time.perf_counter()
    rng = np.random.default_rng(cfg.seed)
    x, xk, y = (np.asarray(a, dtype=float) for a in data)
    y = y[0] if y.ndim == 3 else y
    log_w = np.linspace(*(math.log(v) for v in design.w_range), cfg.gains)
    log_s = np.linspace(*(math.log(v) for v in design.noise_range), cfg.noise_levels) \
        if design.noise_range[1] > design.noise_range[0] else np.zeros(1)
    encoder = learn_encoder(system, design, x, xk, y, log_w, cfg, rng, progress)
    m = slice(0, min(len(x), 20_000))
    worst = 0.0
    for lw in log_w:
        a = system.Te * design.rate_vector(math.exp(lw))
        Z0, ZK = encoder(x[m], math.exp(lw)), encoder(xk[m], math.exp(lw))
        res = (ZK - (1 - a) * Z0 - a * y[m][:, design.channel()]) / a
        worst = max(worst, float(np.max(np.sqrt((res**2).mean(0)) / Z0.std(0))))
    nd = min(len(x), cfg.decoder_samples)
    decoder, err = learn_decoder(system, design, encoder, x[:nd], log_s, cfg, rng, progress)
    locked, err_locked = learn_decoder(system, design, encoder, x[:nd], log_s, cfg, rng,
                                       progress, box=design.lock_box)
    report = {"residual_rel_worst": worst, "recon_rmse": err.tolist(),
              "recon_rmse_locked": err_locked.tolist(), "seconds": time.perf_counter() - t0}
    obs = ScheduledKKL(system, design, encoder, decoder, locked, schedule, u_bar=cfg.u_bar)
    obs.training_metadata = {"design": design.to_dict(), "training": asdict(cfg),
                             "report": report}
    return obs, report
