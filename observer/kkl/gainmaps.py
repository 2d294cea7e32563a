"""Maps that depend continuously on the observer's gain: one tanh hidden layer shared by
every gain, and output weights tabulated on a grid of gains (and noise levels),
interpolated linearly in log.

For a fixed hidden layer the exact least-squares output layer of T is a smooth (rational)
function of the eigenvalues; solving it on a fine grid of gains and interpolating gives
T(x; w) for every w of the range, each grid point as precise as a fixed-gain observer
(the same holds for T*'s output layer). A single network with w as an extra input was
measured 5-10x less precise for the same features (``docs/ablation.md``).
"""

from __future__ import annotations

import bisect
import math

import numpy as np

from observer import jit

compiled_maps = jit.lazy("observer.kkl.compiled_maps")


def _bracket(grid: np.ndarray, v: float) -> tuple[int, float]:
    """(i, t): v lies at (1 - t) grid[i] + t grid[i + 1], clipped to the grid."""
    if grid.size == 1:
        return 0, 0.0
    v = min(max(v, grid[0]), grid[-1])
    i = int(min(np.searchsorted(grid, v, side="right") - 1, grid.size - 2))
    return i, float((v - grid[i]) / (grid[i + 1] - grid[i]))


def _bracket_list(grid: list[float], v: float) -> tuple[int, float]:
    """:func:`_bracket` on a grid held as a list, in plain floats (a step's few calls)."""
    n = len(grid)
    if n == 1:
        return 0, 0.0
    v = min(max(v, grid[0]), grid[-1])
    i = min(bisect.bisect_right(grid, v) - 1, n - 2)
    return i, (v - grid[i]) / (grid[i + 1] - grid[i])


def _kept(cache: dict, key, make, most: int = 8):
    """``cache[key]``, made by ``make()`` when missing; the cache is emptied when it
    holds ``most`` (the few keys a run asks for again stay cheap, and memory stays
    bounded)."""
    value = cache.get(key)
    if value is None:
        value = make()
        if len(cache) >= most:
            cache.clear()
        cache[key] = value
    return value


_TRANSPOSED: dict = {}
#: Samples up to which a map runs compiled (:mod:`observer.kkl.compiled_maps`): a step's
#: one or two; a batch (training, the batched observer) stays with numpy's products.
_FEW = 4


def _transposed(W1: np.ndarray) -> list[np.ndarray]:
    """Each grid gain's hidden layer transposed, contiguous (for ``v @ W1^T``); one
    copy per read-only ``W1`` (a checkpoint's, shared by the maps of many runs)."""
    kept = _TRANSPOSED.get(id(W1))
    if kept is not None and kept[0] is W1:  # the entry holds W1: its id is not reused
        return kept[1]
    out = [np.ascontiguousarray(W.T) for W in (W1[None] if W1.ndim == 2 else W1)]
    if not W1.flags.writeable:
        if len(_TRANSPOSED) >= 16:
            _TRANSPOSED.clear()
        _TRANSPOSED[id(W1)] = (W1, out)
    return out


_STACKED: dict = {}


def _stacked(W1: np.ndarray, transposed: list[np.ndarray]) -> np.ndarray:
    """The hidden layers transposed as one array (n_w or 1, n_in, H), for the kernels;
    one copy per read-only ``W1``, shared by the maps of many runs as :func:`_transposed`
    shares its list (a copy each, 64 seeds' decoders did not fit the cache)."""
    kept = _STACKED.get(id(W1))
    if kept is not None and kept[0] is W1:
        return kept[1]
    out = np.ascontiguousarray(np.stack(transposed))
    if not W1.flags.writeable:
        if len(_STACKED) >= 16:
            _STACKED.clear()
        _STACKED[id(W1)] = (W1, out)
    return out


class GainTableMap:
    """``coef(log w, log s) @ [tanh(W1 v + b1), 1]``.

    Args:
        W1, b1: the hidden layer, shapes (H, n_in), (H,); or one per grid gain, shapes
            (n_w, H, n_in), (n_w, H) (each gain's inputs spread differently), in which
            case the outputs of the two grid gains around w are interpolated.
        coef: output weights, shape (n_w, n_s, n_out, H + 1).
        log_w: the grid of log gains, increasing, shape (n_w,).
        log_s: the grid of log noise levels, increasing, shape (n_s,) (one point: no
            noise dependence).
    """

    def __init__(self, W1, b1, coef, log_w, log_s):
        self.W1, self.b1 = np.asarray(W1, float), np.asarray(b1, float)
        self.coef = np.asarray(coef, float)
        self.log_w, self.log_s = np.asarray(log_w, float), np.asarray(log_s, float)
        self.shared = self.W1.ndim == 2
        self._W1T = _transposed(self.W1)
        self._b1 = self.b1[None] if self.shared else self.b1
        self._rows: dict = {}
        self._weights: dict = {}
        self._kernel = self._grids = None  # the compiled path's (kernel_arrays)

    @property
    def n_in(self) -> int:
        return self.W1.shape[-1]

    @property
    def n_out(self) -> int:
        return self.coef.shape[2]

    def consistent(self) -> bool:
        H = self.W1.shape[-2] if self.W1.ndim >= 2 else -1
        n_w = self.log_w.size
        hidden_ok = (self.W1.ndim == 2 and self.b1.shape == (H,)) or \
            (self.W1.ndim == 3 and self.W1.shape[0] == n_w and self.b1.shape == (n_w, H))
        return (hidden_ok and self.coef.ndim == 4
                and self.coef.shape[0] == self.log_w.size and self.coef.shape[3] == H + 1
                and self.coef.shape[1] == self.log_s.size and self.log_w.ndim == 1
                and bool(np.all(np.diff(self.log_w) > 0)) and self.log_s.ndim == 1
                and bool(np.all(np.diff(self.log_s) > 0)))

    def _row(self, i: int, b: float, j: int) -> np.ndarray:
        """Grid gain i's weights at noise (1 - b) s_j + b s_j+1; the last few kept, as
        a gain moving inside one bracket of the grid asks for the same rows again."""
        C = self.coef
        return _kept(self._rows, (i, b, j),
                     lambda: (1 - b) * C[i, j] + b * C[i, min(j + 1, C.shape[1] - 1)])

    def weights(self, w: float, s: float = 1.0) -> tuple:
        """(i, a, weights at grid gain i, at grid gain i + 1) for gain w and noise s;
        for a shared hidden layer the interpolated weights alone. The last few are
        kept: a change of gain asks for the old gain's and the new one's in turn."""
        return _kept(self._weights, (w, s), lambda: self._interpolated(w, s))

    def _interpolated(self, w: float, s: float) -> tuple:
        i, a = _bracket(self.log_w, float(np.log(w)))
        j, b = _bracket(self.log_s, float(np.log(s)))
        i1 = min(i + 1, self.coef.shape[0] - 1)
        lo, hi = self._row(i, b, j), self._row(i1, b, j)
        return ((1 - a) * lo + a * hi) if self.shared else (i, a, lo, hi)

    def features(self, v: np.ndarray, i: int = 0) -> np.ndarray:
        """The hidden layer (of grid gain i) plus a constant column."""
        hidden = np.asarray(v, float) @ self._W1T[i] + self._b1[i]
        out = np.empty(hidden.shape[:-1] + (hidden.shape[-1] + 1,))
        np.tanh(hidden, out=out[..., :-1])
        out[..., -1] = 1.0
        return out

    def __call__(self, v: np.ndarray, w: float, s: float = 1.0) -> np.ndarray:
        """The map at gain w and noise s, on inputs of shape (..., n_in)."""
        v = np.asarray(v, float)
        if jit.enabled() and v.size <= _FEW * v.shape[-1] and v.flags.c_contiguous:
            return self._compiled(v, w, s)
        if self.shared:
            return self.features(v) @ self.weights(w, s).T
        i, a, lo, hi = self.weights(w, s)
        out = (1 - a) * (self.features(v, i) @ lo.T)
        if a > 0:
            out = out + a * (self.features(v, i + 1) @ hi.T)
        return out

    def kernel_arrays(self) -> tuple:
        """(hidden layers (n_w or 1, n_in, H), their biases (n_w or 1, H), coef, log_w,
        log_s): the map as the compiled kernels take it, made once."""
        if self._kernel is None:
            self._kernel = (_stacked(self.W1, self._W1T), np.ascontiguousarray(self._b1),
                            self.coef, self.log_w, self.log_s)
            self._last = (None, None)
        return self._kernel

    def shared_weights(self, w: float, s: float = 1.0) -> np.ndarray:
        """A shared hidden layer's output weights at (w, s), shape (1, 1, n_out, H + 1),
        as the kernels take them (interpolated by a kernel, as :meth:`weights` does);
        the last call's when (w, s) are the same."""
        coef = self.kernel_arrays()[2]
        key, C = self._last
        if key != (w, s):
            C = compiled_maps.interpolated_weights(coef, *self._brackets(w, s))
            self._last = (w, s), C
        return C

    def _brackets(self, w: float, s: float) -> tuple:
        """(i, i + 1, a, j, j + 1, b): the grid gains around w and the grid noises around
        s, each clipped to its grid, and where w and s lie between them."""
        if self._grids is None:
            self._grids = self.log_w.tolist(), self.log_s.tolist()
        i, a = _bracket_list(self._grids[0], math.log(w))
        j, b = _bracket_list(self._grids[1], math.log(s))
        n_w, n_s = self.coef.shape[:2]
        return i, min(i + 1, n_w - 1), a, j, min(j + 1, n_s - 1), b

    def _compiled(self, v: np.ndarray, w: float, s: float) -> np.ndarray:
        """:meth:`__call__` on a few samples, in one compiled call
        (:func:`~observer.kkl.compiled_maps.map_rows`). Per-gain hidden layers
        interpolate their output weights in the noise as they go (the noise moves every
        step: a cache would miss); a shared one takes :meth:`shared_weights`."""
        W1T, b1, coef, _, _ = self.kernel_arrays()
        rows = v.reshape(-1, v.shape[-1])
        out = np.empty((rows.shape[0], self.n_out))
        if self.shared:
            compiled_maps.map_rows(rows, W1T, b1, self.shared_weights(w, s), 0, 0, 0.0, 0, 0,
                                   0.0, True, out)
        else:
            compiled_maps.map_rows(rows, W1T, b1, coef, *self._brackets(w, s), False, out)
        return out.reshape(v.shape[:-1] + (self.n_out,))

    def arrays(self) -> dict[str, np.ndarray]:
        return {"W1": self.W1, "b1": self.b1, "coef": self.coef, "log_w": self.log_w,
                "log_s": self.log_s}
