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
import time
from dataclasses import asdict, dataclass, field

import numpy as np
import torch
from tqdm.auto import tqdm

from .kkl import KKLDesign, KKLObserver, stationary_noise_covariance
from .nets import TanhMLP
from .system import DiscreteSystem


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
            raise ValueError(f"decoder_noise={self.decoder_noise!r}: use 'observer' or 'none'")
        for name in ("n_samples", "hidden", "batch_size", "horizon"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name}={getattr(self, name)!r}: must be >= 1")
        if not self.output_solve and min(self.encoder_epochs, self.decoder_epochs) < 1:
            raise ValueError("without output_solve, encoder_epochs and decoder_epochs must be >= 1")


@dataclass
class TrainingReport:
    """What training measured (stored in the checkpoint metadata)."""

    loss_dyn: float = math.nan  # final mean L_dyn, residual / spread, summed over z
    loss_recon: float = math.nan  # final mean L_recon, error / domain half-width, summed
    z_spread: list = field(default_factory=list)
    seconds: float = math.nan


def transitions(system: DiscreteSystem, n: int, u_bar: float, rng: np.random.Generator,
                horizon: int = 1):
    """``(x_k, x_{k+K})`` and the outputs ``(y_k .. y_{k+K-1})`` for ``n`` uniform states x_k.

    With K = 1 this is the data set D of Algorithm 1. Shapes: ``(n, n_state)`` twice and
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


def _cosine_lr(opt, step, total, lr0, lr1):
    frac = step / max(total - 1, 1)
    for group in opt.param_groups:
        group["lr"] = lr1 + 0.5 * (lr0 - lr1) * (1 + math.cos(math.pi * frac))


def _adam(net: TanhMLP, loss_fn, n: int, epochs: int, cfg: TrainingConfig, gen, desc: str,
          progress: bool) -> float:
    """Minimise ``loss_fn(idx)`` over mini-batches; returns the last epoch's mean loss."""
    opt = torch.optim.Adam(net.parameters(), lr=cfg.lr)
    total = epochs * math.ceil(n / cfg.batch_size)
    step, epoch_loss = 0, math.nan
    bar = tqdm(range(epochs), desc=desc, disable=not progress, leave=False)
    for _ in bar:
        epoch_loss = 0.0
        for idx in torch.randperm(n, generator=gen).split(cfg.batch_size):
            _cosine_lr(opt, step, total, cfg.lr, cfg.lr_final)
            loss = loss_fn(idx)
            opt.zero_grad()
            loss.backward()
            opt.step()
            epoch_loss += loss.item() * len(idx)
            step += 1
        epoch_loss /= n
        bar.set_postfix(loss=f"{epoch_loss:.2e}")
    return epoch_loss


def _init_features(net: TanhMLP, scale: float, gen) -> None:
    """Random tanh features spanning the normalised input box (a good start for the solve)."""
    w = net.hidden.weight
    with torch.no_grad():
        w.copy_(torch.randn(w.shape, generator=gen) * scale / math.sqrt(w.shape[1]))
        net.hidden.bias.copy_((torch.rand(w.shape[0], generator=gen) * 2 - 1) * scale)


def _features(net: TanhMLP, v: np.ndarray) -> np.ndarray:
    """Hidden activations plus a constant column, float64, ``(n, H + 1)``."""
    W = net.hidden.weight.detach().double().numpy()
    b = net.hidden.bias.detach().double().numpy()
    shift, scale = net.in_shift.double().numpy(), net.in_scale.double().numpy()
    phi = np.tanh(((v - shift) / scale) @ W.T + b)
    return np.hstack([phi, np.ones((v.shape[0], 1))])


def _set_output(net: TanhMLP, coef: np.ndarray) -> None:
    """Write solved output weights ``coef`` (n_out, H + 1), in output units, into ``net``."""
    shift, scale = net.out_shift.double().numpy(), net.out_scale.double().numpy()
    coef = coef.copy()
    coef[:, -1] -= shift
    coef /= scale[:, None]
    with torch.no_grad():
        net.output.weight.copy_(torch.as_tensor(coef[:, :-1]))
        net.output.bias.copy_(torch.as_tensor(coef[:, -1]))


def _ridge_solve(G: np.ndarray, rhs: np.ndarray, ridge: float) -> np.ndarray:
    reg = ridge * np.trace(G) / G.shape[0]
    return np.linalg.solve(G + reg * np.eye(G.shape[0]), rhs)


def solve_encoder_output(net: TanhMLP, x0, xk, s, contraction, ridge) -> np.ndarray:
    """Exact minimiser of L_dyn over T's output layer, for the current hidden layer.

    T(x) = W phi(x) enters L_dyn linearly and A is diagonal, so each z component i is
    an independent least-squares problem: W_i (phi(x_K) - l_i^K phi(x_0)) = S_K,i.
    The three Gram matrices are shared by all components. Returns the residual per
    sample and component, shape ``(n, q)``.
    """
    P0, PK = _features(net, x0), _features(net, xk)
    G00, GKK, GK0 = P0.T @ P0, PK.T @ PK, PK.T @ P0
    rK, r0 = PK.T @ s, P0.T @ s
    coef = np.empty((s.shape[1], P0.shape[1]))
    for i, c in enumerate(contraction):
        G = GKK - c * (GK0 + GK0.T) + c**2 * G00
        coef[i] = _ridge_solve(G, rK[:, i] - c * r0[:, i], ridge)
    _set_output(net, coef)
    return PK @ coef.T - contraction * (P0 @ coef.T) - s


def train_kkl(system: DiscreteSystem, design: KKLDesign, config: TrainingConfig | None = None,
              data=None, progress: bool = True) -> tuple[KKLObserver, TrainingReport]:
    """Run Algorithm 1 and return the observer (numpy inference) and a report.

    Args:
        system: plant, used for its dimensions, domain, noise levels and (unless
            ``data`` is given) to generate transitions.
        design: eigenvalues of A and B.
        config: hyper-parameters.
        data: optional precomputed ``(x_k, x_{k+K}, (y_k..y_{k+K-1}))`` (e.g. from MuJoCo).
        progress: show tqdm bars.
    """
    cfg = config or TrainingConfig()
    t0 = time.perf_counter()
    torch.manual_seed(cfg.seed)
    torch.set_num_threads(cfg.threads)
    gen = torch.Generator().manual_seed(cfg.seed)
    rng = np.random.default_rng(cfg.seed)
    stages = tqdm(total=3, desc="Algorithm 1", disable=not progress, leave=False,
                  bar_format="{desc}: {n}/{total} {postfix}")
    stages.set_postfix_str("transitions")
    if data is None:
        data = transitions(system, cfg.n_samples, cfg.u_bar, rng, cfg.horizon)
    stages.update()
    stages.set_postfix_str("encoder T (L_dyn)")
    x_np, xk_np, ys_np = (np.asarray(a, dtype=np.float64) for a in data)
    if ys_np.ndim == 2:
        ys_np = ys_np[None]
    n = x_np.shape[0]
    lam = np.asarray(design.eigenvalues, dtype=float)
    B = design.B_array
    if B.shape[1] != system.n_output:
        raise ValueError(f"B has {B.shape[1]} columns but the system has "
                         f"{system.n_output} outputs")
    contraction = lam ** ys_np.shape[0]
    s_np = filtered_outputs(ys_np, lam, B)
    report = TrainingReport()

    # 1. T by L_dyn. Typical |z_i| = |B y| / (1 - l_i) scales the net's outputs to O(1).
    z_scale = np.abs(ys_np[0] @ B.T).mean(axis=0) / (1.0 - lam) + 1e-12
    center, half = system.domain_center, system.domain_halfwidth
    encoder = TanhMLP(system.n_state, cfg.hidden, design.q, center, half,
                      np.zeros(design.q), z_scale)
    if cfg.output_solve:
        _init_features(encoder, cfg.feature_scale, gen)
    X, XK, S = (torch.as_tensor(a, dtype=torch.float64) for a in (x_np, xk_np, s_np))
    A_t = torch.as_tensor(contraction, dtype=torch.float64)
    if cfg.encoder_epochs:
        weight = torch.ones(design.q)

        def loss_dyn(idx):
            res = encoder(XK[idx]) - (A_t * encoder(X[idx]) + S[idx])
            return (res**2 * weight).sum(dim=1).mean()

        # Algorithm 1: weight each residual by 1 / D(z_i)^2, D the spread of z_i.
        with torch.no_grad():
            weight = 1.0 / encoder(X[:20000]).std(dim=0).clamp_min(1e-9) ** 2
        report.loss_dyn = _adam(encoder, loss_dyn, n, cfg.encoder_epochs, cfg, gen,
                                "learn T (L_dyn)", progress)
    if cfg.output_solve:
        res = solve_encoder_output(encoder, x_np, xk_np, s_np, contraction, cfg.ridge)
    else:
        with torch.no_grad():
            res = (encoder(XK) - (A_t * encoder(X) + S)).double().numpy()
    stages.update()
    stages.set_postfix_str("decoder T* (L_recon)")

    # 2. Rescale z for good: z~ = z / D(z), B~ = B / D(z).
    with torch.no_grad():
        Z = encoder(X).double().numpy()
    spread = np.maximum(Z.std(axis=0), 1e-12)
    report.z_spread = spread.tolist()
    report.loss_dyn = float(((res / spread) ** 2).sum(axis=1).mean())
    Zs = Z / spread
    B_scaled = B / spread[:, None]

    # 3. T* by L_recon on z (+ the running observer's z noise).
    if cfg.decoder_noise == "observer":
        R = np.diag(system.measurement_noise_std**2)
        P = stationary_noise_covariance(lam, B_scaled, R) * cfg.decoder_noise_scale**2
        Zin = Zs + rng.standard_normal(Zs.shape) @ np.linalg.cholesky(
            P + 1e-12 * np.eye(design.q)).T
    else:
        Zin = Zs
    decoder = TanhMLP(design.q, cfg.decoder_hidden or cfg.hidden, system.n_state, Zs.mean(0),
                      Zs.std(0), center, half)
    if cfg.output_solve:
        _init_features(decoder, cfg.decoder_feature_scale or cfg.feature_scale, gen)
    Zin_t = torch.as_tensor(Zin, dtype=torch.float64)
    half_t = torch.as_tensor(half, dtype=torch.float64)
    if cfg.decoder_epochs:
        def loss_recon(idx):
            return (((decoder(Zin_t[idx]) - X[idx]) / half_t) ** 2).sum(dim=1).mean()

        _adam(decoder, loss_recon, n, cfg.decoder_epochs, cfg, gen, "learn T* (L_recon)",
              progress)
    if cfg.output_solve:
        F = _features(decoder, Zin)
        _set_output(decoder, _ridge_solve(F.T @ F, F.T @ x_np, cfg.ridge).T)
    with torch.no_grad():
        err = (decoder(Zin_t).double().numpy() - x_np) / half
    report.loss_recon = float((err**2).sum(axis=1).mean())

    stages.update()
    stages.close()
    enc_np = encoder.export().scaled_output(1.0 / spread)
    dec_np = decoder.export()
    report.seconds = time.perf_counter() - t0
    obs = KKLObserver(system, lam, B_scaled, enc_np, dec_np, u_bar=cfg.u_bar)
    obs.training_metadata = {
        "design": design.to_dict(),
        "training": asdict(cfg),
        "report": asdict(report),
    }
    return obs, report
