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

# old module -> its home now (aliases; observer/ grouped by what it estimates, issue 47).
# observer.kkl, observer.navigation and observer.supervision became the packages of their
# groups; each package lends its old module's names (see its __init__).
MOVED: dict[str, str] = {
    "observer.bank": "observer.kkl.bank",
    "observer.checkpoint": "observer.kkl.checkpoint",
    "observer.checkpoint_io": "observer.kkl.checkpoint_io",
    "observer.export": "observer.kkl.export",
    "observer.errors": "observer.exceptions",
    "observer.fading": "observer.supervision.fading",
    "observer.fitting": "observer.kkl.fitting",
    "observer.gain_tracking": "observer.supervision.gain_tracking",
    "observer.gainmaps": "observer.kkl.gainmaps",
    "observer.gimbal_load": "observer.supervision.gimbal_load",
    "observer.handover": "observer.kkl.handover",
    "observer.hull_loads": "observer.navigation.hull_loads",
    "observer.ins": "observer.navigation.ins",
    "observer.ins_aiding": "observer.navigation.ins_aiding",
    "observer.ins_state": "observer.navigation.ins_state",
    "observer.line_of_sight": "observer.navigation.line_of_sight",
    "observer.maps": "observer.kkl.maps",
    "observer.nets": "observer.kkl.nets",
    "observer.occlusion": "observer.supervision.occlusion",
    "observer.oracle": "observer.baselines.oracle",
    "observer.rotations": "observer.navigation.rotations",
    "observer.scheduled": "observer.kkl.scheduled",
    "observer.scheduled_checkpoint": "observer.kkl.scheduled_checkpoint",
    "observer.scheduled_design": "observer.kkl.scheduled_design",
    "observer.scheduled_training": "observer.kkl.scheduled_training",
    "observer.training": "observer.kkl.training",
}


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


def lent_names(module: str):
    """A package's ``__getattr__`` that lends it the names of ``module``: the package took
    the old module's path (``observer.kkl``), so ``from observer.kkl import KKLObserver``
    still works (an alias; new code imports from ``module``)."""
    package = module.rpartition(".")[0]

    def __getattr__(name: str):
        if not name.startswith("__"):
            try:
                return getattr(importlib.import_module(module), name)
            except AttributeError:
                pass
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    return __getattr__


def install(table: dict[str, str]) -> None:
    """Put a finder for ``table`` on :data:`sys.meta_path` (once per table)."""
    if not any(isinstance(f, MovedModules) and f.table is table for f in sys.meta_path):
        sys.meta_path.append(MovedModules(table))


install(MOVED)
