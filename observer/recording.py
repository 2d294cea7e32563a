"""What an estimator was given, call by call, so that a run can be replayed.

:class:`RecordingEstimator` runs any :class:`~observer.estimator.Estimator` and keeps
every call of its interface (``seed_run``, ``reset``, ``update``, ``predict``,
``adapt_noise``) with its arguments and what it returned. Replaying the calls in order
on a fresh estimator of the same kind (:func:`replay_calls`) gives the same estimates,
bit for bit; fed to another implementation of the same observer (an ONNX export), the
differences are that implementation's.

The record is a few flat arrays (:meth:`CallRecord.arrays`), for an ``.npz`` trace:

===========  ========  ============================================================
key          shape     meaning
===========  ========  ============================================================
call_kind    (m,)      index into :data:`CALLS`
call_step    (m,)      the control step it came in (steps end at each ``predict``)
call_args    (m, w)    its numbers (NaN-padded): y [W], x0 (and its covariance,
                       flattened), u, or (noise, y)
call_nargs   (m,)      how many of them are arguments (a missing y is NaN too)
call_out     (m, n)    the estimate it returned (NaN: none)
===========  ========  ============================================================
"""

from __future__ import annotations

import numpy as np

from observer.estimator import Estimator

#: The recorded calls, by their index in ``call_kind``.
CALLS = ("seed_run", "reset", "update", "predict", "adapt_noise")


class CallRecord:
    """The calls an estimator received (see the module docstring)."""

    def __init__(self, n_state: int, n_output: int):
        # A reset's arguments: x0, then its covariance (flattened) when one is given.
        self.n_state, self.width = n_state, max(n_state + n_state**2, n_output + 1, 1)
        self.kind: list[int] = []
        self.step: list[int] = []
        self.args: list[np.ndarray] = []
        self.out: list[np.ndarray | None] = []
        self.steps = 0

    def add(self, name: str, args=(), out=None) -> None:
        self.kind.append(CALLS.index(name))
        self.step.append(self.steps)
        self.args.append(np.asarray(args, dtype=float).reshape(-1))
        self.out.append(None if out is None else np.asarray(out, dtype=float).copy())
        if name == "predict":
            self.steps += 1

    def arrays(self) -> dict[str, np.ndarray]:
        """The record as the flat arrays of the module docstring."""
        m = len(self.kind)
        args = np.full((m, self.width), np.nan)
        out = np.full((m, self.n_state), np.nan)
        nargs = np.zeros(m, dtype=int)
        for i, (a, o) in enumerate(zip(self.args, self.out, strict=True)):
            args[i, :a.size], nargs[i] = a, a.size
            if o is not None:
                out[i] = o
        return {"call_kind": np.asarray(self.kind, dtype=int),
                "call_step": np.asarray(self.step, dtype=int), "call_args": args,
                "call_nargs": nargs, "call_out": out}


class RecordingEstimator(Estimator):
    """``inner`` as it is, keeping what it is given in :attr:`record`. Any other
    attribute is the inner estimator's."""

    def __init__(self, inner: Estimator):
        super().__init__(inner.system)
        self.inner = inner
        self.name = inner.name
        self.record = CallRecord(inner.system.n_state, inner.system.n_output)

    def __getattr__(self, name):  # only for what this class does not define
        return getattr(self.inner, name)

    @property
    def outside_domain(self) -> bool:
        return self.inner.outside_domain

    @property
    def models_its_noise(self) -> bool:
        return self.inner.models_its_noise

    def covariance(self):
        return self.inner.covariance()

    def seed_run(self, seed: int) -> None:
        self.record.add("seed_run", [seed])
        self.inner.seed_run(seed)

    def reset(self, x0=None, covariance=None) -> None:
        args = [] if x0 is None else list(np.asarray(x0, dtype=float).reshape(-1))
        if covariance is not None:
            args += list(np.asarray(covariance, dtype=float).reshape(-1))
        self.record.add("reset", args)
        self.inner.reset(x0, covariance)

    def update(self, y) -> np.ndarray:
        x = self.inner.update(y)
        self.record.add("update", y, x)
        return x

    def predict(self, u) -> None:
        self.record.add("predict", [u])
        self.inner.predict(u)

    def adapt_noise(self, noise_ratio: float, y=None):
        x = self.inner.adapt_noise(noise_ratio, y)
        self.record.add("adapt_noise", [noise_ratio] + ([] if y is None else list(y)), x)
        return x


def replay_calls(estimator: Estimator, arrays: dict[str, np.ndarray]) -> float:
    """Give ``estimator`` the recorded calls in order; returns the largest absolute
    difference between what it returns and what the record says was returned (0.0 when
    the record holds no estimate)."""
    worst = 0.0
    for kind, args, n, out in zip(arrays["call_kind"], arrays["call_args"],
                                  arrays["call_nargs"], arrays["call_out"], strict=True):
        a = args[:n]
        name = CALLS[int(kind)]
        if name == "seed_run":
            estimator.seed_run(int(a[0]))
        elif name == "reset":
            ns = estimator.system.n_state
            estimator.reset(a[:ns] if n else None,
                            a[ns:n].reshape(ns, ns) if n > ns else None)
        elif name == "update":
            worst = max(worst, difference(estimator.update(a), out))
        elif name == "predict":  # u: a float on one input, an array on more
            estimator.predict(float(a[0]) if n == 1 else np.array(a))
        else:
            x = estimator.adapt_noise(float(a[0]), a[1:] if n > 1 else None)
            if x is not None:
                worst = max(worst, difference(x, out))
    return worst


def difference(x, out) -> float:
    """Largest |x - out|; NaN in both is equal, NaN in one is infinitely far."""
    x = np.asarray(x, dtype=float)
    both = np.isnan(x) & np.isnan(out)
    d = np.where(both, 0.0, np.abs(x - out))
    return float(np.max(np.where(np.isnan(d), np.inf, d))) if d.size else 0.0
