"""Interrupted commands leave nothing behind: no output, no temporary file, exit 130."""

import signal
import subprocess
import sys
import time

import pytest

COMMANDS = {
    # Long enough to be mid-work at the interrupt however fast the loop gets (at 24x real
    # time, 4 x 30 s used to end right at the 4 s mark, and the signal hit the exit).
    "run": ["run", "--estimator", "ekf", "--seeds", "4", "--workers", "2", "--seconds", "120",
            "--out", "{out}"],
    "evaluate": ["evaluate", "--scenario", "if1", "--seeds", "20", "--workers", "2",
                 "--out", "{out}"],
    "simulate": ["simulate", "--seconds", "3600", "--out", "{out}"],
    "demo": ["demo", "--seeds", "4", "--out", "{out}"],
    "render": ["render", "--seconds", "30", "--width", "160", "--height", "120",
               "--out", "{out}.mp4"],
    "train": ["train", "--samples", "400000", "--out", "{out}.pt"],
}


@pytest.mark.parametrize("name", list(COMMANDS))
def test_sigint_leaves_nothing_behind(tmp_path, name):
    out = tmp_path / "result"
    args = [a.format(out=out) for a in COMMANDS[name]]
    proc = subprocess.Popen([sys.executable, "-m", "ledsim.cli", *args, "--quiet"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(4.0)  # well into the work
    assert proc.poll() is None, f"{name} finished before the interrupt: {proc.communicate()}"
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "interrupted" in err
    assert list(tmp_path.iterdir()) == [], sorted(p.name for p in tmp_path.iterdir())


def test_two_renders_to_one_file_never_share_a_temporary(tmp_path):
    import imageio.v3 as iio

    out = tmp_path / "clip.mp4"
    procs = [subprocess.Popen([sys.executable, "-m", "ledsim.cli", "render", "--seconds", s,
                               "--width", "160", "--height", "120", "--fps", "10", "--quiet",
                               "--out", str(out)], stderr=subprocess.PIPE, text=True)
             for s in ("1.0", "1.5")]
    for p in procs:
        _, err = p.communicate(timeout=300)
        assert p.returncode == 0, err
    assert iio.imread(out).shape[0] in (10, 15)  # one whole video, not a mix
    assert [p.name for p in tmp_path.iterdir()] == ["clip.mp4"]


def test_a_swallowed_interrupt_still_commits_nothing(tmp_path):
    # Python ignores a KeyboardInterrupt raised in some callbacks (an import lock's), so
    # the work can finish after a Ctrl-C: the flag the handler sets stops the commit.
    from ledsim.outputs import INTERRUPTED, atomic_write_text, output_folder

    INTERRUPTED.set()
    try:
        with pytest.raises(KeyboardInterrupt):
            with output_folder(tmp_path / "out") as tmp:
                (tmp / "table.md").write_text("x")
        with pytest.raises(KeyboardInterrupt):
            atomic_write_text(tmp_path / "a.json", "{}")
    finally:
        INTERRUPTED.clear()
    assert list(tmp_path.iterdir()) == []


def test_a_failed_output_folder_takes_away_the_folders_made_for_it(tmp_path):
    from ledsim.outputs import output_folder

    (tmp_path / "kept").mkdir()
    with pytest.raises(RuntimeError):
        with output_folder(tmp_path / "kept" / "new" / "deeper" / "out") as tmp:
            (tmp / "table.md").write_text("x")
            raise RuntimeError("the work failed")
    assert [p.name for p in tmp_path.rglob("*")] == ["kept"]


def test_demo_checks_every_estimator_and_its_video_before_it_writes(tmp_path):
    """A scene the demo cannot use is refused before its first run, with nothing
    written: not even the folders of --out (the demo used to check each estimator in
    its output folder, and left that folder's parents behind)."""
    from conftest import assert_user_error, run_cli

    out = tmp_path / "a" / "b"
    r = run_cli("demo", "--scene", str(tmp_path / "missing.xml"), "--out", str(out))
    assert_user_error(r, "missing.xml")
    assert list(tmp_path.iterdir()) == []
