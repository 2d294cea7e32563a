"""The README's video frames, rendered by the same code as ``ledsim render``.

    python scripts/readme_images.py      # about 15 s

docs/img/alignment_occluded.png: side camera, the KKL loop (seed 0) at t = 4 s while a
plate cuts the beam (the overlay shows the lost link). docs/img/alignment.png: chase
camera, the same loop at t = 3 s, aligned.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "osmesa")

from ledsim.loop.run_config import RunConfig  # noqa: E402
from ledsim.loop.video import VideoSpec, render_video  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "docs" / "img"
SHOTS = [  # (file, camera, run)
    ("alignment_occluded.png", "side",
     RunConfig(seconds=4.0, disturbances=("occlusion:start=3.7,duration=0.3",))),
    ("alignment.png", "chase", RunConfig(seconds=3.0)),
]


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        for name, camera, cfg in SHOTS:
            render_video(cfg, 0, Path(tmp) / "v.mp4", VideoSpec(camera=camera),
                         still=OUT / name)
            print(OUT / name)


if __name__ == "__main__":
    main()
