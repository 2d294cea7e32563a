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
import math
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ledsim.errors import LedsimError
from ledsim.files.results import DictAccess
from ledsim.loop.replay_onnx import ReplayError, replay_onnx
from ledsim.loop.run_config import RunConfig
from observer.exceptions import ObserverError
from observer.recording import CALLS, replay_calls

#: What a replayable trace must hold: each array's dtype kinds (numpy's ``dtype.kind``)
#: and number of dimensions.
NEEDED = {"config": ("U", 0), "call_kind": ("iu", 1), "call_step": ("iu", 1),
          "call_args": ("f", 2), "call_nargs": ("iu", 1), "call_out": ("f", 2)}
_NPY_HEADERS = {(1, 0): np.lib.format.read_array_header_1_0,
                (2, 0): np.lib.format.read_array_header_2_0}


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
    """The record of a saved trace (the arrays of :data:`NEEDED`), refused in one line
    unless it holds one, of the right dtypes and shapes. The file is read as a zip of
    ``.npy`` arrays by their headers: nothing in it is unpickled, and an array of Python
    objects is refused."""
    path = Path(path)
    name = f"trace {str(path)!r}"
    if not path.exists():
        raise ReplayError(f"{name} does not exist")
    if not path.is_file():
        raise ReplayError(f"{name} is not a file")
    try:
        with open(path, "rb") as f:
            head = f.read(4)
    except OSError as e:
        raise ReplayError(f"{name} cannot be read: {e.strerror or type(e).__name__}") from None
    if not head:
        raise ReplayError(f"{name} is empty")
    if head == b"\x93NUM":
        raise ReplayError(f"{name} is one .npy array, not a .npz trace: save one with "
                          "ledsim run --save-trace")
    if head != b"PK\x03\x04":  # every .npz is a zip
        raise ReplayError(f"{name} is not a .npz trace (not a zip archive): save one with "
                          "ledsim run --save-trace")
    try:
        with zipfile.ZipFile(path) as zf:
            bad = zf.testzip()  # every member read through, its CRC-32 checked
            if bad is not None:
                raise ReplayError(f"{name} is damaged: {bad!r} fails its CRC-32 check")
            members = {i.filename.removesuffix(".npy"): i for i in zf.infolist()
                       if i.filename.endswith(".npy")}
            missing = [k for k in NEEDED if k not in members]
            if missing:
                _refuse_without_record(name, zf, members, missing)
            arrays = {k: _read_npy(name, zf, members[k], *NEEDED[k]) for k in NEEDED}
    except ReplayError:
        raise
    except Exception as e:  # zipfile's, zlib's and numpy's: a damaged file
        # Their text is not shown: numpy's advises loading the file unsafely.
        raise ReplayError(f"{name} is damaged (truncated or corrupted: "
                          f"{type(e).__name__})") from None
    return _check_record(name, arrays)


def _read_npy(name: str, zf: zipfile.ZipFile, info: zipfile.ZipInfo, kinds: str,
              ndim: int) -> np.ndarray:
    """One array of the zip, its header checked (dtype kind, dimensions, size) before its
    data are read."""
    key = info.filename.removesuffix(".npy")
    with zf.open(info) as f:
        header = _NPY_HEADERS.get(np.lib.format.read_magic(f))
        if header is None:
            raise ReplayError(f"{name}: array {key!r} is of a .npy version ledsim does "
                              "not write")
        shape, _, dtype = header(f)
        if dtype.hasobject:
            raise ReplayError(f"{name}: array {key!r} holds Python objects, which are "
                              "not loaded (nothing in a trace is unpickled)")
        if dtype.kind not in kinds or len(shape) != ndim:
            want = {"U": "a string", "f": "floats", "iu": "integers"}[kinds]
            raise ReplayError(f"{name}: array {key!r} is {dtype} of shape {shape}, not "
                              f"{want} in {ndim} dimension{'s' * (ndim != 1)}")
        if math.prod(shape) * dtype.itemsize > info.file_size:
            raise ReplayError(f"{name}: array {key!r} claims more data than it holds")
    with zf.open(info) as f:
        return np.lib.format.read_array(f, allow_pickle=False)


def _refuse_without_record(name: str, zf: zipfile.ZipFile, members: dict,
                           missing: list[str]) -> None:
    """A trace without the record: say why (the oracle's has none), in one line."""
    if "config" in members:
        try:
            saved = json.loads(str(_read_npy(name, zf, members["config"], "U", 0)))
        except (ReplayError, ValueError):
            saved = None
        if isinstance(saved, dict) and saved.get("estimator") == "oracle":
            raise ReplayError(f"{name} is of the oracle, which reads the true state: there "
                              "is nothing to replay")
    raise ReplayError(f"{name} holds no record of what its estimator was given "
                      f"({', '.join(missing)} missing): save it with ledsim run --save-trace")


def _check_record(name: str, arrays: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The record's arrays, refused unless they agree with each other (one row per call,
    known calls, no more arguments than columns)."""
    m = len(arrays["call_kind"])
    rows = {k: len(arrays[k]) for k in NEEDED if k != "config"}
    if set(rows.values()) != {m}:
        raise ReplayError(f"{name}: the record's arrays have different numbers of calls "
                          f"({', '.join(f'{k} {n}' for k, n in rows.items())})")
    kind, nargs = arrays["call_kind"], arrays["call_nargs"]
    if m and not ((kind >= 0) & (kind < len(CALLS))).all():
        raise ReplayError(f"{name}: call_kind holds a call that is not one of "
                          f"{', '.join(CALLS)}")
    if m and not ((nargs >= 0) & (nargs <= arrays["call_args"].shape[1])).all():
        raise ReplayError(f"{name}: call_nargs counts more arguments than call_args holds")
    return arrays


def check_calls(name: str, arrays: dict[str, np.ndarray], n_state: int,
                n_output: int, n_input: int = 1) -> None:
    """Refuse a record that the estimator of ``n_state`` states, ``n_output`` outputs
    and ``n_input`` inputs was not given: each call with its own number of arguments
    (``reset``: none, x0, or x0 and its covariance), finite but for a missing sample,
    and estimates of its size."""
    takes = {"seed_run": {1}, "reset": {0, n_state, n_state + n_state**2},
             "update": {n_output}, "predict": {n_input},
             "adapt_noise": {1, 1 + n_output}}
    kind, nargs, args = arrays["call_kind"], arrays["call_nargs"], arrays["call_args"]
    if arrays["call_out"].shape[1] != n_state:
        raise ReplayError(f"{name}: call_out has {arrays['call_out'].shape[1]} columns, "
                          f"the estimator {n_state} states")
    cols = np.arange(args.shape[1])
    given = cols < nargs[:, None]
    # y (of update and adapt_noise) is NaN where a sample is missing; the rest is finite.
    may_be_nan = np.isin(kind, [CALLS.index("update"), CALLS.index("adapt_noise")])[:, None] \
        & (cols >= (kind == CALLS.index("adapt_noise"))[:, None])
    for i, call in enumerate(CALLS):
        bad = np.flatnonzero((kind == i) & ~np.isin(nargs, list(takes[call])))
        if bad.size:
            raise ReplayError(f"{name}: call {bad[0]} ({call}) has {nargs[bad[0]]} "
                              f"arguments, where {call} takes "
                              f"{' or '.join(map(str, sorted(takes[call])))}")
    bad = np.flatnonzero((given & ~may_be_nan & ~np.isfinite(args)).any(axis=1))
    if bad.size:
        raise ReplayError(f"{name}: call {bad[0]} ({CALLS[kind[bad[0]]]}) has a NaN or "
                          "infinite argument")
    seeds = args[kind == CALLS.index("seed_run"), 0]
    if not ((seeds >= 0) & (seeds < 2.0**63) & (seeds == np.floor(seeds))).all():
        raise ReplayError(f"{name}: a seed_run's seed is not a non-negative integer")


def trace_config(arrays: dict[str, np.ndarray], path: str | Path | None = None) -> RunConfig:
    """The run's configuration, as saved in the trace, checked as a run's is
    (:meth:`RunConfig.from_dict`)."""
    name = "trace" if path is None else f"trace {str(path)!r}"
    try:
        saved = json.loads(str(arrays["config"]))
    except json.JSONDecodeError as e:
        raise ReplayError(f"{name}: its config is not JSON ({e.msg} at line {e.lineno}, "
                          f"column {e.colno})") from None
    try:
        return RunConfig.from_dict(saved)
    except LedsimError as e:
        raise ReplayError(f"{name}: its config is not a run's: {e}") from None


def run_estimator(cfg: RunConfig):
    """A fresh estimator of the run ``cfg`` (its checkpoint, its identified model)."""
    from ledsim.loop.build.estimation import identified_model, loop_estimator
    from ledsim.physics.gimbal_system import GimbalSystem

    if cfg.mission_plan is not None and cfg.world.two_axes and cfg.estimator != "kkl":
        raise ReplayError("a pan-tilt filter flying a --mission follows the range each "
                          "step (agent/range_gain.py), which the trace does not keep: "
                          "its replay is not supported yet")
    if cfg.world.two_axes:  # a pan-tilt head's, built as its run built it
        from ledsim.loop.build.control import head_estimator, head_model
        from ledsim.physics.head_system import HeadSystem

        system = HeadSystem(cfg.world_config())
        return head_estimator(cfg, system, head_model(cfg, identified_model(system)))
    system = GimbalSystem(cfg.world_config())
    est, _ = loop_estimator(cfg, system, identified_model(system))
    return est


def replay(path: str | Path, onnx: str | Path | None = None) -> ReplayResult:
    """Replay the trace at ``path`` into a fresh estimator (or the ONNX export at
    ``onnx``); see the module docstring."""
    arrays = load_trace(path)
    cfg = trace_config(arrays, path)
    try:
        est = run_estimator(cfg)
    except (LedsimError, ObserverError) as e:  # its checkpoint or scene, say
        raise ReplayError(f"trace {str(path)!r}: its estimator cannot be rebuilt: {e}") \
            from None
    check_calls(f"trace {str(path)!r}", arrays, est.system.n_state, est.system.n_output,
                est.system.n_input)
    if onnx is None:  # an estimate per update; the exported step gives one per predict
        worst, against, counted = replay_calls(est, arrays), "numpy", "update"
    else:
        worst, against, counted = replay_onnx(est, arrays, onnx), "onnx", "predict"
    estimates = int(np.sum(arrays["call_kind"] == CALLS.index(counted)))
    return ReplayResult(str(path), cfg.estimator, against, int(len(arrays["call_kind"])),
                        estimates, worst)
