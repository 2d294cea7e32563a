"""Convert ``.pt`` checkpoints (``torch.save``, ledsim 0.2 and earlier) to ``.safetensors``.

    python scripts/convert_checkpoints.py [PATH.pt ...]     # needs torch

Writes ``PATH.safetensors`` beside each (and its metadata in ``PATH.json``), then reads
both files back and checks that the new one holds the same format, the same metadata and
the same arrays, bit for bit (dtype, shape and bytes). The ``.pt`` is left as it is: a
``.pt`` name given to ledsim stands for its ``.safetensors`` sibling. Without a PATH,
every ``.pt`` in ledsim/assets/checkpoints (how the shipped observers were converted).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ledsim.files.outputs import atomic_write_bytes
from observer.kkl import checkpoint, checkpoint_io

SHIPPED = Path(__file__).resolve().parent.parent / "ledsim" / "assets" / "checkpoints"


def _write(path: Path, data: bytes) -> None:
    atomic_write_bytes(path, lambda tmp: Path(tmp).write_bytes(data))


def same(a: checkpoint.Stored, b: checkpoint.Stored) -> str | None:
    """What differs between two checkpoints' contents (None: nothing, bit for bit)."""
    if (a.format, a.metadata_json) != (b.format, b.metadata_json):
        return "format or metadata"
    if a.arrays.keys() != b.arrays.keys():
        return f"array names {sorted(a.arrays)} vs {sorted(b.arrays)}"
    for k, x in a.arrays.items():
        y = b.arrays[k]
        if x.dtype != y.dtype or x.shape != y.shape or x.tobytes() != y.tobytes():
            return f"array {k!r}"
    return None


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("paths", nargs="*", type=Path, help=".pt checkpoints")
    args = ap.parse_args()
    paths = args.paths or sorted(SHIPPED.glob("*.pt"))
    if not paths:
        print("nothing to convert", file=sys.stderr)
        return 0
    for src in paths:
        try:
            dst = checkpoint_io.convert(src, write_bytes=_write)
            diff = same(checkpoint.read(src), checkpoint.read(dst))
        except checkpoint.CheckpointError as exc:
            print(f"convert_checkpoints: error: {exc}", file=sys.stderr)
            return 2
        if diff:
            print(f"convert_checkpoints: error: {dst} differs from {src} in {diff}",
                  file=sys.stderr)
            return 1
        print(f"{src} -> {dst} ({src.stat().st_size} -> {dst.stat().st_size} bytes)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
