"""Serialising the runners' typed results: one place, strict JSON.

Every runner returns dataclasses; :func:`to_jsonable` turns them (and numpy values) into
plain JSON data, with NaN and infinities written as ``null`` so that every
``results.json`` is valid JSON that any parser reads.
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np

from ledsim.files.outputs import atomic_write_text


def to_jsonable(obj):
    """Plain JSON data from dataclasses, dicts, sequences and numpy values."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: to_jsonable(getattr(obj, f.name)) for f in dataclasses.fields(obj)
                if f.metadata.get("json", True)}
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        return to_jsonable(obj.item())
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def dumps(obj) -> str:
    """Strict JSON text (no NaN or Infinity tokens), indented."""
    return json.dumps(to_jsonable(obj), indent=2, allow_nan=False) + "\n"


def write_json(path: str | Path, obj) -> Path:
    """Write ``obj`` as strict JSON, atomically."""
    atomic_write_text(Path(path), dumps(obj))
    return Path(path)


class DictAccess:
    """``result["key"]`` as an alias of ``result.key``, for code written against the
    dict results of earlier versions."""

    def __getitem__(self, key: str):
        try:
            return getattr(self, key)
        except AttributeError:
            raise KeyError(key) from None
