"""Checkpoints are safetensors files, read without torch and without executing anything;
the shipped ones hold what their ``.pt`` files held, bit for bit; a ``.pt`` of ledsim 0.2
still loads where torch is installed."""

from __future__ import annotations

import hashlib
import json
import pickle
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from ledsim.files.resources import checkpoint_dir, shipped_checkpoint
from observer.kkl import checkpoint, checkpoint_io

#: sha256 (its first 128 bits) of each shipped checkpoint's format, metadata and arrays
#: (:func:`_digest`), taken from its .pt file by ``torch.load(..., weights_only=True)``
#: before it was converted (scripts/convert_checkpoints.py) and removed; the pan-tilt's
#: pair, trained as .safetensors by scripts/train_pan_tilt.py, as saved.
SHIPPED_DIGESTS = {
    "kkl_d0.085": "02dac53b16d9f37676388580bf94ca19",
    "kkl_d0.1": "df5512bd957695e16fe0e8ecf9075d6b",
    "kkl_d0.2": "b6bb9d2b631bcb332f128fdc95599d3e",
    "kkl_mujoco_d0.085": "a26ccf0b57a4dd4c5ced3bd7d49ca5e9",
    "kkl_mujoco_d0.085_noise13": "3b98b5f30caf54aefb98948a2d468e21",
    "kkl_mujoco_d0.085_noise3": "76bd382012740440654f0d76e4c0eb6b",
    "kkl_mujoco_d0.085_noise6": "a495577c004ae37aa9be67a23a10da0a",
    "kkl_mujoco_d0.1": "840541633992eaa7782bc38d030d0bc9",
    "kkl_mujoco_d0.2": "043ba850fee8b45a8aa16a898f00985b",
    "kkl_mujoco_lens_d0.085": "9ff43f11cef57236e8cdbd529efe43f6",
    "kkl_mujoco_lens_d0.085_noise13": "35338e20cabc258f561824502c73140d",
    "kkl_mujoco_lens_d0.085_noise3": "dcd32d55367a0819e4e0c962e874175c",
    "kkl_mujoco_lens_d0.085_noise6": "8788fcb3e7b0b1991674b40a47ddb676",
    "kkl_mujoco_scheduled_d0.085": "ce74190f9b9427be77904dd81537ed90",
    "kkl_mujoco_scheduled_lens_d0.085": "4bd225c62e1a5d433df968289d44a53d",
    "kkl_pan_tilt_azimuth": "237c10132d588e8f4c6dcea628e6c0d7",
    "kkl_pan_tilt_elevation": "bece8300666e7185af743f7176d7904e",
    "kkl_pan_tilt_lens10_azimuth": "c4221972bbe1f1c819fe0033f31ab44d",
    "kkl_pan_tilt_lens10_elevation": "38ea33a01ff97f2353f5dbde30f273c9",
    "kkl_paper_d0.085": "39b2c56fde93e732ef115dab14eda1c7",
    "kkl_scheduled_d0.085": "cd7ddc5e2c5df531c2fe709de87dc85c",
    "kkl_scheduled_d0.1": "0de3fcbede77b765a218d49c0fb438ff",
    "kkl_scheduled_d0.2": "f0900b32919ccde8a32831d337592c09",
    "kkl_slow_d0.1": "22aca20d1911614f0bbe8d1e34d1fa99",
    "kkl_slow_d0.2": "b617ba0a9208ce8f5bb75ccac6e04bc0",
}


def _digest(stored: checkpoint.Stored) -> str:
    h = hashlib.sha256()
    h.update(stored.format.encode())
    h.update(stored.metadata_json.encode())
    for k in sorted(stored.arrays):
        a = stored.arrays[k]
        h.update(f"{k}|{a.dtype.str}|{a.shape}|".encode())
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()[:32]


def test_the_shipped_checkpoints_hold_what_their_pt_files_held():
    shipped = {p.stem: p for p in checkpoint_dir().glob("*.safetensors")}
    assert shipped.keys() == SHIPPED_DIGESTS.keys()
    assert not list(checkpoint_dir().glob("*.pt"))
    for stem, path in shipped.items():
        stored = checkpoint.read(path)
        assert _digest(stored) == SHIPPED_DIGESTS[stem], stem
        assert json.loads(path.with_suffix(".json").read_text()) == \
            json.loads(stored.metadata_json), stem


def test_a_shipped_pt_name_stands_for_its_safetensors(system):
    """The names docs and scripts used (kkl_d0.085.pt) still load the shipped observer."""
    new = shipped_checkpoint(0.085)
    old = new.with_suffix(".pt")
    assert not old.exists() and checkpoint.resolve(old) == new
    x = np.array([[0.1, 0.02]])
    np.testing.assert_array_equal(checkpoint.load(old, system).encode(x),
                                  checkpoint.load(new, system).encode(x))
    assert checkpoint.metadata(old) == checkpoint.metadata(new)


def test_save_to_a_pt_name_writes_its_safetensors_sibling(tiny_observer, system, tmp_path):
    path = checkpoint.save(tiny_observer, tmp_path / "m.pt")
    assert path == tmp_path / "m.safetensors"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.json", "m.safetensors"]
    assert checkpoint.load(tmp_path / "m.pt", system).q == tiny_observer.q


def _legacy_pt(obs, path: Path) -> Path:
    """``obs`` as ledsim 0.2 saved it: ``torch.save`` of the format, the metadata and
    the tensors."""
    torch = pytest.importorskip("torch")
    stored = checkpoint.read(checkpoint.save(obs, path.with_suffix(".safetensors")))
    torch.save({"format": stored.format, "metadata_json": stored.metadata_json,
                **{k: torch.from_numpy(a.copy()) for k, a in stored.arrays.items()}}, path)
    path.with_suffix(".safetensors").unlink()
    return path


def test_a_pt_of_ledsim_0_2_loads_through_torch_and_converts(tiny_observer, system,
                                                             tmp_path):
    old = _legacy_pt(tiny_observer, tmp_path / "old.pt")
    x = np.array([[0.1, 0.02], [-0.2, 0.1]])
    np.testing.assert_array_equal(checkpoint.load(old, system).encode(x),
                                  tiny_observer.encode(x))
    new = checkpoint_io.convert(old)
    assert new == tmp_path / "old.safetensors" and old.is_file()
    assert _digest(checkpoint.read(new)) == _digest(checkpoint.read(old))
    r = subprocess.run([sys.executable, "scripts/convert_checkpoints.py", str(old)],
                       capture_output=True, text=True,
                       cwd=Path(__file__).resolve().parent.parent)
    assert r.returncode == 0 and "old.safetensors" in r.stdout, r.stderr


def test_without_torch_a_pt_is_refused_in_one_line(tiny_observer, system, tmp_path,
                                                   monkeypatch):
    old = _legacy_pt(tiny_observer, tmp_path / "old.pt")
    monkeypatch.setitem(sys.modules, "torch", None)  # import torch raises ImportError
    with pytest.raises(checkpoint.CheckpointError, match="needs torch") as e:
        checkpoint.load(old, system)
    assert "convert_checkpoints.py" in str(e.value) and "\n" not in str(e.value)


class _Payload:
    def __init__(self, marker: Path):
        self.marker = marker

    def __reduce__(self):
        return (Path.touch, (self.marker,))


def test_a_pickle_that_would_run_code_is_refused_and_not_run(tmp_path, system):
    pytest.importorskip("torch")
    marker = tmp_path / "ran"
    bad = tmp_path / "evil.pt"
    with zipfile.ZipFile(bad, "w") as z:
        z.writestr("evil/data.pkl", pickle.dumps({"x": _Payload(marker)}, protocol=2))
        z.writestr("evil/byteorder", "little")
    with pytest.raises(checkpoint.CheckpointError, match="corrupt"):
        checkpoint.load(bad, system)
    assert not marker.exists()


def test_damaged_and_foreign_files_are_refused(tmp_path, system, tiny_observer):
    from safetensors.numpy import save_file

    good = checkpoint.save(tiny_observer, tmp_path / "good.safetensors").read_bytes()
    cases = {"empty": b"", "cut": good[:len(good) // 2], "header": good[:20],
             "json": b'{"format": "ledsim-kkl/1"}', "text": b"not a checkpoint"}
    for name, data in cases.items():
        (tmp_path / f"{name}.safetensors").write_bytes(data)
        with pytest.raises(checkpoint.CheckpointError, match="corrupt") as e:
            checkpoint.load(tmp_path / f"{name}.safetensors", system)
        assert "\n" not in str(e.value)
    save_file({"w": np.zeros(3)}, tmp_path / "model.safetensors", metadata={"format": "pt"})
    with pytest.raises(checkpoint.CheckpointError, match="not a ledsim checkpoint"):
        checkpoint.load(tmp_path / "model.safetensors", system)


def test_a_short_run_does_not_import_torch(tmp_path):
    """``ledsim run`` with the shipped KKL bank loads its checkpoints without torch (the
    import alone cost a one-seed run about a second)."""
    code = ("import sys; from ledsim.cli import main\n"
            "try:\n    main(sys.argv[1:])\nexcept SystemExit as e:\n    assert not e.code\n"
            "assert 'torch' not in sys.modules, 'torch was imported'")
    subprocess.run([sys.executable, "-c", code, "run", "--seeds", "1", "--seconds", "1",
                    "--no-plot", "-q", "--out", str(tmp_path / "o")], check=True)
    assert (tmp_path / "o" / "results.json").is_file()
