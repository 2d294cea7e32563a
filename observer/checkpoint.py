"""Saving and loading trained KKL observers: weights plus JSON metadata.

A checkpoint is one ``.pt`` file holding only tensors and a JSON string (so it loads
with ``torch.load(..., weights_only=True)``; nothing is unpickled) and a readable
``.json`` copy of the metadata beside it. Both are written atomically. Loading checks
the metadata (Te, A, B, model constants) against the system it is loaded for.

Loading does not import torch: :mod:`observer.tensorfile` reads the file's tensors
without executing anything in it, and only a file it does not recognise goes to
``torch.load(..., weights_only=True)``.
"""

from __future__ import annotations

import io
import json
import math
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

from . import scheduled_checkpoint, tensorfile
from .errors import ObserverError
from .kkl import KKLObserver
from .nets import NumpyMLP
from .scheduled import ScheduledKKL
from .system import DiscreteSystem

FORMAT = "ledsim-kkl/1"


class CheckpointError(ObserverError):
    """A checkpoint is missing, corrupt, or was trained for another system."""


def _replace(path: Path, data: bytes) -> None:
    """Write ``data`` beside ``path`` and rename it over ``path`` (never half a file)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        tmp.write_bytes(data)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def save(obs: KKLObserver, path: str | Path, extra: dict | None = None,
         write_bytes: Callable[[Path, bytes], None] | None = None) -> Path:
    """Write ``obs`` to ``path`` (``.pt``) and its metadata to ``path.with_suffix('.json')``.

    ``write_bytes(path, data)`` writes each file (default: beside it, then renamed over
    it); an application passes its own (``ledsim.outputs.save_checkpoint``)."""
    path = Path(path)
    write_bytes = write_bytes or _replace
    if isinstance(obs, ScheduledKKL):
        meta, named = scheduled_checkpoint.metadata(obs), scheduled_checkpoint.arrays(obs)
    else:
        meta = {"format": FORMAT, "system": obs.system.metadata(),
                "eigenvalues": obs.eigenvalues.tolist(), "B_scaled": obs.B.tolist(),
                "u_bar": obs.u_bar}
        named = {f"{prefix}.{k}": a for prefix, net in (("encoder_T", obs.encoder_T),
                                                      ("decoder_T_star", obs.decoder_T_star))
                 for k, a in net.arrays().items()}
    meta = strict_json({**meta, **getattr(obs, "training_metadata", {}), **(extra or {})})
    import torch

    tensors = {k: torch.from_numpy(np.ascontiguousarray(a)) for k, a in named.items()}
    payload = {"format": meta["format"], "metadata_json": json.dumps(meta, allow_nan=False),
               **tensors}
    buf = io.BytesIO()
    torch.save(payload, buf)
    write_bytes(path, buf.getvalue())
    write_bytes(path.with_suffix(".json"),
                (json.dumps(meta, indent=2, allow_nan=False) + "\n").encode())
    return path


def metadata(path: str | Path) -> dict:
    """The metadata a checkpoint was saved with (its system, design, training)."""
    path = Path(path)
    if not path.is_file():
        raise CheckpointError(f"checkpoint {str(path)!r} does not exist")
    try:
        return json.loads(_read(path)["metadata_json"])
    except Exception as exc:
        raise CheckpointError(f"checkpoint {str(path)!r} is corrupt or not a ledsim "
                              f"checkpoint ({type(exc).__name__})") from None


def load(path: str | Path, system: DiscreteSystem, check: bool = True, *,
         model: DiscreteSystem | None = None, use_omega: bool = True,
         name: str | None = None) -> KKLObserver | ScheduledKKL:
    """Load a checkpoint for ``system``; raise :class:`CheckpointError` if it does not fit.
    A gain-scheduled KKL's checkpoint (``ledsim train --design scheduled``) gives a
    :class:`~observer.scheduled.ScheduledKKL`.

    ``model``: what the observer computes with (Omega's f, the h of missing samples;
    default ``system``); ``use_omega``: apply the Omega correction; ``name``: the
    estimator's name in tables (default ``kkl``)."""
    path = Path(path)
    if not path.is_file():
        raise CheckpointError(f"checkpoint {str(path)!r} does not exist")
    try:
        payload = _read_shared(path)
        meta = json.loads(payload["metadata_json"])
        if payload.get("format") == scheduled_checkpoint.FORMAT:
            _check_system(path, meta["system"], system, check)
            obs = scheduled_checkpoint.build(payload, meta, system if model is None
                                             else model, use_omega)
            return _named(obs, meta, name)
        enc, dec = (_net(payload, prefix) for prefix in ("encoder_T", "decoder_T_star"))
        lam = np.asarray(meta["eigenvalues"], dtype=float)
        B = np.asarray(meta["B_scaled"], dtype=float)
        u_bar = float(meta.get("u_bar", 0.0))
        saved_system = meta["system"]
    except CheckpointError:  # it loads, but was trained for another system
        raise
    except Exception as exc:  # corrupt file, wrong keys, not a torch file
        raise CheckpointError(f"checkpoint {str(path)!r} is corrupt or not a ledsim "
                              f"checkpoint ({type(exc).__name__})") from None
    if payload.get("format") != FORMAT:
        raise CheckpointError(f"checkpoint {str(path)!r} has format "
                              f"{payload.get('format')!r}, expected {FORMAT!r}")
    _check_contents(path, enc, dec, lam, B, u_bar, system)
    _check_system(path, saved_system, system, check)
    obs = KKLObserver(system if model is None else model, lam, B, enc, dec, u_bar=u_bar,
                      use_omega=use_omega)
    return _named(obs, meta, name)


def _check_system(path: Path, saved_system: dict, system: DiscreteSystem, check: bool) -> None:
    if check:
        mismatch = first_mismatch(saved_system, system.metadata())
        if mismatch:
            key, saved, current = mismatch
            raise CheckpointError(f"checkpoint {str(path)!r} was trained with {key}={saved!r} "
                                  f"but the run uses {key}={current!r}")


def _named(obs, meta: dict, name: str | None):
    if name is not None:
        obs.name = name
    obs.training_metadata = {k: meta[k] for k in ("design", "training", "report") if k in meta}
    return obs


_PAYLOADS: dict = {}


def _read_shared(path: Path) -> dict:
    """:func:`_read`, kept per process while the file is unchanged, its arrays made
    read-only (copy one to change it): the runs of many seeds share one copy of the
    weights (64 seeds held 64 copies of a few MB each, and stepped through them out of
    cache)."""
    st = path.stat()
    key = (str(path.resolve()), st.st_ino, st.st_size, st.st_mtime_ns)
    payload = _PAYLOADS.get(key)
    if payload is None:
        payload = _read(path)
        for v in payload.values():
            if isinstance(v, np.ndarray):
                v.flags.writeable = False
        if len(_PAYLOADS) >= 16:  # a process that loads many checkpoints keeps a few
            _PAYLOADS.clear()
        _PAYLOADS[key] = payload
    return payload


def _read(path: Path) -> dict:
    """The saved dict, tensors as numpy arrays: by :mod:`observer.tensorfile` (no torch),
    or for a file it does not recognise by ``torch.load(..., weights_only=True)``."""
    try:
        return tensorfile.read(path)
    except tensorfile.Unsupported:
        pass
    import warnings

    import torch

    # torch warns about foreign pickle protocols before it refuses a file; the refusal is
    # reported as one line by the caller, so the warning is not shown.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        payload = torch.load(path, map_location="cpu", weights_only=True)
    if not isinstance(payload, dict):
        raise TypeError("not a dict")
    return {k: v.numpy(force=True) if isinstance(v, torch.Tensor) else v
            for k, v in payload.items()}


def _net(payload: dict, prefix: str) -> NumpyMLP:
    """A network from its named tensors (``Wm<i>``, ``bm<i>``: layers past the first)."""
    def arr(k):
        return np.asarray(payload[f"{prefix}.{k}"], dtype=np.float64)

    n_mid = sum(1 for k in payload if k.startswith(f"{prefix}.Wm"))
    if n_mid > 16:
        raise ValueError("too many layers")
    return NumpyMLP(*(arr(k) for k in ("W1", "b1", "W2", "b2")),
                    tuple((arr(f"Wm{i}"), arr(f"bm{i}")) for i in range(n_mid)))


def _consistent(net: NumpyMLP) -> bool:
    H = net.W1.shape[0] if net.W1.ndim == 2 else -1
    mids_ok = all(W.shape == (H, H) and b.shape == (H,) for W, b in net.mid)
    return (net.W1.ndim == 2 and net.b1.shape == (H,) and net.W2.ndim == 2 and mids_ok
            and net.W2.shape[1] == H and net.b2.shape == (net.W2.shape[0],))


def _check_contents(path, enc, dec, lam, B, u_bar, system) -> None:
    """A checkpoint that loads can still be poison: refuse bad shapes, non-finite
    numbers and an A that is not a contraction (it would make z diverge)."""
    name = repr(str(path))
    shapes_ok = (_consistent(enc) and _consistent(dec) and lam.ndim == 1
                 and enc.n_in == system.n_state and dec.n_out == system.n_state
                 and enc.n_out == lam.size == dec.n_in and B.shape == (lam.size, system.n_output))
    if not shapes_ok:
        raise CheckpointError(f"checkpoint {name} has network shapes that do not fit "
                              f"a system with n={system.n_state}, p={system.n_output}")
    arrays = [*enc.arrays().values(), *dec.arrays().values(), lam, B, np.array(u_bar)]
    if not all(np.isfinite(a).all() for a in arrays):
        raise CheckpointError(f"checkpoint {name} holds NaN or infinite numbers")
    if not np.all(np.abs(lam) < 1):
        raise CheckpointError(f"checkpoint {name} has eigenvalues {lam.tolist()} outside "
                              "(-1, 1): its observer would diverge")


def strict_json(obj):
    """``obj`` with every non-finite float replaced by None (valid, strict JSON)."""
    if isinstance(obj, dict):
        return {k: strict_json(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [strict_json(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def first_mismatch(saved, current, prefix: str = "") -> tuple[str, object, object] | None:
    """The first key (dotted path) whose value differs between two metadata trees."""
    if isinstance(saved, dict) and isinstance(current, dict):
        for key in sorted(set(saved) | set(current)):
            found = first_mismatch(saved.get(key), current.get(key),
                                   f"{prefix}.{key}" if prefix else key)
            if found:
                return found
        return None
    if isinstance(saved, list | tuple) and isinstance(current, list | tuple):
        if len(saved) != len(current):
            return prefix, saved, current
        for i, (a, b) in enumerate(zip(saved, current, strict=True)):
            found = first_mismatch(a, b, f"{prefix}[{i}]")
            if found:
                return found
        return None
    if isinstance(saved, float | int) and isinstance(current, float | int):
        if not math.isclose(saved, current, rel_tol=1e-9, abs_tol=1e-12):
            return prefix, saved, current
        return None
    if saved != current:
        return prefix, saved, current
    return None
