"""One-hidden-layer tanh networks for the KKL maps, in torch (training) and numpy (inference).

Inputs and outputs are normalised with fixed affine maps so the trainable layers see
O(1) numbers; :meth:`TanhMLP.export` folds those maps into the weights, so the numpy
path is exactly ``W2 tanh(W1 v + b1) + b2``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from torch import nn


class TanhMLP(nn.Module):
    """``out_shift + out_scale * (W2 tanh(W1 (v - in_shift) / in_scale + b1) + b2)``."""

    def __init__(self, n_in: int, n_hidden: int, n_out: int,
                 in_shift, in_scale, out_shift, out_scale):
        super().__init__()
        # float64 throughout: the least-squares output layer has large, cancelling
        # coefficients that float32 would round away.
        self.hidden = nn.Linear(n_in, n_hidden, dtype=torch.float64)
        self.output = nn.Linear(n_hidden, n_out, dtype=torch.float64)
        for name, value in (("in_shift", in_shift), ("in_scale", in_scale),
                            ("out_shift", out_shift), ("out_scale", out_scale)):
            self.register_buffer(name, torch.as_tensor(np.asarray(value), dtype=torch.float64))

    def forward(self, v: torch.Tensor) -> torch.Tensor:
        a = torch.tanh(self.hidden((v - self.in_shift) / self.in_scale))
        return self.out_shift + self.out_scale * self.output(a)

    def export(self) -> NumpyMLP:
        """The same function as float64 numpy arrays with the normalisations folded in."""
        W1 = self.hidden.weight.detach().double().numpy()
        b1 = self.hidden.bias.detach().double().numpy()
        W2 = self.output.weight.detach().double().numpy()
        b2 = self.output.bias.detach().double().numpy()
        in_shift, in_scale = (self.in_shift.double().numpy(), self.in_scale.double().numpy())
        out_shift, out_scale = (self.out_shift.double().numpy(), self.out_scale.double().numpy())
        W1f = W1 / in_scale[None, :]
        b1f = b1 - W1f @ in_shift
        W2f = W2 * out_scale[:, None]
        b2f = b2 * out_scale + out_shift
        return NumpyMLP(W1f, b1f, W2f, b2f)


@dataclass
class NumpyMLP:
    """``W2 tanh(W1 v + b1) + b2`` on arrays of shape ``(..., n_in)``."""

    W1: np.ndarray  # (H, n_in)
    b1: np.ndarray  # (H,)
    W2: np.ndarray  # (n_out, H)
    b2: np.ndarray  # (n_out,)

    def __post_init__(self):
        self._W1T = np.ascontiguousarray(self.W1.T)
        self._W2T = np.ascontiguousarray(self.W2.T)

    @property
    def n_in(self) -> int:
        return self.W1.shape[1]

    @property
    def n_hidden(self) -> int:
        return self.W1.shape[0]

    @property
    def n_out(self) -> int:
        return self.W2.shape[0]

    def __call__(self, v: np.ndarray, chunk: int = 2048) -> np.ndarray:
        v = np.asarray(v)
        if v.ndim == 1:
            return self.vector(v)
        flat = v.reshape(-1, self.n_in)
        out = np.empty((flat.shape[0], self.n_out), dtype=np.result_type(flat, self.W2))
        # Chunks keep the hidden activations in cache (5-10x faster than one huge product).
        for i in range(0, flat.shape[0], chunk):
            h = flat[i:i + chunk] @ self._W1T
            h += self.b1
            np.tanh(h, out=h)
            np.matmul(h, self._W2T, out=out[i:i + chunk])
            out[i:i + chunk] += self.b2
        return out.reshape(v.shape[:-1] + (self.n_out,))

    def vector(self, v: np.ndarray) -> np.ndarray:
        """Single-sample path (1-D ``v``): matrix-vector products, no batch overhead."""
        return np.tanh(v @ self._W1T + self.b1) @ self._W2T + self.b2  # row-major: fastest

    def astype(self, dtype) -> NumpyMLP:
        """A copy with weights of another dtype (float32 doubles batched throughput)."""
        return NumpyMLP(*(np.asarray(a, dtype=dtype) for a in (self.W1, self.b1, self.W2,
                                                               self.b2)))

    def scaled_output(self, scale: np.ndarray) -> NumpyMLP:
        """The same network with its output multiplied by ``scale`` component-wise."""
        return NumpyMLP(self.W1, self.b1, self.W2 * scale[:, None], self.b2 * scale)

    def to_tensors(self, prefix: str) -> dict[str, torch.Tensor]:
        return {f"{prefix}.{k}": torch.from_numpy(np.ascontiguousarray(getattr(self, k)))
                for k in ("W1", "b1", "W2", "b2")}

    @classmethod
    def from_tensors(cls, tensors: dict, prefix: str) -> NumpyMLP:
        return cls(*(tensors[f"{prefix}.{k}"].double().numpy() for k in ("W1", "b1", "W2", "b2")))
