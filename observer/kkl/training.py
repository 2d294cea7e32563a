"""Learning the KKL maps T (encoder) and T* (decoder), paper Algorithm 1.

Data-driven: the only access to the plant is a batch of one-step transitions
``(x_k, f(x_k, u_bar), h(x_k))`` with x_k uniform on the system's domain, so any
simulator that can be set to a state and stepped (the closed-form model, MuJoCo) will do.

1. Learn T minimising L_dyn = |T(x_{k+1}) - (A T(x_k) + B h(x_k))|^2, each component of
   the residual divided by that component's spread D(z_i) (recomputed every epoch):
   this is Algorithm 1's rescaling of z, done so the slow filters do not drown the fast.
2. Rescale z by 1/D(z_i) for good (B becomes diag(1/D) B).
3. Learn T* minimising L_recon = |x - T*(T(x) + e)|^2. The paper uses e = 0; the
   ``decoder_noise="observer"`` option draws e from the stationary covariance that the
   running observer's z actually has under measurement noise, so T* learns to average
   noise out instead of amplifying it (``docs/observer.md``).
"""

from __future__ import annotations

import math
import sys
import time
from dataclasses import asdict, dataclass, field

import numpy as np
import torch
from tqdm.auto import tqdm

from observer.exceptions import ObserverError
from observer.kkl.fitting import (
    adam,
    features,
    init_features,
    ridge_solve,
    set_output,
    solve_encoder_output,
)
from observer.kkl.fixed_gain import KKLDesign, KKLObserver, stationary_noise_covariance
from observer.kkl.maps import TanhMLP
from observer.system import DiscreteSystem


@dataclass
class TrainingConfig:
    """Hyper-parameters of Algorithm 1 (defaults: the shipped observer)."""

    n_samples: int = 200_000  # uniform samples on the domain (paper: 2e5)
    horizon: int = 1  # K of the K-step L_dyn (paper: 1)
    hidden: int = 500  # tanh units in the one hidden layer of T (paper: 500)
    decoder_hidden: int | None = None  # tanh units of T* (None: same as T)
    encoder_epochs: int = 0  # Adam epochs on all weights of T before the output solve
    decoder_epochs: int = 0  # Adam epochs on all weights of T* before the output solve
    output_solve: bool = True  # finish with the exact least-squares output layer
    decoder_layers: int = 1  # hidden layers of T* (paper: 1)
    finetune_epochs: int = 0  # Adam epochs on all weights of T and T* after the solve
    feature_scale: float = 4.0  # std x sqrt(n_in) of the initial hidden weights of T
    decoder_feature_scale: float | None = None  # the same for T* (None: feature_scale)
    ridge: float = 1e-9  # relative Tikhonov term of the output solve
    batch_size: int = 1024
    lr: float = 2e-3
    lr_final: float = 2e-5
    u_bar: float = 0.0  # constant input of the training transitions
    decoder_noise: str = "observer"  # "observer" (noise-aware T*) or "none" (paper)
    decoder_noise_scale: float = 1.0  # multiplies the stationary z-noise std
    seed: int = 0
    threads: int = 2

    def __post_init__(self):
        if self.decoder_noise not in ("observer", "none"):
            raise ObserverError(f"decoder_noise={self.decoder_noise!r}: use 'observer' or 'none'")
        for name in ("n_samples", "hidden", "batch_size", "horizon", "decoder_layers"):
            if getattr(self, name) < 1:
                raise ObserverError(f"{name}={getattr(self, name)!r}: must be >= 1")
        if not self.output_solve and min(self.encoder_epochs, self.decoder_epochs) < 1:
            raise ObserverError("without output_solve, encoder_epochs and decoder_epochs "
                                "must be >= 1")


@dataclass
class TrainingReport:
    """What training measured (stored in the checkpoint metadata)."""

    loss_dyn: float = math.nan  # final mean L_dyn, residual / spread, summed over z
    loss_recon: float = math.nan  # final mean L_recon, error / domain half-width, summed
    z_spread: list = field(default_factory=list)
    seconds: float = math.nan


def generate_transitions(system: DiscreteSystem, n: int, u_bar: float, rng: np.random.Generator,
                horizon: int = 1):
    """``(x_k, x_{k+K})`` and the outputs ``(y_k .. y_{k+K-1})`` for ``n`` uniform states x_k.

    Step 1 of Algorithm 1: with K = 1 this is its data set D. Shapes: ``(n, n_state)`` twice and
    ``(K, n, n_output)``.
    """
    x = system.sample_domain(rng, n)
    ys = np.empty((horizon, n, system.n_output))
    xk = x
    for j in range(horizon):
        ys[j] = system.h(xk)
        xk = system.f(xk, u_bar)
    return x, xk, ys


def filtered_outputs(ys: np.ndarray, eigenvalues: np.ndarray, B: np.ndarray) -> np.ndarray:
    """S_K = sum_j A^(K-1-j) B y_j: what the linear filter adds over K steps, ``(n, q)``."""
    s = np.zeros((ys.shape[1], len(eigenvalues)))
    for y in ys:
        s = eigenvalues * s + y @ B.T
    return s


#: Former name of :func:`generate_transitions`.
transitions = generate_transitions


def learn_encoder_T(system: DiscreteSystem, design: KKLDesign, cfg: TrainingConfig, data,
                    gen: torch.Generator, progress: bool = False):
    """Step 2 of Algorithm 1: T minimising L_dyn = |T(x_K) - (A^K T(x_0) + S_K)|^2.

    Adam (with each residual component weighted by 1 / D(z_i)^2, D the spread of z_i)
    and/or the exact least-squares output layer. Returns ``(encoder, residual)``, the
    residual per sample and z component, shape ``(n, q)``.
    """
    x_np, xk_np, ys_np = data
    lam = np.asarray(design.eigenvalues, dtype=float)
    B = design.B_array
    contraction = lam ** ys_np.shape[0]
    s_np = filtered_outputs(ys_np, lam, B)
    # Typical |z_i| = |B y| / (1 - l_i) scales the net's outputs to O(1).
    z_scale = np.abs(ys_np[0] @ B.T).mean(axis=0) / (1.0 - lam) + 1e-12
    encoder = TanhMLP(system.n_state, cfg.hidden, design.q, system.domain_center,
                      system.domain_halfwidth, np.zeros(design.q), z_scale)
    if cfg.output_solve:
        init_features(encoder, cfg.feature_scale, gen)
    X, XK, S = (torch.as_tensor(a, dtype=torch.float64) for a in (x_np, xk_np, s_np))
    A_t = torch.as_tensor(contraction, dtype=torch.float64)

    def descend(epochs: int, desc: str) -> None:
        with torch.no_grad():
            weight = 1.0 / encoder(X[:20000]).std(dim=0).clamp_min(1e-9) ** 2

        def loss_dyn(idx):
            res = encoder(XK[idx]) - (A_t * encoder(X[idx]) + S[idx])
            return (res**2 * weight).sum(dim=1).mean()

        adam(encoder, loss_dyn, len(x_np), epochs, cfg, gen, desc, progress)

    if cfg.encoder_epochs:
        descend(cfg.encoder_epochs, "learn T (L_dyn)")
    if cfg.output_solve:
        residual = solve_encoder_output(encoder, x_np, xk_np, s_np, contraction, cfg.ridge)
        if not cfg.finetune_epochs:
            return encoder, residual
        descend(cfg.finetune_epochs, "fine-tune T (L_dyn)")  # warm start: the LS solution
    with torch.no_grad():
        return encoder, (encoder(XK) - (A_t * encoder(X) + S)).double().numpy()


def rescale_z(encoder: TanhMLP, x: np.ndarray, residual: np.ndarray, B: np.ndarray):
    """Step 3 of Algorithm 1: z~ = z / D(z), B~ = diag(1/D) B, for good.

    Returns ``(spread D, z~ of the training states, B~, L_dyn in the rescaled z)``.
    """
    with torch.no_grad():
        Z = encoder(torch.as_tensor(x, dtype=torch.float64)).double().numpy()
    spread = np.maximum(Z.std(axis=0), 1e-12)
    loss_dyn = float(((residual / spread) ** 2).sum(axis=1).mean())
    return spread, Z / spread, B / spread[:, None], loss_dyn


def decoder_inputs(system: DiscreteSystem, Zs: np.ndarray, eigenvalues, B_scaled,
                   cfg: TrainingConfig, rng: np.random.Generator) -> np.ndarray:
    """z~ as T* will see it: plus the running observer's z noise (noise-aware T*) or not."""
    if cfg.decoder_noise != "observer":
        return Zs
    R = np.diag(system.measurement_noise_std**2)
    P = stationary_noise_covariance(eigenvalues, B_scaled, R) * cfg.decoder_noise_scale**2
    return Zs + rng.standard_normal(Zs.shape) @ np.linalg.cholesky(
        P + 1e-12 * np.eye(len(eigenvalues))).T


def learn_decoder_T_star(system: DiscreteSystem, Zs: np.ndarray, Zin: np.ndarray,
                         x: np.ndarray, cfg: TrainingConfig, gen: torch.Generator,
                         progress: bool = False):
    """Step 4 of Algorithm 1: T* minimising L_recon = |x - T*(z~ + e)|^2.

    Returns ``(decoder, L_recon)`` (errors divided by the domain half-widths, summed).
    """
    center, half = system.domain_center, system.domain_halfwidth
    decoder = TanhMLP(Zs.shape[1], cfg.decoder_hidden or cfg.hidden, system.n_state,
                      Zs.mean(0), Zs.std(0), center, half, n_layers=cfg.decoder_layers)
    if cfg.output_solve:
        init_features(decoder, cfg.decoder_feature_scale or cfg.feature_scale, gen)
    Zin_t = torch.as_tensor(Zin, dtype=torch.float64)
    X = torch.as_tensor(x, dtype=torch.float64)
    half_t = torch.as_tensor(half, dtype=torch.float64)

    def loss_recon(idx):
        return (((decoder(Zin_t[idx]) - X[idx]) / half_t) ** 2).sum(dim=1).mean()

    if cfg.decoder_epochs:
        adam(decoder, loss_recon, len(x), cfg.decoder_epochs, cfg, gen, "learn T* (L_recon)",
             progress)
    if cfg.output_solve:
        F = features(decoder, Zin)
        set_output(decoder, ridge_solve(F.T @ F, F.T @ x, cfg.ridge).T)
        if cfg.finetune_epochs:  # warm start: Adam from the least-squares solution
            adam(decoder, loss_recon, len(x), cfg.finetune_epochs, cfg, gen,
                 "fine-tune T* (L_recon)", progress)
    with torch.no_grad():
        err = (decoder(Zin_t).double().numpy() - x) / half
    return decoder, float((err**2).sum(axis=1).mean())


def train_kkl(system: DiscreteSystem, design: KKLDesign, config: TrainingConfig | None = None,
              data=None, progress: bool = True) -> tuple[KKLObserver, TrainingReport]:
    """Run Algorithm 1 and return the observer (numpy inference) and a report.

    Args:
        system: plant, used for its dimensions, domain, noise levels and (unless
            ``data`` is given) to generate transitions.
        design: eigenvalues of A and B.
        config: hyper-parameters.
        data: optional precomputed ``(x_k, x_{k+K}, (y_k..y_{k+K-1}))`` (e.g. from MuJoCo).
        progress: show progress bars (stderr).
    """
    cfg = config or TrainingConfig()
    t0 = time.perf_counter()
    torch.manual_seed(cfg.seed)
    torch.set_num_threads(cfg.threads)
    gen = torch.Generator().manual_seed(cfg.seed)
    rng = np.random.default_rng(cfg.seed)
    if design.B_array.shape[1] != system.n_output:
        raise ObserverError(f"B has {design.B_array.shape[1]} columns but the system has "
                            f"{system.n_output} outputs")
    stages = tqdm(total=3, desc="Algorithm 1", disable=not progress, leave=False,
                  bar_format="{desc}: {n}/{total} {postfix}", file=sys.stderr)
    stages.set_postfix_str("transitions")
    if data is None:
        data = generate_transitions(system, cfg.n_samples, cfg.u_bar, rng, cfg.horizon)
    x, xk, ys = (np.asarray(a, dtype=np.float64) for a in data)
    ys = ys[None] if ys.ndim == 2 else ys
    stages.update()
    stages.set_postfix_str("encoder T (L_dyn)")
    encoder, residual = learn_encoder_T(system, design, cfg, (x, xk, ys), gen, progress)
    stages.update()
    stages.set_postfix_str("decoder T* (L_recon)")
    report = TrainingReport()
    spread, Zs, B_scaled, report.loss_dyn = rescale_z(encoder, x, residual, design.B_array)
    report.z_spread = spread.tolist()
    lam = np.asarray(design.eigenvalues, dtype=float)
    Zin = decoder_inputs(system, Zs, lam, B_scaled, cfg, rng)
    decoder, report.loss_recon = learn_decoder_T_star(system, Zs, Zin, x, cfg, gen, progress)
    stages.update()
    stages.close()
    report.seconds = time.perf_counter() - t0
    obs = KKLObserver(system, lam, B_scaled, encoder.export().scaled_output(1.0 / spread),
                      decoder.export(), u_bar=cfg.u_bar)
    obs.training_metadata = {"design": design.to_dict(), "training": asdict(cfg),
                             "report": asdict(report)}
    return obs, report
