"""``ledsim replay --onnx``: a saved trace through the ONNX export of its estimator
(``ledsim export``) instead of the numpy one; see :func:`replay_onnx`."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ledsim.errors import LedsimError
from observer.exceptions import ObserverError
from observer.kkl.fixed_gain import KKLObserver
from observer.recording import CALLS, difference, replay_calls


class ReplayError(LedsimError):
    """The trace cannot be replayed (not a trace, no record, or another export)."""


def replay_onnx(est, arrays: dict[str, np.ndarray], onnx: str | Path) -> float:
    """The recorded calls through the ONNX export of ``est`` (``ledsim export``); the
    largest difference of its estimates from the recorded ones:

    - a fixed-gain KKL: its exported step, one per ``predict`` on the step's last
      measurement (a re-seed re-encodes z with ``est``'s own encoder);
    - the gain-scheduled KKL: ``est`` with its maps run from the graph
      (:func:`~observer.kkl.export_maps.onnx_scheduled`), given every call;
    - the pan-tilt's pair: each axis's exported step (NAME_azimuth.onnx and
      NAME_elevation.onnx of ``onnx`` = NAME.onnx) run for that axis, given every call.
    """
    from observer.kkl.decoupled import PerAxis
    from observer.kkl.scheduled import ScheduledKKL

    if isinstance(est, ScheduledKKL):
        from observer.kkl.export_maps import onnx_scheduled

        _session(onnx)  # its own errors first
        try:
            onnx_scheduled(est, onnx)
        except ObserverError as e:
            raise ReplayError(str(e)) from None
        return replay_calls(est, arrays)
    if isinstance(est, PerAxis) and all(isinstance(a, KKLObserver) for a in est.axes):
        from ledsim.loop.build.head_kkl import AXES

        base = Path(onnx)
        for a, name in enumerate(AXES):
            est.axes[a] = OnnxStep(est.axes[a], _session(
                base.with_name(f"{base.stem}_{name}.onnx"), est.axes[a].q))
        return replay_calls(est, arrays)
    if not isinstance(est, KKLObserver):
        raise ReplayError(f"an ONNX export is a KKL's; this trace's estimator "
                          f"({type(est).__name__}) is not one: replay it without --onnx")
    sess = _session(onnx, est.q)
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


def _session(path: str | Path, q: int | None = None):
    """onnxruntime's session of the graph at ``path`` (a step whose z has ``q``
    entries, when given), refused in one line."""
    try:
        import onnxruntime as ort
    except ImportError:
        raise ReplayError("--onnx needs onnxruntime: pip install 'ledsim[onnx]'") from None
    path = Path(path)
    if not path.is_file():
        raise ReplayError(f"ONNX file {str(path)!r} does not exist")
    try:
        sess = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"])
    except Exception as e:
        raise ReplayError(f"ONNX file {str(path)!r} does not load: "
                          f"{str(e).splitlines()[0]}") from None
    if q is not None:
        shape = sess.get_inputs()[0].shape
        if sess.get_inputs()[0].name != "z" or shape != [q]:
            raise ReplayError(f"ONNX file {str(path)!r} is not a KKL step with z of {q} "
                              "(the trace's): export the run's checkpoint")
    return sess


class OnnxStep:
    """A fixed-gain KKL run by its exported step (:func:`~observer.kkl.export.
    kkl_step_graph`), with the estimator's calls: ``update`` gives T*(z), ``predict``
    the step's z_next on the update's measurement; a reset encodes z with the numpy
    observer's encoder."""

    def __init__(self, obs: KKLObserver, session):
        self.obs, self.session, self.system = obs, session, obs.system
        self.outside_domain = False
        self.reset()

    def seed_run(self, seed: int) -> None:
        pass

    def reset(self, x0=None, covariance=None) -> None:
        self.z = self.obs.encode(self.obs.initial_guess(x0))
        self.y = None

    def update(self, y) -> np.ndarray:
        self.y = np.asarray(y, dtype=float)
        x, _ = self.session.run(None, {"z": self.z, "y": self.y,
                                       "u": np.array([self.obs.u_bar])})
        return x

    def predict(self, u) -> None:
        _, self.z = self.session.run(None, {"z": self.z, "y": self.y,
                                            "u": np.array([float(u)])})

    def adapt_noise(self, noise_ratio: float, y=None):
        return None

    def tell_noise_scale(self, scale: float) -> None:
        pass
