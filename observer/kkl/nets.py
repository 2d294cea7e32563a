"""Inference of the KKL maps: tanh networks (one hidden layer, or more) on numpy arrays.

Training happens in torch (:mod:`observer.kkl.maps`); :meth:`TanhMLP.export` folds the
normalisations into the weights, so inference is exactly ``W2 tanh(W1 v + b1) + b2``
and needs neither torch nor its import time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def _tanh_inplace(h: np.ndarray) -> np.ndarray:
    """tanh(h) in place as 1 - 2 / (exp(2 h) + 1): numpy's exp is vectorised where its
    tanh is not (float64), twice as fast on a batch; within 4e-16 of np.tanh, and exact
    at the limits (exp overflows to inf, giving 1)."""
    np.multiply(h, 2.0, out=h)
    with np.errstate(over="ignore"):
        np.exp(h, out=h)
    h += 1.0
    np.divide(2.0, h, out=h)
    np.subtract(1.0, h, out=h)
    return h


@dataclass
class NumpyMLP:
    """``W2 a + b2`` with ``a = tanh(W1 v + b1)`` then ``a = tanh(W a + b)`` for each
    ``(W, b)`` of ``mid`` (none: one hidden layer), on arrays of shape ``(..., n_in)``."""

    W1: np.ndarray  # (H, n_in)
    b1: np.ndarray  # (H,)
    W2: np.ndarray  # (n_out, H)
    b2: np.ndarray  # (n_out,)
    mid: tuple = ()  # ((W (H, H), b (H,)), ...): further hidden layers

    def __post_init__(self):
        self._W1T = np.ascontiguousarray(self.W1.T)
        self._W2T = np.ascontiguousarray(self.W2.T)
        self._midT = [(np.ascontiguousarray(W.T), b) for W, b in self.mid]

    @property
    def n_in(self) -> int:
        return self.W1.shape[1]

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
            _tanh_inplace(h)
            for WT, b in self._midT:
                h = _tanh_inplace(h @ WT + b)
            np.matmul(h, self._W2T, out=out[i:i + chunk])
            out[i:i + chunk] += self.b2
        return out.reshape(v.shape[:-1] + (self.n_out,))

    def vector(self, v: np.ndarray) -> np.ndarray:
        """Single-sample path (1-D ``v``): matrix-vector products, no batch overhead."""
        h = np.tanh(v @ self._W1T + self.b1)  # row-major: fastest
        for WT, b in self._midT:
            h = np.tanh(h @ WT + b)
        return h @ self._W2T + self.b2

    def _compiled_weights(self) -> tuple[np.ndarray, ...]:
        """(W1^T, b1, W2, b2) contiguous, as the compiled kernels take one hidden
        layer (:func:`observer.kkl.compiled_fixed.mlp`)."""
        return tuple(np.ascontiguousarray(a) for a in (self._W1T, self.b1, self.W2,
                                                        self.b2))

    def astype(self, dtype) -> NumpyMLP:
        """A copy with weights of another dtype (float32 doubles batched throughput)."""
        return NumpyMLP(*(np.asarray(a, dtype=dtype) for a in (self.W1, self.b1, self.W2,
                                                               self.b2)),
                        tuple((W.astype(dtype), b.astype(dtype)) for W, b in self.mid))

    def scaled_output(self, scale: np.ndarray) -> NumpyMLP:
        """The same network with its output multiplied by ``scale`` component-wise."""
        return NumpyMLP(self.W1, self.b1, self.W2 * scale[:, None], self.b2 * scale,
                        self.mid)

    def arrays(self) -> dict[str, np.ndarray]:
        """The weights by name (W1, b1, W2, b2, and Wm<i>, bm<i> of each further layer)."""
        out = {k: getattr(self, k) for k in ("W1", "b1", "W2", "b2")}
        for i, (W, b) in enumerate(self.mid):
            out[f"Wm{i}"], out[f"bm{i}"] = W, b
        return out
