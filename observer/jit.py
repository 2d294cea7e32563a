"""The compiled path: numba where it is installed, the numpy reference where it is not.

Every compiled kernel of the project has a Python (numpy) twin that stays the readable
reference; the classes call the kernel when :func:`enabled`. numba comes with the
package's ``fast`` extra (and with ``make``); without it, or with ``LEDSIM_COMPILED=0`` in
the environment, everything runs the reference path. The two agree to round-off
(``tests/test_compiled.py``): compiled math does not round as numpy does, so a
closed-loop run may part from the reference's in the last bits.

Kernels are compiled on their first call and cached on disk beside the module
(``cache=True``): the first run in a fresh checkout pays a few seconds once
(``python -m ledsim.loop.warm``, which ``make`` runs, pays them at install). numba itself
is imported with the first kernel module a run uses (:func:`lazy`), not with this one: a
process that never runs a kernel does not pay its import (0.25 s).
"""

from __future__ import annotations

import importlib
import importlib.util
import os
from contextlib import contextmanager

_installed = importlib.util.find_spec("numba") is not None

#: The environment variable that turns the compiled path off ("0", "false", "no", "off").
SWITCH = "LEDSIM_COMPILED"


def installed() -> bool:
    """numba can be imported."""
    return _installed


def _from_environment() -> bool:
    return _installed and \
        os.environ.get(SWITCH, "1").strip().lower() not in ("0", "false", "no", "off")


_enabled = _from_environment()


def enabled() -> bool:
    """The compiled kernels run: numba is installed and ``LEDSIM_COMPILED`` (read at
    import) did not turn them off, or :func:`use` switched them on."""
    return _enabled


@contextmanager
def use(compiled: bool):
    """Within the block, run the compiled kernels (``True``, where numba is installed) or
    the numpy reference (``False``); the previous choice after it."""
    global _enabled
    before = _enabled
    _enabled = bool(compiled) and _installed
    try:
        yield
    finally:
        _enabled = before


def njit(*args, **kwargs):
    """``numba.njit(cache=True, error_model="numpy", ...)`` (without the cache where
    numba finds nowhere to write it: a read-only install with no writable home and no
    ``NUMBA_CACHE_DIR``; each process then compiles what it runs); without numba, the
    function itself (the kernel is then only reachable through a path that checks
    :func:`enabled`, never called)."""
    kwargs.setdefault("cache", True)
    # numpy's error model: a division by zero gives inf or NaN, as in numpy, and the
    # loops vectorise (Python's model checks every division).
    kwargs.setdefault("error_model", "numpy")
    if not _installed:
        return args[0] if args and callable(args[0]) else (lambda f: f)
    import numba

    def decorate(f):
        try:
            return numba.njit(**kwargs)(f)
        except RuntimeError as exc:  # nowhere to write the cache (numba's locators)
            if not kwargs.get("cache") or "no locator available" not in str(exc):
                raise
            kwargs["cache"] = False  # compile in each process instead
            return numba.njit(**kwargs)(f)

    return decorate(args[0]) if args and callable(args[0]) else decorate


class lazy:  # noqa: N801 (used as a module)
    """A kernel module imported on first use: ``compiled_step = lazy("observer.kkl.
    compiled_step")``, then ``compiled_step.estimate(...)``. The first attribute read
    imports it and copies its names here, so later reads cost what a module's do."""

    def __init__(self, name: str):
        self._module_name = name

    def __getattr__(self, attr: str):  # only for names not copied yet
        module = importlib.import_module(self._module_name)
        self.__dict__.update(vars(module))
        return getattr(module, attr)
