"""All-or-nothing outputs: a file appears complete under its name, a command's files
appear together, or not at all; and the Ctrl-C flag that stops them being committed."""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import tempfile
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from ledsim.errors import LedsimError

#: Set by a command-line SIGINT handler. Python ignores a KeyboardInterrupt raised inside
#: some callbacks (an import lock's weakref callback, for one), so the work may carry on:
#: no output is then committed (:func:`check_interrupt` before every final rename).
INTERRUPTED = threading.Event()

#: The temporaries being written (files and folders beside their final names), for
#: :func:`discard_temporaries`.
_TEMPORARIES: set[Path] = set()
#: Held while outputs are renamed into place: :func:`discard_temporaries` waits for it.
_COMMITTING = threading.Lock()


def check_interrupt() -> None:
    """Raise KeyboardInterrupt if an interrupt was requested, even a swallowed one."""
    if INTERRUPTED.is_set():
        raise KeyboardInterrupt


@contextmanager
def deferred_sigint() -> Iterator[None]:
    """Hold Ctrl-C (SIGINT) back during the block and deliver it at its end, to the handler
    that was there before: for steps that an interrupt must not cut in two (starting a
    worker process, renaming a command's files into place), each quick.

    Only the main thread handles signals: elsewhere, or under a handler not installed from
    Python, the block runs as is."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.getsignal(signal.SIGINT)
    if previous in (None, signal.SIG_IGN):  # not Python's to hold back, or nothing to hold
        yield
        return
    held = []
    signal.signal(signal.SIGINT, lambda signum, frame: held.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        if held:
            signal.raise_signal(signal.SIGINT)


@contextmanager
def _committing() -> Iterator[None]:
    """Renaming outputs into place: not cut by Ctrl-C, nor by :func:`discard_temporaries`."""
    with deferred_sigint(), _COMMITTING:
        yield


def discard_temporaries() -> None:
    """Remove every temporary still being written, once any rename into place is done,
    and allow no rename after: the last resort of a process that must exit at once
    (``ledsim`` after Ctrl-C, when its cleanup overruns). Does not return the lock."""
    _COMMITTING.acquire()
    for tmp in list(_TEMPORARIES):
        if tmp.is_dir():
            shutil.rmtree(tmp, ignore_errors=True)
        else:
            try:
                tmp.unlink()
            except OSError:
                pass


def umask() -> int:
    """The process's umask (read without changing it)."""
    umask = os.umask(0)
    os.umask(umask)
    return umask


def atomic_write_bytes(path: Path, write) -> None:
    """Call ``write(tmp_path)`` then rename over ``path``: never a half-written file. The
    file gets the usual mode (0666 less the umask)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with deferred_sigint():  # no temporary made but not known
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
        _TEMPORARIES.add(Path(tmp))
    try:
        os.close(fd)
        write(tmp)
        os.chmod(tmp, 0o666 & ~umask())  # mkstemp makes 0600
        with _committing():
            check_interrupt()
            os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    finally:
        _TEMPORARIES.discard(Path(tmp))


def atomic_write_text(path: Path, text: str) -> None:
    atomic_write_bytes(path, lambda tmp: Path(tmp).write_text(text))


def save_checkpoint(obs, path: str | Path, extra: dict | None = None) -> Path:
    """:func:`observer.kkl.checkpoint.save` through :func:`atomic_write_bytes` (so Ctrl-C
    leaves no checkpoint behind). Returns the checkpoint's path (``.safetensors``, also
    for a ``.pt`` name)."""
    from observer.kkl import checkpoint

    return checkpoint.save(obs, path, extra, write_bytes=lambda p, data: atomic_write_bytes(
        p, lambda tmp: Path(tmp).write_bytes(data)))


def _can_create_in(folder: Path) -> bool:
    """Whether an entry can really be made in ``folder``: permission bits are not enough
    (root passes ``os.access`` on ``/proc`` and read-only mounts). Leaves nothing."""
    if not folder.is_dir() or not os.access(folder, os.W_OK | os.X_OK):
        return False
    try:
        with deferred_sigint():  # Ctrl-C would leave the probe behind
            os.rmdir(tempfile.mkdtemp(dir=folder, prefix=".ledsim-probe."))
    except OSError:
        return False
    return True


def check_out_dir(path: str | Path, flag: str = "--out") -> Path:
    """Refuse, before any work, a folder that could not be written: an existing file, or
    a path whose nearest existing parent is not a folder we can create entries in.
    Leaves nothing behind."""
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise LedsimError(f"{flag} {str(path)!r} exists and is not a folder")
    probe = out
    while not probe.exists():
        probe = probe.parent
    # The outputs are built beside ``out`` (output_folder), so its parent must take them.
    if not _can_create_in(probe) or (probe == out and not _can_create_in(out.parent)):
        raise LedsimError(f"{flag} {str(path)!r} cannot be written: {str(probe)!r} is not a "
                          "writable folder")
    return out


def check_out_file(path: str | Path, suffix: str | tuple[str, ...],
                   flag: str = "--out") -> Path:
    """Refuse an output file that could not be written, before any work is done.
    ``suffix``: the file's, or the ones it may have (the first is the usual one)."""
    out = Path(path)
    suffixes = (suffix,) if isinstance(suffix, str) else suffix
    if out.is_dir():
        raise LedsimError(f"{flag} {str(path)!r} is a folder, not a file")
    if out.suffix.lower() not in suffixes:
        raise LedsimError(f"{flag} {str(path)!r}: the file must end in "
                          f"{' or '.join(suffixes)}")
    parent = out.parent
    if not _can_create_in(parent):
        raise LedsimError(f"{flag} {str(path)!r}: folder {str(parent)!r} does not exist or is not "
                          "writable")
    return out


@contextmanager
def output_folder(out: str | Path) -> Iterator[Path]:
    """Yield a private folder to write into; on success its entries move into ``out``.

    Everything is written beside ``out`` under a unique temporary name, so an error or
    an interrupt leaves ``out`` as it was (and removes the folders made to hold it), and
    two runs to the same ``out`` never share a file. A new ``out`` appears in one rename;
    into an existing ``out`` the entries move one by one, with Ctrl-C held back until the
    last (:func:`deferred_sigint`).
    """
    out = Path(out)
    made = [p for p in out.absolute().parents if not p.exists()]  # innermost first
    out.parent.mkdir(parents=True, exist_ok=True)
    with deferred_sigint():  # no temporary made but not known
        tmp = Path(tempfile.mkdtemp(dir=out.parent, prefix=f".{out.name}.", suffix=".partial"))
        _TEMPORARIES.add(tmp)
    try:
        os.chmod(tmp, 0o777 & ~umask())  # mkdtemp makes 0700
        yield tmp
        with _committing():
            check_interrupt()
            _move_into(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        for folder in made:  # and the folders made for it, if still empty
            with contextlib.suppress(OSError):
                folder.rmdir()
        raise
    finally:
        _TEMPORARIES.discard(tmp)


def _move_into(tmp: Path, out: Path) -> None:
    """The entries of folder ``tmp`` into ``out`` (replacing those of the same name), or
    ``tmp`` renamed to ``out`` if there is none."""
    if not out.exists():
        os.replace(tmp, out)
        return
    for entry in tmp.iterdir():
        dest = out / entry.name
        if dest.is_dir() and entry.is_dir():
            shutil.rmtree(dest)
        os.replace(entry, dest)
    tmp.rmdir()
