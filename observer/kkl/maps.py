"""The KKL maps as torch modules, for training (Algorithm 1).

Inputs and outputs are normalised with fixed affine maps so the trainable layers see
O(1) numbers; :meth:`TanhMLP.export` folds those maps into the weights of a
:class:`~observer.kkl.nets.NumpyMLP`.
"""

from __future__ import annotations

import numpy as np
import torch
from torch import nn

from observer.kkl.nets import NumpyMLP


class TanhMLP(nn.Module):
    """``out_shift + out_scale * (W2 a + b2)`` with ``a = tanh(W1 (v - in_shift) /
    in_scale + b1)``, and ``n_layers - 1`` more tanh layers of the same width in between
    (``n_layers = 1``: the paper's one hidden layer)."""

    def __init__(self, n_in: int, n_hidden: int, n_out: int,
                 in_shift, in_scale, out_shift, out_scale, n_layers: int = 1):
        super().__init__()
        # float64 throughout: the least-squares output layer has large, cancelling
        # coefficients that float32 would round away.
        self.hidden = nn.Linear(n_in, n_hidden, dtype=torch.float64)
        self.mids = nn.ModuleList(nn.Linear(n_hidden, n_hidden, dtype=torch.float64)
                                  for _ in range(n_layers - 1))
        self.output = nn.Linear(n_hidden, n_out, dtype=torch.float64)
        for name, value in (("in_shift", in_shift), ("in_scale", in_scale),
                            ("out_shift", out_shift), ("out_scale", out_scale)):
            self.register_buffer(name, torch.as_tensor(np.asarray(value), dtype=torch.float64))

    def activations(self, v: torch.Tensor) -> torch.Tensor:
        """The last hidden layer's activations (what the output layer combines)."""
        a = torch.tanh(self.hidden((v - self.in_shift) / self.in_scale))
        for m in self.mids:
            a = torch.tanh(m(a))
        return a

    def forward(self, v: torch.Tensor) -> torch.Tensor:
        return self.out_shift + self.out_scale * self.output(self.activations(v))

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
        mid = tuple((m.weight.detach().double().numpy(), m.bias.detach().double().numpy())
                    for m in self.mids)
        return NumpyMLP(W1f, b1f, W2f, b2f, mid)
