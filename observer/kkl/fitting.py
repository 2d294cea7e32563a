"""How the weights of the KKL maps are fitted: Adam on mini-batches, random tanh
features, and the exact least-squares output layers (``docs/observer.md``)."""

from __future__ import annotations

import math
import sys

import numpy as np
import torch
from tqdm.auto import tqdm

from observer.kkl.maps import TanhMLP


def cosine_lr(opt, step, total, lr0, lr1):
    frac = step / max(total - 1, 1)
    for group in opt.param_groups:
        group["lr"] = lr1 + 0.5 * (lr0 - lr1) * (1 + math.cos(math.pi * frac))


def adam(net: TanhMLP, loss_fn, n: int, epochs: int, cfg, gen, desc: str,
         progress: bool) -> float:
    """Minimise ``loss_fn(idx)`` over mini-batches; returns the last epoch's mean loss.

    ``cfg`` gives ``lr``, ``lr_final`` (cosine schedule) and ``batch_size``."""
    opt = torch.optim.Adam(net.parameters(), lr=cfg.lr)
    total = epochs * math.ceil(n / cfg.batch_size)
    step, epoch_loss = 0, math.nan
    bar = tqdm(range(epochs), desc=desc, disable=not progress, leave=False, file=sys.stderr)
    for _ in bar:
        epoch_loss = 0.0
        for idx in torch.randperm(n, generator=gen).split(cfg.batch_size):
            cosine_lr(opt, step, total, cfg.lr, cfg.lr_final)
            loss = loss_fn(idx)
            opt.zero_grad()
            loss.backward()
            opt.step()
            epoch_loss += loss.item() * len(idx)
            step += 1
        epoch_loss /= n
        bar.set_postfix(loss=f"{epoch_loss:.2e}")
    return epoch_loss


def init_features(net: TanhMLP, scale: float, gen) -> None:
    """Random tanh features spanning the normalised input box (a good start for the solve)."""
    w = net.hidden.weight
    with torch.no_grad():
        w.copy_(torch.randn(w.shape, generator=gen) * scale / math.sqrt(w.shape[1]))
        net.hidden.bias.copy_((torch.rand(w.shape[0], generator=gen) * 2 - 1) * scale)


def features(net: TanhMLP, v: np.ndarray) -> np.ndarray:
    """Last hidden layer's activations plus a constant column, float64, ``(n, H + 1)``."""
    if len(net.mids):
        with torch.no_grad():
            phi = net.activations(torch.as_tensor(v, dtype=torch.float64)).numpy()
    else:  # the common case, in numpy
        W = net.hidden.weight.detach().double().numpy()
        b = net.hidden.bias.detach().double().numpy()
        shift, scale = net.in_shift.double().numpy(), net.in_scale.double().numpy()
        phi = np.tanh(((v - shift) / scale) @ W.T + b)
    return np.hstack([phi, np.ones((v.shape[0], 1))])


def set_output(net: TanhMLP, coef: np.ndarray) -> None:
    """Write solved output weights ``coef`` (n_out, H + 1), in output units, into ``net``."""
    shift, scale = net.out_shift.double().numpy(), net.out_scale.double().numpy()
    coef = coef.copy()
    coef[:, -1] -= shift
    coef /= scale[:, None]
    with torch.no_grad():
        net.output.weight.copy_(torch.as_tensor(coef[:, :-1]))
        net.output.bias.copy_(torch.as_tensor(coef[:, -1]))


def ridge_solve(G: np.ndarray, rhs: np.ndarray, ridge: float) -> np.ndarray:
    reg = ridge * np.trace(G) / G.shape[0]
    return np.linalg.solve(G + reg * np.eye(G.shape[0]), rhs)


def solve_encoder_output(net: TanhMLP, x0, xk, s, contraction, ridge) -> np.ndarray:
    """Exact minimiser of L_dyn over T's output layer, for the current hidden layer.

    T(x) = W phi(x) enters L_dyn linearly and A is diagonal, so each z component i is
    an independent least-squares problem: W_i (phi(x_K) - l_i^K phi(x_0)) = S_K,i.
    The three Gram matrices are shared by all components. Returns the residual per
    sample and component, shape ``(n, q)``.
    """
    P0, PK = features(net, x0), features(net, xk)
    G00, GKK, GK0 = P0.T @ P0, PK.T @ PK, PK.T @ P0
    rK, r0 = PK.T @ s, P0.T @ s
    coef = np.empty((s.shape[1], P0.shape[1]))
    for i, c in enumerate(contraction):
        G = GKK - c * (GK0 + GK0.T) + c**2 * G00
        coef[i] = ridge_solve(G, rK[:, i] - c * r0[:, i], ridge)
    set_output(net, coef)
    return PK @ coef.T - contraction * (P0 @ coef.T) - s
