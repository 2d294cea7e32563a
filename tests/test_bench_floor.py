"""scripts/bench_floor.py: the parts' floors run, and its stacked maps are the maps."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))

import bench_floor  # noqa: E402


@pytest.fixture(scope="module")
def estimators():
    from ledsim.loop.closed_loop import ClosedLoop
    from ledsim.loop.run_config import RunConfig

    cfg = RunConfig(scenario="align", estimator="kkl", supervision=True, seconds=0.3)
    loop = ClosedLoop(cfg, range(3))
    loop.run()
    return [r.step.estimator for r in loop.runs]


def test_stacked_maps_equal_the_seed_by_seed_calls(estimators):
    """The numpy reference's maps, stacked and seed by seed (the compiled maps agree
    with them to round-off: tests/test_compiled.py)."""
    from observer import jit

    with jit.use(False):
        _stacked_equal(estimators[0])


def _stacked_equal(e) -> None:
    rng = np.random.default_rng(0)
    lo, hi = e.design.w_range
    ws = list(np.exp(rng.uniform(np.log(lo), np.log(hi), 5)))
    ss = [1.0, 1.5, 2.0, 1.0, 3.0]
    z = rng.normal(size=(5, e.q)) * 1e-3 + e.z
    got = bench_floor._stacked(e.decoder_T_star, z[:, None], ws, ss)
    want = np.array([e.decoder_T_star(z[i], ws[i], ss[i]) for i in range(5)])
    assert np.array_equal(got, want)
    x = rng.normal(size=(5, 2)) * 0.1
    got = bench_floor._stacked(e.encoder_T, x[:, None], ws, [1.0] * 5)
    assert np.array_equal(got, np.array([e.encoder_T(x[i], ws[i]) for i in range(5)]))


def test_measure_reports_every_part():
    r = bench_floor.measure(2, 0.05)
    for key in ("loop_sps", "rollout_sps", "physics_us", "maps_one_by_one_us",
                "maps_stacked_us", "vehicle_us", "sensor_us", "floor_us"):
        assert r[key] > 0, key
    assert r["maps_stacked_max_difference"] <= 1e-12  # numpy stacked, compiled one by one
    assert r["floor_us"] > r["estimator_floor_us"] > r["physics_us"]
    assert r["world_floor_us"] > 0
    assert r["loop_less_control_us"] == r["loop_run_us"] - r["control_us"] > 0
    assert "| **physics and the maps**" in bench_floor.table(r)


def test_bad_seeds_is_one_line_and_exit_2():
    p = subprocess.run([sys.executable, str(ROOT / "scripts" / "bench_floor.py"),
                        "--seeds", "0"], capture_output=True, text=True, timeout=120)
    assert p.returncode == 2
    assert p.stderr.strip() == "bench_floor: error: --seeds 0 is not allowed: must be > 0"
