"""Atomic file writes: a file appears complete under its name, or not at all."""

from __future__ import annotations

import os
import tempfile
import threading
from pathlib import Path

#: Set by a command-line SIGINT handler. Python ignores a KeyboardInterrupt raised inside
#: some callbacks (an import lock's weakref callback, for one), so the work may carry on:
#: no output is then committed (:func:`check_interrupt` before every final rename).
INTERRUPTED = threading.Event()


def check_interrupt() -> None:
    """Raise KeyboardInterrupt if an interrupt was requested, even a swallowed one."""
    if INTERRUPTED.is_set():
        raise KeyboardInterrupt


def atomic_write_bytes(path: Path, write) -> None:
    """Call ``write(tmp_path)`` then rename over ``path``: never a half-written file."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    umask = os.umask(0)
    os.umask(umask)
    try:
        write(tmp)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; give the usual file mode
        check_interrupt()
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def atomic_write_text(path: Path, text: str) -> None:
    atomic_write_bytes(path, lambda tmp: Path(tmp).write_text(text))
