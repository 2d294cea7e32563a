"""Old module paths that keep working after a module moved: one import hook, two tables.

``import ledsim.step`` gives the very module :mod:`ledsim.agent.step` (the same object,
so its classes, ``isinstance`` and ``monkeypatch`` targets are shared), without a shim
file at the old path. :data:`MOVED` lists the estimation package's moves; ledsim's are
in :mod:`ledsim.moved`. Each entry is an alias of a documented path; new code imports
the new one.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys

# old module -> its home now (aliases; observer/ grouped by what it estimates, issue 47)
MOVED: dict[str, str] = {}


class MovedModules(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds an old module path in ``table`` and loads it as the module it moved to."""

    def __init__(self, table: dict[str, str]):
        self.table = table

    def find_spec(self, fullname, path=None, target=None):
        if fullname not in self.table:
            return None
        return importlib.util.spec_from_loader(fullname, self)

    def create_module(self, spec):
        module = importlib.import_module(self.table[spec.name])
        spec.loader_state = module.__spec__
        return module

    def exec_module(self, module):
        # the import system stamped the alias's spec on the module; give it its own back
        module.__spec__ = module.__spec__.loader_state


def install(table: dict[str, str]) -> None:
    """Put a finder for ``table`` on :data:`sys.meta_path` (once per table)."""
    if not any(isinstance(f, MovedModules) and f.table is table for f in sys.meta_path):
        sys.meta_path.append(MovedModules(table))


install(MOVED)
