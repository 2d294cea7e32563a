"""Checkpoint files: what one holds (:class:`Stored`) and how it is read and written.

A checkpoint is a ``.safetensors`` file (a JSON header giving each array's dtype, shape
and byte range, then the raw bytes: reading it interprets and executes nothing) holding
the observer's arrays, with the format's name and the metadata, as a JSON string, in its
header. ledsim 0.2 wrote ``.pt`` files (``torch.save`` of the same strings and arrays):
one still reads, by ``torch.load(..., weights_only=True)`` where torch is installed, and
:func:`convert` rewrites it as ``.safetensors``. A ``.pt`` name stands for its
``.safetensors`` sibling where there is one (:func:`resolve`).

:mod:`observer.kkl.checkpoint` builds observers from these and checks them against a run.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

import numpy as np

from observer.exceptions import ObserverError
from observer.kkl import scheduled_checkpoint

FORMAT = "ledsim-kkl/1"
#: The formats a checkpoint's header may name.
FORMATS = (FORMAT, scheduled_checkpoint.FORMAT)
SUFFIX = ".safetensors"
LEGACY_SUFFIX = ".pt"


class CheckpointError(ObserverError):
    """A checkpoint is missing, corrupt, or was trained for another system."""


class Stored(NamedTuple):
    """What a checkpoint file holds: its format's name, its metadata (a JSON string) and
    its arrays by name."""

    format: str
    metadata_json: str
    arrays: dict[str, np.ndarray]


def resolve(path: str | Path) -> Path:
    """The file a checkpoint name stands for: a ``.pt`` name's ``.safetensors`` sibling
    when there is one (the same checkpoint, converted or written since), else the name."""
    path = Path(path)
    if path.suffix.lower() == LEGACY_SUFFIX and path.with_suffix(SUFFIX).is_file():
        return path.with_suffix(SUFFIX)
    return path


def target(path: str | Path) -> Path:
    """Where a checkpoint saved as ``path`` is written: ``path``, or for a ``.pt`` name its
    ``.safetensors`` sibling."""
    path = Path(path)
    return path.with_suffix(SUFFIX) if path.suffix.lower() == LEGACY_SUFFIX else path


def replace_file(path: Path, data: bytes) -> None:
    """Write ``data`` beside ``path`` and rename it over ``path`` (never half a file)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        tmp.write_bytes(data)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def _serialise(stored: Stored) -> bytes:
    """The bytes of a ``.safetensors`` checkpoint (``safetensors.numpy``)."""
    from safetensors.numpy import save as save_safetensors

    return save_safetensors({k: np.ascontiguousarray(a) for k, a in stored.arrays.items()},
                            metadata={"format": stored.format,
                                      "metadata_json": stored.metadata_json})


def write(stored: Stored, path: Path, write_bytes: Callable[[Path, bytes], None]) -> None:
    """The checkpoint at ``path`` and its metadata, readable, in ``.json`` beside it."""
    write_bytes(path, _serialise(stored))
    meta = json.loads(stored.metadata_json)
    write_bytes(path.with_suffix(".json"),
                (json.dumps(meta, indent=2, allow_nan=False) + "\n").encode())


def convert(src: str | Path, dst: str | Path | None = None,
            write_bytes: Callable[[Path, bytes], None] | None = None) -> Path:
    """Rewrite the ``.pt`` checkpoint ``src`` as ``.safetensors`` at ``dst`` (default:
    beside it), with its metadata in ``.json`` beside that: the same arrays, bit for bit,
    and the same metadata. Reading ``src`` needs torch. Returns the path written."""
    src = Path(src)
    if not src.is_file():
        raise CheckpointError(f"checkpoint {str(src)!r} does not exist")
    with open(src, "rb") as f:
        head = f.read(9)
    if _kind(head) != "torch":
        raise CheckpointError(f"checkpoint {str(src)!r} is not a .pt (torch) file")
    try:
        stored = _read_torch(src)
        json.loads(stored.metadata_json)
    except CheckpointError:
        raise
    except Exception as exc:
        raise corrupt(src, exc) from None
    dst = src.with_suffix(SUFFIX) if dst is None else Path(dst)
    write(stored, dst, write_bytes or replace_file)
    return dst


def corrupt(path: Path, exc: Exception | None = None,
            reason: str | None = None) -> CheckpointError:
    """The one-line refusal of a file that is not a checkpoint: ``reason``, or the type of
    ``exc`` (not its text, which can run to many lines: torch's does)."""
    return CheckpointError(f"checkpoint {str(path)!r} is corrupt or not a ledsim "
                           f"checkpoint ({reason or type(exc).__name__})")


def _kind(head: bytes) -> str:
    """``safetensors``, ``torch`` or ``unknown``, from a file's first 9 bytes."""
    if head[8:9] == b"{":  # safetensors: the header's length (8 bytes), then its JSON
        return "safetensors"
    # torch.save: a zip (torch >= 1.6), or before that a bare pickle (protocol >= 2)
    if head[:4] == b"PK\x03\x04" or head[:1] == b"\x80":
        return "torch"
    return "unknown"


def read(path: str | Path, arrays: bool = True) -> Stored:
    """What the checkpoint file at ``path`` holds, unchecked (without its arrays unless
    ``arrays``: a ``.pt`` file is read whole either way). Raises on a file it cannot read:
    a :class:`CheckpointError`, or another error for a malformed one."""
    path = Path(path)
    try:
        with open(path, "rb") as f:
            head = f.read(9)
    except OSError as exc:
        raise CheckpointError(f"checkpoint {str(path)!r} cannot be read: "
                              f"{exc.strerror or type(exc).__name__}") from None
    if not head:
        raise corrupt(path, reason="an empty file")
    kind = _kind(head)
    if kind == "safetensors":
        return _read_safetensors(path, arrays)
    if kind == "torch":
        return _read_torch(path)
    raise corrupt(path, reason="neither a .safetensors nor a .pt file")


def _read_safetensors(path: Path, arrays: bool) -> Stored:
    try:
        from safetensors import safe_open
    except ImportError:  # a base dependency: only an install that skipped it lacks it
        raise CheckpointError(f"checkpoint {str(path)!r}: reading it needs the safetensors "
                              "package (pip install safetensors)") from None

    with safe_open(path, framework="np") as f:
        header = f.metadata() or {}
        fmt = header.get("format")
        if fmt not in FORMATS or not isinstance(header.get("metadata_json"), str):
            # refused before its arrays are read: it may be any model's weights
            raise CheckpointError(f"checkpoint {str(path)!r} is a safetensors file but not "
                                  f"a ledsim checkpoint (format {fmt!r})")
        # Each array copied into numpy's own memory, as the readers before did: BLAS can
        # take another path, and round otherwise, over memory aligned otherwise.
        named = {k: np.array(f.get_tensor(k)) for k in f.keys()} if arrays else {}
    return Stored(fmt, header["metadata_json"], named)


def _read_torch(path: Path) -> Stored:
    """A ``.pt`` checkpoint (``torch.save`` of strings and tensors), by
    ``torch.load(..., weights_only=True)``, which builds tensors and nothing else."""
    try:
        import torch
    except ImportError:
        raise CheckpointError(f"checkpoint {str(path)!r} is a .pt file (ledsim 0.2 and "
                              "earlier): loading it needs torch (pip install torch), or "
                              "convert it to .safetensors where torch is installed: python "
                              f"scripts/convert_checkpoints.py {str(path)!r}") from None
    import warnings

    # torch warns about foreign pickle protocols before it refuses a file; the refusal is
    # reported as one line by the caller, so the warning is not shown.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        payload = torch.load(path, map_location="cpu", weights_only=True)
    if not isinstance(payload, dict):
        raise TypeError("not a dict")
    fmt, meta_json = payload.pop("format", None), payload.pop("metadata_json", None)
    if not (isinstance(fmt, str) and isinstance(meta_json, str)):
        raise TypeError("no format or metadata")
    if not all(isinstance(v, torch.Tensor) for v in payload.values()):
        raise TypeError("a value that is not a tensor")
    return Stored(fmt, meta_json, {k: np.array(v.numpy(force=True))
                                   for k, v in payload.items()})
