"""The learned Kazantzis-Kravaris-Luenberger observer (paper section 3).

    z_{k+1} = A z_k + B y_k + Omega(z_k, u_k),      x_hat_k = T*(z_k)
    Omega(z, u) = T(f(T*(z), u)) - T(f(T*(z), u_bar))               (eq. equatcol1a)

``A`` is diagonal (its eigenvalues are stored), ``T`` is the learned encoder
(``encoder_T``) and ``T*`` the learned decoder (``decoder_T_star``), both numpy MLPs.
``z`` is kept in the rescaled coordinates of Algorithm 1 (each component divided by its
spread over the training set), so ``B`` here is the rescaled one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from observer import jit
from observer.estimator import Estimator, usable_mask
from observer.exceptions import ObserverError
from observer.kkl.nets import NumpyMLP
from observer.system import DiscreteSystem

compiled_fixed = jit.lazy("observer.kkl.compiled_fixed")


@dataclass(frozen=True)
class KKLDesign:
    """The linear part of the observer: eigenvalues of the diagonal A and the matrix B.

    Attributes:
        eigenvalues: diagonal of A, each in (0, 1) (discrete-time Hurwitz).
        B: input matrix, shape (q, p), as nested tuples (JSON-able).
        name: label used in tables.
    """

    eigenvalues: tuple[float, ...]
    B: tuple[tuple[float, ...], ...]
    name: str = "custom"

    def __post_init__(self):
        lam = np.asarray(self.eigenvalues)
        B = np.asarray(self.B)
        if lam.ndim != 1 or not np.all((lam > -1) & (lam < 1)):
            raise ObserverError(f"eigenvalues={self.eigenvalues!r}: all must lie in (-1, 1)")
        if B.shape[0] != lam.size:
            raise ObserverError(f"B has {B.shape[0]} rows but A has {lam.size} eigenvalues")

    @property
    def B_array(self) -> np.ndarray:
        return np.asarray(self.B, dtype=float)

    @property
    def q(self) -> int:
        return len(self.eigenvalues)

    @classmethod
    def paper(cls, Te: float) -> KKLDesign:
        """The paper's literal choice: A = diag(1 - Te [1, 2, 4, 6, 8, 10]), B = ones(6, 2)."""
        lam = tuple(1.0 - Te * r for r in (1, 2, 4, 6, 8, 10))
        return cls(lam, tuple((1.0, 1.0) for _ in lam), "paper")

    @classmethod
    def split(cls, Te: float, rates=(1, 2, 4, 6, 8, 10), n_output: int = 2,
              name: str = "split") -> KKLDesign:
        """Each output drives its own copy of the filter bank diag(1 - Te * rates).

        With B = ones every z component only sees y1 + y2; here y1 and y2 are filtered
        separately (q = n_output * len(rates)), the structure of Andrieu-Praly's KKL design.
        """
        lam, rows = [], []
        for j in range(n_output):
            for r in rates:
                lam.append(1.0 - Te * r)
                rows.append(tuple(1.0 if i == j else 0.0 for i in range(n_output)))
        return cls(tuple(lam), tuple(rows), name)

    def to_dict(self) -> dict:
        return {"name": self.name, "eigenvalues": list(self.eigenvalues),
                "B": [list(r) for r in self.B]}

    @classmethod
    def from_dict(cls, d: dict) -> KKLDesign:
        return cls(tuple(d["eigenvalues"]), tuple(tuple(r) for r in d["B"]), d.get("name", ""))


def stationary_noise_covariance(eigenvalues, B, R) -> np.ndarray:
    """Covariance P of z's response to white measurement noise of covariance R.

    Solves P = A P A^T + B R B^T for diagonal A: P_ij = (B R B^T)_ij / (1 - l_i l_j).
    """
    lam = np.asarray(eigenvalues, dtype=float)
    BRB = np.asarray(B) @ np.asarray(R) @ np.asarray(B).T
    return BRB / (1.0 - np.outer(lam, lam))


def series_encoder(system: DiscreteSystem, eigenvalues, B, x, steps: int = 3000) -> np.ndarray:
    """T(x) = sum_j A^j B h(f^-(j+1)(x, u_bar=0)), paper eq. (equat3a), by brute force.

    Needs ``system.f_inverse`` (a time-reversible closed-form model); used to check a
    learned encoder. Truncated after ``steps`` terms (A^steps must be negligible).
    """
    lam = np.asarray(eigenvalues, dtype=float)
    B = np.asarray(B, dtype=float)
    z = np.zeros((len(x), lam.size))
    xb = np.array(x, dtype=float)
    for j in range(steps):
        xb = system.f_inverse(xb)
        z += lam**j * (system.h(xb) @ B.T)
    return z


class KKLObserver(Estimator):
    """Learned KKL observer with a fast numpy inference path.

    Args:
        system: the plant (gives f for the Omega correction and the dimensions).
        eigenvalues: diagonal of A, shape (q,).
        B: rescaled input matrix, shape (q, p).
        encoder_T: numpy MLP x -> z (rescaled coordinates).
        decoder_T_star: numpy MLP z -> x.
        u_bar: the constant input the maps were learned for.
        use_omega: apply the Omega(z, u) correction when u != u_bar.

    On the compiled path (:mod:`observer.jit`) a two-state system that gives its f as
    numbers (``compiled_f``: the identified gimbal model, one axis of a pan-tilt head),
    with maps of one hidden layer, runs :mod:`observer.kkl.compiled_fixed`; this class's
    methods stay the reference.
    """

    name = "kkl"

    def __init__(self, system: DiscreteSystem, eigenvalues, B, encoder_T: NumpyMLP,
                 decoder_T_star: NumpyMLP, u_bar: float = 0.0, use_omega: bool = True):
        super().__init__(system)
        self.eigenvalues = np.asarray(eigenvalues, dtype=float)
        self.B = np.asarray(B, dtype=float)
        self.encoder_T = encoder_T
        self.decoder_T_star = decoder_T_star
        self.u_bar = float(u_bar)
        self.use_omega = use_omega
        self.z = np.zeros(self.q)
        self._y = None
        self._xhat = None

    @property
    def q(self) -> int:
        return self.eigenvalues.size

    # -- the maps ------------------------------------------------------------------------

    def encode(self, x: np.ndarray) -> np.ndarray:
        """z = T(x), batched."""
        return self.encoder_T(np.asarray(x, dtype=float))

    def decode(self, z: np.ndarray) -> np.ndarray:
        """x_hat = T*(z), batched."""
        return self.decoder_T_star(np.asarray(z, dtype=float))

    def omega_correction(self, z: np.ndarray, u, xhat: np.ndarray | None = None) -> np.ndarray:
        """Omega(z, u) = T(f(T*(z), u)) - T(f(T*(z), u_bar)), batched over z."""
        xh = self.decode(z) if xhat is None else xhat
        f = self.system.f
        return self.encode(f(xh, u)) - self.encode(f(xh, self.u_bar))

    # -- Estimator interface (one trajectory) ----------------------------------------------

    def reset(self, x0=None, covariance=None) -> None:  # no covariance to set
        self.z = self.encode(self.initial_guess(x0))
        self._y = None
        self._xhat = None
        self.outside_domain = False

    def _compiled_numbers(self) -> tuple | None:
        """The kernels' constants (f's coefficients, the box, the outputs' bounds, the
        maps' weights), or None where the reference runs."""
        nets = (self.encoder_T, self.decoder_T_star)
        numbers = getattr(self, "_numbers", None)
        if numbers is None or numbers[0] is not nets[0] or numbers[1] is not nets[1]:
            s = self.system
            numbers = (*nets, None)  # the maps they are for, then the constants
            if hasattr(s, "compiled_f") and s.n_state == 2 and s.n_input == 1 and all(
                    isinstance(n, NumpyMLP) and not n.mid and n.W1.dtype == np.float64
                    for n in nets):
                bounded = s.output_low is not None
                y_box = [np.ascontiguousarray(np.broadcast_to(
                    np.asarray(v if bounded else 0.0, dtype=float), (s.n_output,)))
                    for v in (s.output_low, s.output_high)]
                box = [np.array(v, dtype=float) for v in zip(*self._box, strict=True)]
                numbers = (*nets, (tuple(np.ascontiguousarray(c, dtype=float)
                                         for c in s.compiled_f()), *box, *y_box, bounded,
                                   *(tuple(n._compiled_weights()) for n in nets)))
            self._numbers = numbers
        return numbers[2] if jit.enabled() else None

    def update(self, y) -> np.ndarray:
        y = np.asarray(y, dtype=float)
        c = self._compiled_numbers()
        if c is not None and y.ndim == 1:
            xhat, inside, usable = compiled_fixed.update(self.z, y, *c[7], *c[1:6])
            self._xhat, self.outside_domain = xhat, not inside
            self._y = y if usable else \
                np.where(usable_mask(self.system, y), y, self.system.h(xhat))
            return xhat
        self._xhat = self.decoder_T_star.vector(self.z)
        self.outside_domain = not self.in_domain(self._xhat)
        ok = usable_mask(self.system, y)
        if not ok.all():
            # Hold the prediction: a missing power is replaced by h(x_hat).
            y = np.where(ok, y, self.system.h(self._xhat))
        self._y = y
        return self._xhat

    def predict(self, u) -> None:
        c = self._compiled_numbers()
        if c is not None and isinstance(u, float | int):
            self.z, inside = compiled_fixed.predict(
                self.z, self._y, self._xhat, float(u), self.u_bar, bool(self.use_omega),
                self.eigenvalues, self.B, *c[0], *c[6], *c[1:3])
            self.outside_domain = self.outside_domain or not inside
            return
        z_next = self.eigenvalues * self.z + self.B @ self._y
        moved = (u != self.u_bar) if isinstance(u, float | int) else \
            np.any(np.asarray(u, dtype=float) != self.u_bar)
        if self.use_omega and moved:  # single-sample Omega: matrix-vector products only
            f, enc, xh = self.system.f, self.encoder_T.vector, self._xhat
            driven = f(xh, u)
            self.outside_domain = self.outside_domain or not self.in_domain(driven)
            z_next = z_next + enc(driven) - enc(f(xh, self.u_bar))
        self.z = z_next

    # -- many trajectories of the autonomous observer ---------------------------------

    def run_trajectories(self, ys: np.ndarray, x0: np.ndarray | None = None,
                  dtype=np.float64) -> np.ndarray:
        """Estimates for ``B_traj`` trajectories at once, at u = u_bar with every sample
        present: the linear recursion z' = A z + B y first, then one large decode (what
        :meth:`update` and :meth:`predict` give step by step, much faster).

        Args:
            ys: measurements, shape ``(N, B_traj, p)``, all usable.
            x0: initial guesses, shape ``(B_traj, n)``; default the domain centre.
            dtype: precision of the decode (float32 is about twice as fast; z itself is
                always propagated in float64).

        Returns:
            x_hat, shape ``(N, B_traj, n)``.
        """
        ys = np.asarray(ys, dtype=float)
        if not usable_mask(self.system, ys).all():
            raise ObserverError("run_trajectories needs every sample usable: step a run with "
                                "missing samples through update and predict")
        n_steps, n_traj, _ = ys.shape
        guess = self.system.domain_center if x0 is None else x0
        z = self.encode(np.broadcast_to(guess, (n_traj, self.system.n_state)))
        zs = np.empty((n_steps, n_traj, self.q))
        By = ys @ self.B.T
        for k in range(n_steps):
            zs[k] = z
            z = self.eigenvalues * z + By[k]
        decoder = self.decoder_T_star if dtype == np.float64 else \
            self.decoder_T_star.astype(dtype)
        flat = zs.reshape(-1, self.q).astype(dtype, copy=False)
        return decoder(flat).astype(np.float64).reshape(n_steps, n_traj, -1)
