"""All-or-nothing output folders: a command's files appear together, or not at all."""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from observer.atomic import check_interrupt

from .errors import LedsimError


def _can_create_in(folder: Path) -> bool:
    """Whether an entry can really be made in ``folder``: permission bits are not enough
    (root passes ``os.access`` on ``/proc`` and read-only mounts). Leaves nothing."""
    if not folder.is_dir() or not os.access(folder, os.W_OK | os.X_OK):
        return False
    try:
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


def check_out_file(path: str | Path, suffix: str, flag: str = "--out") -> Path:
    """Refuse an output file that could not be written, before any work is done."""
    out = Path(path)
    if out.is_dir():
        raise LedsimError(f"{flag} {str(path)!r} is a folder, not a file")
    if out.suffix.lower() != suffix:
        raise LedsimError(f"{flag} {str(path)!r}: the file must end in {suffix}")
    parent = out.parent
    if not _can_create_in(parent):
        raise LedsimError(f"{flag} {str(path)!r}: folder {str(parent)!r} does not exist or is not "
                          "writable")
    return out


@contextmanager
def output_folder(out: str | Path) -> Iterator[Path]:
    """Yield a private folder to write into; on success its entries move into ``out``.

    Everything is written beside ``out`` under a unique temporary name, so an error or
    an interrupt leaves ``out`` as it was, and two runs to the same ``out`` never share
    a file. A new ``out`` appears in one rename.
    """
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(dir=out.parent, prefix=f".{out.name}.", suffix=".partial"))
    try:
        yield tmp
        check_interrupt()
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    if not out.exists():
        os.replace(tmp, out)
        return
    for entry in tmp.iterdir():
        dest = out / entry.name
        if dest.is_dir() and entry.is_dir():
            shutil.rmtree(dest)
        os.replace(entry, dest)
    tmp.rmdir()
