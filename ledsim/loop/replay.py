"""Replay a saved trace: give a fresh estimator, or an ONNX export of it, what the run's
estimator was given, and measure how far its estimates are from the run's.

``ledsim run --save-trace`` keeps, beside the run's series, every call its estimator
received (:mod:`ledsim.loop.given`, :mod:`observer.recording`) and the run's
configuration. :func:`replay` rebuilds the estimator of that configuration (the same
checkpoint, the same identified model) and gives it the same calls, in order: the
estimates agree to the last bit. With an ONNX export of a fixed-gain KKL it runs the
exported step instead (z re-encoded by the numpy encoder at each re-seed), and the
differences are the export's.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from observer.kkl import KKLObserver
from observer.recording import CALLS, difference, replay_calls

from ..errors import LedsimError
from ..results import DictAccess
from .config import RunConfig

#: What a replayable trace must hold.
NEEDED = ("config", "call_kind", "call_step", "call_args", "call_nargs", "call_out")


class ReplayError(LedsimError):
    """The trace cannot be replayed (not a trace, no record, or another export)."""


@dataclass
class ReplayResult(DictAccess):
    """A replay: the trace, its estimator, how many calls and estimates it replayed,
    against what (``numpy`` or ``onnx``), and the largest absolute difference of an
    estimate from the run's (phi [rad] or phidot [rad/s])."""

    trace: str
    estimator: str
    against: str
    calls: int
    estimates: int
    max_abs_difference: float


def load_trace(path: str | Path) -> dict[str, np.ndarray]:
    """The arrays of a saved trace, refused in one line unless it holds a record."""
    path = Path(path)
    if not path.is_file():
        raise ReplayError(f"trace {str(path)!r} does not exist or is not a file")
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
    except (OSError, ValueError) as e:
        raise ReplayError(f"trace {str(path)!r} is not a .npz trace: {e}") from None
    missing = [k for k in NEEDED if k not in arrays]
    if "config" in arrays and missing:
        cfg = json.loads(str(arrays["config"]))
        if cfg.get("estimator") == "oracle":
            raise ReplayError(f"trace {str(path)!r} is of the oracle, which reads the true "
                              "state: there is nothing to replay")
    if missing:
        raise ReplayError(f"trace {str(path)!r} holds no record of what its estimator was "
                          f"given ({', '.join(missing)} missing): save it with ledsim run "
                          "--save-trace")
    return arrays


def trace_config(arrays: dict[str, np.ndarray]) -> RunConfig:
    """The run's configuration, as saved in the trace."""
    saved = json.loads(str(arrays["config"]))
    names = {f.name for f in fields(RunConfig)}
    return RunConfig(**{k: tuple(v) if isinstance(v, list) else v
                        for k, v in saved.items() if k in names})


def run_estimator(cfg: RunConfig):
    """A fresh estimator of the run ``cfg`` (its checkpoint, its identified model)."""
    from ..physics.system import GimbalSystem
    from .estimation import identified_model, loop_estimator

    system = GimbalSystem(cfg.world_config())
    est, _ = loop_estimator(cfg, system, identified_model(system))
    return est


def replay(path: str | Path, onnx: str | Path | None = None) -> ReplayResult:
    """Replay the trace at ``path`` into a fresh estimator (or the ONNX export at
    ``onnx``); see the module docstring."""
    arrays = load_trace(path)
    cfg = trace_config(arrays)
    est = run_estimator(cfg)
    if onnx is None:  # an estimate per update; the exported step gives one per predict
        worst, against, counted = replay_calls(est, arrays), "numpy", "update"
    else:
        worst, against, counted = replay_onnx(est, arrays, onnx), "onnx", "predict"
    estimates = int(np.sum(arrays["call_kind"] == CALLS.index(counted)))
    return ReplayResult(str(path), cfg.estimator, against, int(len(arrays["call_kind"])),
                        estimates, worst)


def replay_onnx(est, arrays: dict[str, np.ndarray], onnx: str | Path) -> float:
    """The recorded calls through the exported step of the fixed-gain KKL ``est``
    (``ledsim export``): one step per ``predict``, on the step's last measurement; a
    re-seed re-encodes z with ``est``'s own encoder. Returns the largest difference of
    its estimates from the recorded ones."""
    if not isinstance(est, KKLObserver):
        raise ReplayError(f"an ONNX export is one fixed-gain KKL; this trace's estimator "
                          f"({type(est).__name__}) is not one: replay it without --onnx")
    try:
        import onnxruntime as ort
    except ImportError:
        raise ReplayError("--onnx needs onnxruntime: pip install 'ledsim[onnx]'") from None
    path = Path(onnx)
    if not path.is_file():
        raise ReplayError(f"ONNX file {str(path)!r} does not exist")
    try:
        sess = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"])
    except Exception as e:
        raise ReplayError(f"ONNX file {str(path)!r} does not load: "
                          f"{str(e).splitlines()[0]}") from None
    q = sess.get_inputs()[0].shape[0]
    if q != est.q:
        raise ReplayError(f"ONNX file {str(path)!r} is a KKL with z of {q}, the trace's "
                          f"has {est.q}: export the run's checkpoint")
    z, y, out, worst = est.encode(est.initial_guess(None)), None, None, 0.0
    for kind, args, n, rec in zip(arrays["call_kind"], arrays["call_args"],
                                  arrays["call_nargs"], arrays["call_out"], strict=True):
        name = CALLS[int(kind)]
        if name == "reset":
            # x0, then its covariance (which a KKL has no use for)
            z = est.encode(est.initial_guess(args[:est.system.n_state] if n else None))
        elif name == "update":
            y, out = args[:n], rec
        elif name == "predict":
            x, z = sess.run(None, {"z": z, "y": y, "u": args[:1]})
            worst = max(worst, difference(x, out))
    return worst
