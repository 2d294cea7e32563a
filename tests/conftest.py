import os
import subprocess
import sys

os.environ.setdefault("MUJOCO_GL", "osmesa")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from ledsim.constants import LinkConstants  # noqa: E402
from ledsim.paper.model import LEDLinkModel  # noqa: E402


def run_cli(*args, env=None, cwd=None):
    """Run ``python -m ledsim.cli ARGS`` as a user would; returns the CompletedProcess."""
    return subprocess.run([sys.executable, "-m", "ledsim.cli", *args], capture_output=True,
                          text=True, timeout=600, env=env, cwd=cwd)


def assert_user_error(r, needle: str) -> None:
    """A user mistake: exit 2, one line on stderr naming ``needle``, no traceback."""
    assert r.returncode == 2, r.stderr
    assert needle in r.stderr, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "Traceback" not in r.stderr


@pytest.fixture(scope="session")
def system():
    return LEDLinkModel(LinkConstants())


@pytest.fixture(scope="session")
def tiny_observer(system):
    """A small KKL observer trained in a few seconds (default recipe, fewer samples)."""
    from ledsim.experiment.observer_presets import observer_preset
    from observer.kkl.training import train_kkl

    design, cfg = observer_preset("default", system.Te)
    cfg.n_samples = 30_000
    cfg.hidden = 300
    obs, _ = train_kkl(system, design, cfg, progress=False)
    return obs


@pytest.fixture
def rng():
    return np.random.default_rng(0)
