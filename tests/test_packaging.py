"""The wheel carries its scene and checkpoints and runs from any folder."""

import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    out = tmp_path_factory.mktemp("wheel")
    r = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps",
                        "--no-build-isolation", "-q", "-w", str(out), str(ROOT)],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    (path,) = out.glob("ledsim-*.whl")
    return path


def test_wheel_holds_the_scene_and_every_checkpoint(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    assert "ledsim/physics/led_link.xml" in names
    shipped = {p.name for p in (ROOT / "ledsim" / "assets" / "checkpoints").iterdir()}
    assert {f"ledsim/assets/checkpoints/{n}" for n in shipped} <= names


def test_wheel_holds_every_package(wheel):
    """Every package of the source tree is in the wheel (an installed wheel beside an
    editable install can borrow a missing one from the source and hide it)."""
    names = set(zipfile.ZipFile(wheel).namelist())
    packages = {str(p.relative_to(ROOT)) for pkg in ("ledsim", "observer")
                for p in (ROOT / pkg).rglob("__init__.py")}
    assert packages <= names, sorted(packages - names)


def test_installed_wheel_runs_from_another_folder(wheel, tmp_path):
    target = tmp_path / "site"
    r = subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps",
                        "--target", str(target), str(wheel)], capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stderr
    env = {k: v for k, v in os.environ.items() if k != "MUJOCO_GL"}
    env["PYTHONPATH"] = str(target)
    work = tmp_path / "elsewhere"
    work.mkdir()
    r = subprocess.run([sys.executable, "-m", "ledsim", "run", "--estimator", "kkl", "--seeds",
                        "1", "--seconds", "2", "--quiet", "--out", "res"], cwd=work, env=env,
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    assert (work / "res" / "results.json").is_file()
    r = subprocess.run([sys.executable, "-c", "import ledsim; print(ledsim.__file__)"],
                       cwd=work, env=env, capture_output=True, text=True)
    assert r.stdout.startswith(str(target))


def test_torch_is_the_train_extra_not_a_requirement(wheel):
    meta = next(n for n in zipfile.ZipFile(wheel).namelist() if n.endswith("METADATA"))
    lines = zipfile.ZipFile(wheel).read(meta).decode().splitlines()
    requires = [ln for ln in lines if ln.startswith("Requires-Dist:")]
    core = [ln for ln in requires if "extra ==" not in ln]
    assert not any("torch" in ln for ln in core), core
    assert any("torch" in ln and 'extra == "train"' in ln for ln in requires)
    assert any("onnxruntime" in ln and 'extra == "onnx"' in ln for ln in requires)
