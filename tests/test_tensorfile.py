"""Checkpoints load without torch and without executing anything in the file."""

from __future__ import annotations

import pickle
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
import torch

from observer import checkpoint, tensorfile

SHIPPED = sorted((Path(__file__).parent.parent / "ledsim" / "assets" / "checkpoints")
                 .glob("*.pt"))


@pytest.mark.parametrize("path", SHIPPED, ids=[p.name for p in SHIPPED])
def test_every_shipped_checkpoint_reads_as_torch_loads_it(path):
    ours = tensorfile.read(path)
    ref = torch.load(path, map_location="cpu", weights_only=True)
    assert ours.keys() == ref.keys()
    for k, v in ref.items():
        if isinstance(v, torch.Tensor):
            assert ours[k].dtype == v.numpy().dtype
            np.testing.assert_array_equal(ours[k], v.numpy(), err_msg=k)
        else:
            assert ours[k] == v


def test_dtypes_offsets_and_the_torch_fallback(tmp_path, tiny_observer, system):
    base = torch.arange(12, dtype=torch.float64)
    payload = {"f32": torch.linspace(0, 1, 7, dtype=torch.float32),
               "view": base[3:9].reshape(2, 3), "i64": torch.tensor([1, -2]),
               "strided": base.reshape(3, 4).t(), "s": "text", "n": 3}
    torch.save(payload, tmp_path / "t.pt")
    with pytest.raises(tensorfile.Unsupported, match="strided"):
        tensorfile.read(tmp_path / "t.pt")
    del payload["strided"]
    torch.save(payload, tmp_path / "t.pt")
    got = tensorfile.read(tmp_path / "t.pt")
    for k in ("f32", "view", "i64"):
        np.testing.assert_array_equal(got[k], payload[k].numpy())
    assert got["s"] == "text" and got["n"] == 3
    # A checkpoint with a strided weight is outside the reader: torch.load takes over.
    good = checkpoint.save(tiny_observer, tmp_path / "good.pt")
    p = torch.load(good, weights_only=True)
    p["encoder_T.W1"] = p["encoder_T.W1"].t().contiguous().t()
    torch.save(p, tmp_path / "strided.pt")
    x = np.array([[0.1, 0.02]])
    np.testing.assert_array_equal(checkpoint.load(tmp_path / "strided.pt", system).encode(x),
                                  checkpoint.load(good, system).encode(x))


class _Payload:
    def __init__(self, marker: Path):
        self.marker = marker

    def __reduce__(self):
        return (Path.touch, (self.marker,))


def test_a_pickle_that_would_run_code_is_refused_and_not_run(tmp_path, system):
    marker = tmp_path / "ran"
    bad = tmp_path / "evil.pt"
    with zipfile.ZipFile(bad, "w") as z:
        z.writestr("evil/data.pkl", pickle.dumps({"x": _Payload(marker)}, protocol=2))
        z.writestr("evil/byteorder", "little")
    with pytest.raises(tensorfile.Unsupported, match="global"):
        tensorfile.read(bad)
    with pytest.raises(checkpoint.CheckpointError, match="corrupt"):
        checkpoint.load(bad, system)
    assert not marker.exists()


@pytest.mark.parametrize("cut", [10, 200, 2000])
def test_truncated_and_mangled_pickles_are_unsupported(tmp_path, cut):
    src = SHIPPED[0]
    with zipfile.ZipFile(src) as z:
        names = z.namelist()
        files = {n: z.read(n) for n in names}
    pkl = next(n for n in names if n.endswith("data.pkl"))
    files[pkl] = files[pkl][:cut]
    bad = tmp_path / "cut.pt"
    with zipfile.ZipFile(bad, "w") as z:
        for n, b in files.items():
            z.writestr(n, b)
    with pytest.raises(tensorfile.Unsupported):
        tensorfile.read(bad)


def test_a_short_run_does_not_import_torch(tmp_path):
    """``ledsim run`` with the shipped KKL bank loads its checkpoints without torch (the
    import alone cost a one-seed run about a second)."""
    code = ("import sys; from ledsim.cli import main\n"
            "try:\n    main(sys.argv[1:])\nexcept SystemExit as e:\n    assert not e.code\n"
            "assert 'torch' not in sys.modules, 'torch was imported'")
    subprocess.run([sys.executable, "-c", code, "run", "--seeds", "1", "--seconds", "1",
                    "--no-plot", "-q", "--out", str(tmp_path / "o")], check=True)
    assert (tmp_path / "o" / "results.json").is_file()
