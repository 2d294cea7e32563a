"""Old module paths keep working after issue 47's moves: each is the very module it moved to."""

import importlib
import subprocess
import sys
from pathlib import Path

import pytest

from ledsim.moved import MOVED
from observer.moved import MOVED as OBSERVER_MOVED

ROOT = Path(__file__).resolve().parent.parent
TABLE = {**MOVED, **OBSERVER_MOVED}


@pytest.mark.parametrize("old", sorted(TABLE))
def test_an_old_path_is_the_module_it_moved_to(old):
    new = TABLE[old]
    assert not (ROOT / (old.replace(".", "/") + ".py")).exists(), f"{old} still has a file"
    module = importlib.import_module(old)
    assert module is importlib.import_module(new)
    assert module.__spec__.name == new  # the alias does not rename the module


def test_names_import_from_old_paths_in_a_fresh_interpreter():
    """The README's and CHANGELOG's spellings, before anything else imported the new ones."""
    code = ("from ledsim.step import ControlStep\n"
            "from ledsim.loop.config import RunConfig\n"
            "from ledsim.physics.vehicle import Vehicle\n"
            "import ledsim.agent.step, ledsim.loop.run_config, ledsim.agent.autopilot\n"
            "assert ControlStep is ledsim.agent.step.ControlStep\n"
            "assert RunConfig is ledsim.loop.run_config.RunConfig\n"
            "assert Vehicle is ledsim.agent.autopilot.Vehicle\n"
            "import ledsim.optics\n"
            "assert ledsim.optics.photodiode_power.__module__ == 'ledsim.radiometry.optics'\n"
            "print('ok')\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                       timeout=120)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr


def test_an_alias_to_nowhere_fails_loudly():
    from observer.moved import install

    table = {"ledsim.no_such_old_path": "ledsim.no_such_new_path"}
    install(table)
    with pytest.raises(ModuleNotFoundError, match="no_such_new_path"):
        importlib.import_module("ledsim.no_such_old_path")
    sys.modules.pop("ledsim.no_such_old_path", None)


def test_a_group_lends_the_names_of_the_module_whose_path_it_took():
    from observer.kkl import KKLObserver
    from observer.kkl.fixed_gain import KKLObserver as new
    from observer.supervision import ResidualMonitor
    from observer.supervision.monitor import ResidualMonitor as new_monitor

    assert KKLObserver is new and ResidualMonitor is new_monitor
    import observer.navigation

    with pytest.raises(AttributeError, match="no attribute 'NoSuchName'"):
        observer.navigation.NoSuchName  # noqa: B018
