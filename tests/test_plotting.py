"""Every figure function writes a PNG that shows something."""

import numpy as np

from ledsim.experiment.plotting import plot_estimates, plot_powers, plot_powers_by_distance
from ledsim.paper.scenarios import Trajectory


def fake_trajectory(scale: float) -> Trajectory:
    t = np.linspace(0, 1, 100)
    x = np.stack([0.1 * np.sin(6 * t), 0.6 * np.cos(6 * t)], -1)
    y = scale * np.stack([np.cos(x[:, 0]), np.cos(x[:, 0] + 0.1)], -1)
    return Trajectory(x, x + 0.01, y + 0.01, y, y * 0.99, np.zeros(100), 0.0)


def test_figures_are_written(tmp_path):
    traces = {"kkl": fake_trajectory(1.0), "ekf": fake_trajectory(1.0)}
    paths = [plot_estimates(traces, 0.01, "t", tmp_path / "a.png"),
             plot_powers(traces, 0.01, "t", tmp_path / "b.png"),
             plot_powers_by_distance({0.085: fake_trajectory(1.0), 0.2: fake_trajectory(0.2)},
                                     0.01, "t", tmp_path / "c.png")]
    for p in paths:
        assert p.stat().st_size > 10_000 and p.read_bytes()[:4] == b"\x89PNG"
