"""``ledsim sweep``: a grid of closed-loop runs, resumable, the same on every backend."""

import csv

import pytest
from conftest import assert_user_error, run_cli

from ledsim.loop import sweep as sweep_mod
from ledsim.loop.run_config import RunConfig
from ledsim.loop.sweep import COLUMNS, TIMING_COLUMNS, SweepGrid, run_sweep, split_disturbance

OCCLUSION = "occlusion:start=2.2,duration=0.5"


def grid(seeds=1) -> SweepGrid:
    return SweepGrid(estimators=["kkl", "ekf"], disturbances=["none", OCCLUSION],
                     distances=[0.085], noise_scales=[1.0], seeds=seeds,
                     base=RunConfig(seconds=3.0))


def read(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def without_timing(rows):
    return [{k: v for k, v in r.items() if k not in TIMING_COLUMNS} for r in rows]


def test_split_disturbance():
    assert split_disturbance("none") == ()
    assert split_disturbance("current:speed=0.05,gust=0.02+occlusion:start=1e+0") == (
        "current:speed=0.05,gust=0.02", "occlusion:start=1e+0")


def test_sweep_writes_one_row_per_run_in_grid_order(tmp_path):
    rows, paths = run_sweep(grid(2), tmp_path / "s", workers=2, progress=False)
    table = read(tmp_path / "s" / "results.csv")
    assert list(table[0]) == list(COLUMNS)
    assert len(table) == 2 * 2 * 2
    assert [(r["estimator"], r["disturbance"], r["seed"]) for r in table[:4]] == [
        ("kkl", "none", "0"), ("kkl", "none", "1"), ("kkl", OCCLUSION, "0"),
        ("kkl", OCCLUSION, "1")]
    assert all(0.0 <= float(r["availability"]) <= 1.0 for r in table)
    # the occlusion costs availability with either estimator
    by = {(r["estimator"], r["disturbance"], r["seed"]): float(r["availability"])
          for r in table}
    assert by[("ekf", OCCLUSION, "0")] < by[("ekf", "none", "0")]
    assert len(read(tmp_path / "s" / "summary.csv")) == 4
    assert (tmp_path / "s" / "summary.png").stat().st_size > 1000


def test_interrupted_sweep_resumes_without_redoing_finished_runs(tmp_path, monkeypatch):
    out = tmp_path / "s"
    real_save, saved = sweep_mod.SweepStore.save, []

    def save_then_interrupt(self, cell, result):
        real_save(self, cell, result)
        saved.append(cell)
        if len(saved) == 2:
            raise KeyboardInterrupt

    monkeypatch.setattr(sweep_mod.SweepStore, "save", save_then_interrupt)
    with pytest.raises(KeyboardInterrupt):
        run_sweep(grid(), out, workers=1, progress=False)
    assert not (out / "results.csv").exists()  # tables only once every run is done
    monkeypatch.setattr(sweep_mod.SweepStore, "save", real_save)

    ran = []
    real_cell = sweep_mod.run_cell
    monkeypatch.setattr(sweep_mod, "run_cell", lambda job: ran.append(job[1]) or
                        real_cell(job))
    run_sweep(grid(), out, workers=1, progress=False)
    assert len(ran) == 2 and not set(ran) & set(saved)
    fresh = tmp_path / "fresh"
    run_sweep(grid(), fresh, workers=1, progress=False, plot=False)
    assert without_timing(read(out / "results.csv")) == without_timing(
        read(fresh / "results.csv"))


def test_ray_backend_gives_the_same_rows_as_local(tmp_path):
    pytest.importorskip("ray")
    run_sweep(grid(), tmp_path / "local", workers=2, progress=False, plot=False)
    run_sweep(grid(), tmp_path / "ray", backend="ray", workers=2, progress=False,
              plot=False)
    local, ray = read(tmp_path / "local" / "results.csv"), read(tmp_path / "ray" /
                                                                 "results.csv")
    assert list(local[0]) == list(ray[0])
    assert without_timing(local) == without_timing(ray)


@pytest.mark.parametrize("args,needle", [
    (["--estimator", "nope"], "nope"),
    (["--distance", "inf"], "must be finite"),
    (["--noise-scale", "0"], "--noise-scale: 0 is not allowed"),
    (["--disturbance", "occlusion:start=30,duration=1"], "start"),
    (["--address", "auto"], "--address needs --backend ray"),
    (["--seeds", "0"], "--seeds: 0 is not allowed"),
    (["--backend", "ray", "--address", "junk"], "HOST:PORT"),
    (["--backend", "ray", "--address", "127.0.0.1:1"], "cannot connect"),
])
def test_sweep_bad_input_is_one_line(tmp_path, args, needle):
    out = tmp_path / "o"
    assert_user_error(run_cli("sweep", *args, "--out", str(out)), needle)
    assert not out.exists()


@pytest.mark.parametrize("command", [["sweep"], ["run", "--seeds", "1", "--seconds", "1"],
                                     ["demo", "--no-video"]])
def test_an_output_folder_that_cannot_be_created_is_refused_before_any_work(command):
    # root passes os.access on /proc, so the check must really try to create an entry
    r = run_cli(*command, "--out", "/proc/ledsim-out")
    assert_user_error(r, "not a writable folder")
