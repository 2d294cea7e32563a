"""Read a checkpoint's tensors without importing torch, and without unpickling.

A checkpoint is what ``torch.save`` writes for a dict of strings and tensors: a zip
holding ``<root>/data.pkl`` (a pickle of the dict), ``<root>/data/<key>`` (each
tensor's storage as raw bytes) and ``<root>/byteorder``. In that pickle a tensor is

    torch._utils._rebuild_tensor_v2(<storage ('storage', torch.<T>Storage, key, 'cpu',
                                    numel)>, offset, size, stride, requires_grad,
                                    OrderedDict())

:func:`read` interprets the pickle's opcodes (``pickletools.genops``) on a small stack
machine that knows only those three globals, so nothing in the file is ever executed,
and builds numpy arrays from the storage bytes. Anything else (another global, an
opcode a dict of tensors does not use, a big-endian file, a strided view) raises
:class:`Unsupported`: the caller then falls back to ``torch.load(..., weights_only=True)``.

Importing torch costs a short run about a second; loading the shipped observers this
way does not.
"""

from __future__ import annotations

import math
import pickletools
import zipfile
from pathlib import Path

import numpy as np

#: Storage class -> numpy dtype (little-endian).
STORAGE_DTYPES = {"DoubleStorage": "<f8", "FloatStorage": "<f4", "HalfStorage": "<f2",
                  "LongStorage": "<i8", "IntStorage": "<i4", "ShortStorage": "<i2",
                  "CharStorage": "i1", "ByteStorage": "u1", "BoolStorage": "?"}
MAX_ENTRY_BYTES = 256 * 2**20  # a checkpoint's storages are ~100 kB; refuse zip bombs


class Unsupported(Exception):
    """The file is not a plain ``torch.save`` of strings and tensors (or not a zip)."""


class _Storage:
    def __init__(self, name: str):
        self.dtype = np.dtype(STORAGE_DTYPES[name])


_ORDERED_DICT = object()
_REBUILD = object()


def _global(module: str, name: str):
    if (module, name) == ("torch._utils", "_rebuild_tensor_v2"):
        return _REBUILD
    if (module, name) == ("collections", "OrderedDict"):
        return _ORDERED_DICT
    if module == "torch" and name in STORAGE_DTYPES:
        return _Storage(name)
    raise Unsupported(f"global {module}.{name}")


def _tensor(storage: np.ndarray, offset: int, size: tuple, stride: tuple, *_) -> np.ndarray:
    size, stride = tuple(size), tuple(stride)
    expected = tuple(math.prod(size[i + 1:]) for i in range(len(size)))
    n = math.prod(size)
    if (n > 1 and stride != expected) or offset < 0 or offset + n > storage.size:
        raise Unsupported("a strided or out-of-range tensor view")
    return storage[offset:offset + n].reshape(size).copy()


def read(path: str | Path) -> dict:
    """The dict a ``torch.save`` file holds, tensors as numpy arrays.

    Raises :class:`Unsupported` for anything but a plain dict of strings, numbers and
    contiguous tensors."""
    try:
        z = zipfile.ZipFile(path)
    except (zipfile.BadZipFile, OSError) as exc:
        raise Unsupported(f"not a zip file ({type(exc).__name__})") from None
    with z:
        pickles = [i for i in z.infolist() if i.filename.endswith("/data.pkl")
                   or i.filename == "data.pkl"]
        if len(pickles) != 1 or any(i.file_size > MAX_ENTRY_BYTES for i in z.infolist()):
            raise Unsupported("not one data.pkl, or an entry too large")
        root = pickles[0].filename[:-len("data.pkl")]
        if root + "byteorder" in z.namelist() and z.read(root + "byteorder") != b"little":
            raise Unsupported("a big-endian file")

        def storage(pid):
            if not (isinstance(pid, tuple) and len(pid) == 5 and pid[0] == "storage"
                    and isinstance(pid[1], _Storage) and isinstance(pid[2], str)):
                raise Unsupported("a persistent id that is not a storage")
            try:
                raw = z.read(f"{root}data/{pid[2]}")
            except KeyError:
                raise Unsupported(f"storage {pid[2]!r} missing") from None
            arr = np.frombuffer(raw, dtype=pid[1].dtype)
            if arr.size != pid[4]:
                raise Unsupported(f"storage {pid[2]!r} has {arr.size} elements, "
                                  f"not {pid[4]}")
            return arr

        return _run(z.read(pickles[0]), storage)


def _run(data: bytes, storage) -> dict:
    """Interpret the opcodes of ``data`` (never ``pickle.loads``)."""
    stack: list = []
    marks: list[int] = []
    memo: dict = {}

    def pop_mark() -> list:
        start = marks.pop()
        items = stack[start:]
        del stack[start:]
        return items

    try:
        for op, arg, _ in pickletools.genops(data):
            name = op.name
            if name in ("PROTO", "FRAME"):
                continue
            if name == "MARK":
                marks.append(len(stack))
            elif name in ("BINUNICODE", "SHORT_BINUNICODE", "BINUNICODE8", "BININT",
                          "BININT1", "BININT2", "LONG1", "BINFLOAT"):
                stack.append(arg)
            elif name in ("NEWTRUE", "NEWFALSE", "NONE"):
                stack.append({"NEWTRUE": True, "NEWFALSE": False, "NONE": None}[name])
            elif name == "EMPTY_DICT":
                stack.append({})
            elif name == "EMPTY_TUPLE":
                stack.append(())
            elif name == "TUPLE":
                stack.append(tuple(pop_mark()))
            elif name in ("TUPLE1", "TUPLE2", "TUPLE3"):
                k = int(name[-1])
                items = tuple(stack[-k:])
                del stack[-k:]
                stack.append(items)
            elif name in ("BINPUT", "LONG_BINPUT"):
                memo[arg] = stack[-1]
            elif name == "MEMOIZE":
                memo[len(memo)] = stack[-1]
            elif name in ("BINGET", "LONG_BINGET"):
                stack.append(memo[arg])
            elif name == "GLOBAL":
                stack.append(_global(*arg.split(" ", 1)))
            elif name == "BINPERSID":
                stack.append(storage(stack.pop()))
            elif name == "REDUCE":
                args, fn = stack.pop(), stack.pop()
                if fn is _ORDERED_DICT and args == ():
                    stack.append({})
                elif fn is _REBUILD and len(args) in (6, 7) \
                        and isinstance(args[0], np.ndarray):
                    stack.append(_tensor(*args))
                else:
                    raise Unsupported("a call other than a tensor or an empty OrderedDict")
            elif name in ("SETITEM", "SETITEMS"):
                items = pop_mark() if name == "SETITEMS" else [stack.pop(-2), stack.pop()]
                if not isinstance(stack[-1], dict):
                    raise Unsupported("items set on something other than a dict")
                stack[-1].update(zip(items[::2], items[1::2], strict=True))
            elif name == "STOP":
                result = stack.pop()
                if not isinstance(result, dict):
                    raise Unsupported("the top object is not a dict")
                return result
            else:
                raise Unsupported(f"pickle opcode {name}")
    except Unsupported:
        raise
    except Exception as exc:  # truncated stream, bad memo index, wrong stack shape...
        raise Unsupported(f"a malformed pickle ({type(exc).__name__})") from None
    raise Unsupported("a pickle without STOP")
