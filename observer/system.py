"""The small system interface every estimator in :mod:`observer` works through.

A :class:`DiscreteSystem` is a discrete-time plant

    x_{k+1} = f(x_k, u_k) + w_k,      y_k = h(x_k) + v_k,

with its dimensions, sampling period ``Te``, a box ``domain`` on which observers
are trained, and the noise levels the filters assume. Nothing here knows about
LEDs: the closed-form paper model and the MuJoCo world both implement it.

All functions are batched: ``x`` has shape ``(..., n_state)``, ``u`` shape
``(..., n_input)``, ``h(x)`` shape ``(..., n_output)``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from observer.noise import MeasurementNoise


class DiscreteSystem(ABC):
    """Abstract discrete-time system ``x' = f(x, u)``, ``y = h(x)``.

    Subclasses set the attributes below and implement :meth:`f` and :meth:`h`.

    Attributes:
        n_state: state dimension n.
        n_output: output dimension p.
        n_input: input dimension m.
        Te: sampling period [s].
        domain_low, domain_high: corners of the training box, shape ``(n_state,)``.
        process_noise_std: standard deviation of w_k per step, shape ``(n_state,)``.
        measurement_noise_std: standard deviation of v_k, shape ``(n_output,)``.
        measurement_noise: the :class:`~observer.noise.MeasurementNoise` v_k is drawn
            from (None: only ``measurement_noise_std`` is known).
        state_names, output_names: labels (with units) for tables and plots.
    """

    n_state: int
    n_output: int
    n_input: int
    Te: float
    domain_low: np.ndarray
    domain_high: np.ndarray
    process_noise_std: np.ndarray
    measurement_noise_std: np.ndarray
    measurement_noise: MeasurementNoise | None = None
    state_names: tuple[str, ...] = ()
    output_names: tuple[str, ...] = ()
    #: Physically possible measurements, shape ``(n_output,)`` each (None: any finite
    #: value). Estimators treat a measurement outside as missing, like a dropout.
    output_low: np.ndarray | None = None
    output_high: np.ndarray | None = None

    @abstractmethod
    def f(self, x: np.ndarray, u: np.ndarray | float) -> np.ndarray:
        """Noise-free transition x_{k+1} = f(x_k, u_k)."""

    @abstractmethod
    def h(self, x: np.ndarray) -> np.ndarray:
        """Noise-free output y_k = h(x_k)."""

    def metadata(self) -> dict:
        """JSON-able description (constants) used to check that a checkpoint fits."""
        return {
            "class": type(self).__name__,
            "Te": float(self.Te),
            "n_state": self.n_state,
            "n_output": self.n_output,
            "n_input": self.n_input,
            "domain_low": [float(v) for v in self.domain_low],
            "domain_high": [float(v) for v in self.domain_high],
        }

    # -- helpers shared by every system ---------------------------------------------------

    def set_model(self, Te: float, domain_halfwidth, process_noise_std,
                  noise: MeasurementNoise, output_range=(None, None)) -> None:
        """Set the attributes every system has: the period ``Te`` [s], the training box
        +-``domain_halfwidth``, the process noise, the measurement ``noise`` (and its
        standard deviations) and the plausible (low, high) of each output."""
        self.Te = Te
        self.domain_high = np.array(domain_halfwidth, dtype=float)
        self.domain_low = -self.domain_high
        self.process_noise_std = np.array(process_noise_std, dtype=float)
        self.measurement_noise = noise
        self.measurement_noise_std = noise.std_at()
        self.output_low, self.output_high = output_range

    def input_array(self, u, batch_shape: tuple[int, ...] = ()) -> np.ndarray:
        """Broadcast a scalar or array input to shape ``batch_shape + (n_input,)``."""
        u = np.asarray(u, dtype=float)
        if u.ndim == 0 or u.shape[-1] != self.n_input:
            u = u[..., None]
        return np.broadcast_to(u, batch_shape + (self.n_input,))

    @property
    def domain_center(self) -> np.ndarray:
        return 0.5 * (np.asarray(self.domain_low) + np.asarray(self.domain_high))

    @property
    def domain_halfwidth(self) -> np.ndarray:
        return 0.5 * (np.asarray(self.domain_high) - np.asarray(self.domain_low))

    def sample_domain(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` states drawn uniformly from the training box, shape ``(n, n_state)``."""
        return rng.uniform(self.domain_low, self.domain_high, size=(n, self.n_state))

    def f_jacobian(self, x: np.ndarray, u, eps: float = 1e-6) -> np.ndarray:
        """df/dx at ``x`` (central differences unless a subclass knows better), ``(..., n, n)``."""
        return _central_jacobian(lambda v: self.f(v, u), x, eps)

    def h_jacobian(self, x: np.ndarray, eps: float = 1e-6) -> np.ndarray:
        """dh/dx at ``x``, shape ``(..., p, n)``."""
        return _central_jacobian(self.h, x, eps)


def _central_jacobian(fun, x: np.ndarray, eps: float) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    n = x.shape[-1]
    cols = []
    for i in range(n):
        dx = np.zeros(n)
        dx[i] = eps
        cols.append((fun(x + dx) - fun(x - dx)) / (2 * eps))
    return np.stack(cols, axis=-1)
