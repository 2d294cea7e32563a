"""The compiled path: numba where it is installed, the numpy reference where it is not.

Every compiled kernel of the project has a Python (numpy) twin that stays the readable
reference; the classes call the kernel when :func:`enabled`. numba comes with the
package's ``fast`` extra (and with ``make``); without it, or with ``LEDSIM_COMPILED=0`` in
the environment, everything runs the reference path. The two agree to round-off
(``tests/test_compiled.py``): compiled math does not round as numpy does, so a
closed-loop run may part from the reference's in the last bits.

Kernels are compiled on their first call and cached on disk beside the module
(``cache=True``): the first run in a fresh checkout pays a few seconds once.
"""

from __future__ import annotations

import os
from contextlib import contextmanager

try:
    import numba
except ImportError:  # the reference path runs everywhere
    numba = None

#: The environment variable that turns the compiled path off ("0", "false", "no", "off").
SWITCH = "LEDSIM_COMPILED"


def installed() -> bool:
    """numba can be imported."""
    return numba is not None


def _from_environment() -> bool:
    return numba is not None and \
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
    _enabled = bool(compiled) and numba is not None
    try:
        yield
    finally:
        _enabled = before


def njit(*args, **kwargs):
    """``numba.njit(cache=True, error_model="numpy", ...)``; without numba, the function
    itself (the kernel is then only reachable through a path that checks
    :func:`enabled`, never called)."""
    kwargs.setdefault("cache", True)
    # numpy's error model: a division by zero gives inf or NaN, as in numpy, and the
    # loops vectorise (Python's model checks every division).
    kwargs.setdefault("error_model", "numpy")
    if numba is None:
        return args[0] if args and callable(args[0]) else (lambda f: f)
    return numba.njit(*args, **kwargs)
