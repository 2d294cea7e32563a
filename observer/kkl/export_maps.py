"""The gain-scheduled KKL's maps as one ONNX graph, to run on the vehicle's computer.

:class:`~observer.kkl.scheduled.ScheduledKKL` is a fixed-gain KKL whose gain w moves:
all its learned arithmetic is three maps of :class:`~observer.kkl.gainmaps.
GainTableMap` (a tanh layer, output weights interpolated in log w and log s), and the
rest is a few scalar lines (the averaging filters z' = z + a(w) (y - z), the schedule
of w over the time since a restart, the blend into the locked decoder). The graph holds
the maps, in float64:

================  ========  ======================================================
name              shape     meaning
================  ========  ======================================================
x                 (N, n)    input: states for the encoder
z                 (M, q)    input: observer states for the decoders
w                 (1,)      input: the gain [-] (the design's w_range)
s                 (1,)      input: the noise over the nominal [-] (the decoders')
T                 (N, q)    output: the encoder T(x; w) (at s = 1, as the observer)
T_star            (M, n)    output: the decoder T*(z; w, s)
T_star_locked     (M, n)    output: the locked decoder's (when the observer has one)
================  ========  ======================================================

:class:`OnnxGainMap` runs one output through onnxruntime with the numpy map's call
signature, so a :class:`ScheduledKKL` given them (:func:`onnx_scheduled`) is the numpy
observer with its arithmetic in the graph: ``ledsim replay --onnx`` holds the two to
1e-6.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from observer.exceptions import ObserverError
from observer.kkl.export import _Graph
from observer.kkl.gainmaps import GainTableMap

#: The graph's kind (its metadata ``ledsim_kind``), which ``ledsim replay`` reads.
KIND = "scheduled-kkl-maps"


def _scalar(g: _Graph, v: str) -> str:
    return g.op("Reshape", v, g.const(np.zeros(0, dtype=np.int64)))


def _bracket(g: _Graph, grid: np.ndarray, v: str | None) -> tuple[str, str]:
    """(i, t) of :func:`observer.kkl.gainmaps._bracket`: scalar int64 and double
    (``v`` None: 0.0)."""
    if grid.size == 1:
        return g.const(np.int64(0)), g.const(0.0)
    if v is None:
        v = g.const(0.0)
    v = g.op("Clip", v, g.const(float(grid[0])), g.const(float(grid[-1])))
    below = g.op("Cast", g.op("LessOrEqual", g.const(grid), v), to=7)  # INT64
    count = g.op("ReduceSum", below, g.const(np.array([0], dtype=np.int64)), keepdims=0)
    i = g.op("Min", g.op("Sub", count, g.const(np.int64(1))), g.const(np.int64(grid.size - 2)))
    lo = g.op("Gather", g.const(grid), i, axis=0)
    hi = g.op("Gather", g.const(grid), g.op("Add", i, g.const(np.int64(1))), axis=0)
    return i, g.op("Div", g.op("Sub", v, lo), g.op("Sub", hi, lo))


def _lerp(g: _Graph, lo: str, hi: str, t: str) -> str:
    """(1 - t) lo + t hi, as the numpy map computes it."""
    return g.op("Add", g.op("Mul", g.op("Sub", g.const(1.0), t), lo), g.op("Mul", t, hi))


def _map(g: _Graph, m: GainTableMap, v: str, log_w: str, log_s: str | None,
         stem: str) -> str:
    """``m(v, w, s)`` on rows ``v`` (M, n_in) (``log_s`` None: s = 1): see
    :class:`GainTableMap`."""
    H = m.W1.shape[-2]
    n_w, n_s = m.coef.shape[:2]
    i, a = _bracket(g, m.log_w, log_w)
    j, b = _bracket(g, m.log_s, log_s)
    j1 = g.op("Min", g.op("Add", j, g.const(np.int64(1))), g.const(np.int64(n_s - 1)))
    i1 = g.op("Min", g.op("Add", i, g.const(np.int64(1))), g.const(np.int64(n_w - 1)))
    weights = g.const(np.ascontiguousarray(np.swapaxes(m.coef[..., :H], -1, -2)),
                      f"{stem}_W")  # (n_w, n_s, H, n_out)
    bias = g.const(m.coef[..., H], f"{stem}_b")  # (n_w, n_s, n_out)

    def row(table: str, k: str) -> str:  # grid gain k's, at the noise's place
        at = g.op("Gather", table, k, axis=0)
        return _lerp(g, g.op("Gather", at, j, axis=0), g.op("Gather", at, j1, axis=0), b)

    def features(k: str | None) -> str:
        if m.shared:
            W1T, b1 = g.const(m.W1.T, f"{stem}_W1T"), g.const(m.b1, f"{stem}_b1")
        else:
            W1T = g.op("Gather", g.const(np.swapaxes(m.W1, -1, -2), f"{stem}_W1T"), k,
                       axis=0)
            b1 = g.op("Gather", g.const(m.b1, f"{stem}_b1"), k, axis=0)
        return g.op("Tanh", g.op("Add", g.op("MatMul", v, W1T), b1))

    if m.shared:  # the weights interpolated in w, then one layer
        W = _lerp(g, row(weights, i), row(weights, i1), a)
        c = _lerp(g, row(bias, i), row(bias, i1), a)
        return g.op("Add", g.op("MatMul", features(None), W), c, stem=stem)
    lo = g.op("Add", g.op("MatMul", features(i), row(weights, i)), row(bias, i))
    hi = g.op("Add", g.op("MatMul", features(i1), row(weights, i1)), row(bias, i1))
    return g.op("Add", g.op("Mul", g.op("Sub", g.const(1.0), a), lo), g.op("Mul", a, hi),
                stem=stem)


def scheduled_maps_graph(obs, name: str = "scheduled_kkl_maps"):
    """The ONNX model (``onnx.ModelProto``) of the maps of the gain-scheduled KKL
    ``obs`` (the module's table)."""
    g = _Graph()
    n, q = obs.system.n_state, obs.q
    log_w = g.op("Log", _scalar(g, "w"))
    log_s = g.op("Log", _scalar(g, "s"))
    outs = {"T": (_map(g, obs.encoder_T, "x", log_w, None, "T"), ["N", q]),
            "T_star": (_map(g, obs.decoder_T_star, "z", log_w, log_s, "T_star"), ["M", n])}
    if obs.decoder_locked is not None:
        outs["T_star_locked"] = (_map(g, obs.decoder_locked, "z", log_w, log_s,
                                      "T_star_locked"), ["M", n])
    return g.model(name, {"x": ["N", n], "z": ["M", q], "w": [1], "s": [1]}, outs,
                   {"ledsim_kind": KIND, "n_state": str(n), "q": str(q)})


class OnnxGainMap:
    """One output of the maps' graph, called as :class:`GainTableMap` is: ``m(v, w,
    s)`` on inputs of shape (..., n_in)."""

    def __init__(self, session, output: str, n_state: int, q: int):
        self.session, self.output = session, output
        self.encoder = output == "T"
        self.n_in = n_state if self.encoder else q
        self._other = np.zeros((1, q if self.encoder else n_state))

    def __call__(self, v, w: float, s: float = 1.0) -> np.ndarray:
        v = np.asarray(v, dtype=float)
        rows = v.reshape(-1, self.n_in)
        feed = {"x": rows, "z": self._other} if self.encoder else \
            {"x": self._other, "z": rows}
        out, = self.session.run([self.output], {**feed, "w": np.array([float(w)]),
                                                "s": np.array([float(s)])})
        return out.reshape(v.shape[:-1] + (out.shape[-1],))


def onnx_scheduled(obs, path: str | Path):
    """``obs`` (a :class:`~observer.kkl.scheduled.ScheduledKKL`) with its maps run by
    onnxruntime from the graph at ``path`` (:func:`scheduled_maps_graph` of it),
    refused with :class:`ObserverError` when the graph is not of its maps."""
    try:
        import onnxruntime as ort
    except ImportError:
        raise ObserverError("running an ONNX graph needs onnxruntime: "
                            "pip install 'ledsim[onnx]'") from None
    try:
        sess = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"])
    except Exception as e:
        raise ObserverError(f"ONNX file {str(path)!r} does not load: "
                            f"{str(e).splitlines()[0]}") from None
    meta = sess.get_modelmeta().custom_metadata_map
    n, q = obs.system.n_state, obs.q
    if meta.get("ledsim_kind") != KIND or meta.get("n_state") != str(n) or \
            meta.get("q") != str(q):
        raise ObserverError(f"ONNX file {str(path)!r} is not the maps of a gain-scheduled "
                            f"KKL of {n} states and z of {q} (ledsim export --checkpoint "
                            "the run's scheduled checkpoint)")
    outputs = {o.name for o in sess.get_outputs()}
    obs.encoder_T = OnnxGainMap(sess, "T", n, q)
    obs.decoder_T_star = OnnxGainMap(sess, "T_star", n, q)
    if obs.decoder_locked is not None:
        if "T_star_locked" not in outputs:
            raise ObserverError(f"ONNX file {str(path)!r} has no locked decoder, the "
                                "run's KKL has one")
        obs.decoder_locked = OnnxGainMap(sess, "T_star_locked", n, q)
    return obs
