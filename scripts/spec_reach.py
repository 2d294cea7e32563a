"""Which modules a run's spec enters: the ledsim and observer modules whose functions are
handed the run's spec (or one of its parts) during one ``ledsim run``, measured at run
time (``sys.setprofile``), with how many such calls each saw.

    python scripts/spec_reach.py [--seconds 0.2] [--json PATH]

It imports the spec by its old path (``ledsim.loop.config``, an alias now), so the same
script measures an older commit's tree too (``PYTHONPATH=<its worktree>``).
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import sys
import tempfile

os.environ.setdefault("MUJOCO_GL", "osmesa")


def reach(seconds: float) -> dict[str, int]:
    """``{module path: calls handed the spec}`` over one run of ``seconds``."""
    from ledsim.cli import main
    from ledsim.loop.config import PARTS, RunConfig  # the old path: every tree has it

    kinds = (RunConfig, *PARTS.values())
    hits: collections.Counter = collections.Counter()

    def profile(frame, event, arg):
        if event != "call":
            return
        path = frame.f_code.co_filename
        for root in ("/ledsim/", "/observer/"):
            if root in path and any(isinstance(v, kinds) for v in frame.f_locals.values()):
                hits[root.strip("/") + "/" + path.split(root)[-1]] += 1

    with tempfile.TemporaryDirectory() as out:
        sys.setprofile(profile)
        try:
            main(["run", "--seconds", str(seconds), "--seeds", "1", "--workers", "1",
                  "--no-plot", "-q", "--out", os.path.join(out, "run")])
        except SystemExit:
            pass
        finally:
            sys.setprofile(None)
    return dict(sorted(hits.items()))


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=0.2)
    ap.add_argument("--json", metavar="PATH")
    args = ap.parse_args()
    found = reach(args.seconds)
    for module, calls in found.items():
        print(f"{calls:6d}  {module}")
    print(f"{len(found)} modules")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(found, f, indent=1)
