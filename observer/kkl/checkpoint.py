"""Saving and loading trained KKL observers: weights plus JSON metadata.

A checkpoint is one ``.safetensors`` file holding the observer's arrays and, in its
header, the format's name and the metadata (:mod:`observer.kkl.checkpoint_io`), with a
readable ``.json`` copy of the metadata beside it; both are written atomically. Loading
needs no torch and executes nothing in the file, and checks the metadata (Te, A, B,
model constants) against the system it is loaded for. A ``.pt`` checkpoint of ledsim 0.2
still loads where torch is installed; a ``.pt`` name stands for its ``.safetensors``
sibling where there is one (the shipped checkpoints were ``.pt`` files).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np

from observer.kkl import scheduled_checkpoint
from observer.kkl.checkpoint_io import (
    FORMAT,
    CheckpointError,
    Stored,
    corrupt,
    read,
    replace_file,
    resolve,
    target,
    write,
)
from observer.kkl.fixed_gain import KKLObserver
from observer.kkl.nets import NumpyMLP
from observer.kkl.scheduled import ScheduledKKL
from observer.system import DiscreteSystem

#: Checkpoint files whose contents a process keeps (:func:`_read_shared`).
MAX_CACHED = 16


def save(obs: KKLObserver, path: str | Path, extra: dict | None = None,
         write_bytes: Callable[[Path, bytes], None] | None = None) -> Path:
    """Write ``obs`` to ``path`` (``.safetensors``; for a ``.pt`` name, its
    ``.safetensors`` sibling) and its metadata to ``.json`` beside it. Returns the
    checkpoint's path.

    ``write_bytes(path, data)`` writes each file (default: beside it, then renamed over
    it); an application passes its own (``ledsim.files.outputs.save_checkpoint``)."""
    path = target(path)
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
    write(Stored(meta["format"], json.dumps(meta, allow_nan=False), named), path,
           write_bytes or replace_file)
    return path


def metadata(path: str | Path) -> dict:
    """The metadata a checkpoint was saved with (its system, design, training)."""
    path = _existing(path)
    try:
        meta = json.loads(read(path, arrays=False).metadata_json)
        if not isinstance(meta, dict):
            raise TypeError("the metadata is not a JSON object")
        return meta
    except CheckpointError:
        raise
    except Exception as exc:
        raise corrupt(path, exc) from None


def load(path: str | Path, system: DiscreteSystem, check: bool = True, *,
         model: DiscreteSystem | None = None, use_omega: bool = True,
         name: str | None = None) -> KKLObserver | ScheduledKKL:
    """Load a checkpoint for ``system``; raise :class:`CheckpointError` if it does not fit.
    A gain-scheduled KKL's checkpoint (``ledsim train --design scheduled``) gives a
    :class:`~observer.kkl.scheduled.ScheduledKKL`. ``path``: see :func:`resolve`.

    ``model``: what the observer computes with (Omega's f, the h of missing samples;
    default ``system``); ``use_omega``: apply the Omega correction; ``name``: the
    estimator's name in tables (default ``kkl``)."""
    path = _existing(path)
    try:
        stored = _read_shared(path)
        meta = json.loads(stored.metadata_json)
        if stored.format == scheduled_checkpoint.FORMAT:
            _check_system(path, meta["system"], system, check)
            obs = scheduled_checkpoint.build(stored.arrays, meta, system if model is None
                                             else model, use_omega)
            return _named(obs, meta, name)
        enc, dec = (_net(stored.arrays, prefix) for prefix in ("encoder_T", "decoder_T_star"))
        lam = np.asarray(meta["eigenvalues"], dtype=float)
        B = np.asarray(meta["B_scaled"], dtype=float)
        u_bar = float(meta.get("u_bar", 0.0))
        saved_system = meta["system"]
    except CheckpointError:  # it loads, but was trained for another system
        raise
    except Exception as exc:  # corrupt file, wrong keys, wrong types
        raise corrupt(path, exc) from None
    if stored.format != FORMAT:
        raise CheckpointError(f"checkpoint {str(path)!r} has format "
                              f"{stored.format!r}, expected {FORMAT!r}")
    _check_contents(path, enc, dec, lam, B, u_bar, system)
    _check_system(path, saved_system, system, check)
    obs = KKLObserver(system if model is None else model, lam, B, enc, dec, u_bar=u_bar,
                      use_omega=use_omega)
    return _named(obs, meta, name)


def _existing(path: str | Path) -> Path:
    """The file ``path`` stands for (:func:`resolve`), or a one-line refusal."""
    file = resolve(path)
    if not file.is_file():
        what = "is not a file" if file.exists() else "does not exist"
        raise CheckpointError(f"checkpoint {str(path)!r} {what}")
    return file


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


_STORED: dict = {}


def _read_shared(path: Path) -> Stored:
    """:func:`read`, kept per process while the file is unchanged, its arrays made
    read-only (copy one to change it): the runs of many seeds share one copy of the
    weights (64 seeds held 64 copies of a few MB each, and stepped through them out of
    cache). A process that loads many checkpoints keeps the last few."""
    st = path.stat()
    key = (str(path.resolve()), st.st_ino, st.st_size, st.st_mtime_ns)
    stored = _STORED.get(key)
    if stored is None:
        stored = read(path)
        for a in stored.arrays.values():
            a.flags.writeable = False
        if len(_STORED) >= MAX_CACHED:
            _STORED.clear()
        _STORED[key] = stored
    return stored


def _net(arrays: dict, prefix: str) -> NumpyMLP:
    """A network from its named arrays (``Wm<i>``, ``bm<i>``: layers past the first)."""
    def arr(k):
        return np.asarray(arrays[f"{prefix}.{k}"], dtype=np.float64)

    n_mid = sum(1 for k in arrays if k.startswith(f"{prefix}.Wm"))
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
