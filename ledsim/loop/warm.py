"""Compile the control step's kernels once, ahead of the first run (:mod:`observer.jit`):
``python -m ledsim.loop.warm``, which ``make`` runs after installing.

numba compiles each kernel on its first call and caches it beside its module; a fresh
install would otherwise spend its first run's first seconds compiling (about 15 s on 2
cores). This runs a short supervised KKL run on the default world, which calls every
kernel the loop uses, and reports the time it took. Without numba, or with
``LEDSIM_COMPILED=0``, it says so and does nothing.
"""

from __future__ import annotations

import os
import sys
import time


def warm(seconds: float = 0.3) -> float | None:
    """Run ``seconds`` [s] of the align scenario on the paper's bench and on the default
    physical link (the yaw gimbal's and the pan-tilt's steps), so that the kernels are
    compiled and cached; returns the wall time [s] (None: the compiled path is off)."""
    os.environ.setdefault("MUJOCO_GL", "osmesa")
    from observer import jit

    if not jit.enabled():
        return None
    from ledsim.loop.closed_loop import run_once
    from ledsim.loop.run_config import RunConfig

    t0 = time.perf_counter()
    for link in ("paper", "luma"):
        run_once(RunConfig(scenario="align", estimator="kkl", seconds=seconds, link=link),
                 seed=0)
    return time.perf_counter() - t0


def main() -> int:
    spent = warm()
    if spent is None:
        print("ledsim: the compiled path is off (numba not installed, or LEDSIM_COMPILED=0)")
    else:
        print(f"ledsim: the control step's kernels are compiled and cached ({spent:.1f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
