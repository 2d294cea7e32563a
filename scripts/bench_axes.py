"""One axis against two: the cost of a control step with the EKF, measured in one run.

The same loop on each world (luma at 30 m, one thread): the sensor's reading, the
control step (``Unsupervised`` EKF, ``AlignmentPID``, ``GimbalMotor``) and the tick of
``WorldRows``; the one-axis step on the paper's pair with the run's identified model,
the two-axis step on the quad of a pan-tilt head with ``HeadModel``. Both start aligned
and hold (the tracking regime a run spends its time in). Rounds alternate the two, and
the table gives each one's median and their ratio (the issue's target: at most 1.5).

    python scripts/bench_axes.py [--steps 2000] [--rounds 5] [--out docs/bench_axes.md]
                                 [--json PATH]
"""

from __future__ import annotations

import os

for _name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")  # one core, before numpy is imported
os.environ.setdefault("MUJOCO_GL", "osmesa")

import argparse  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from dataclasses import replace  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from ledsim.agent.laws import AlignmentPID  # noqa: E402
from ledsim.agent.step import ControlStep, GimbalMotor, Unsupervised, identity_gate  # noqa: E402
from ledsim.loop.build.estimation import identified_model  # noqa: E402
from ledsim.physics.gimbal_system import GimbalSystem  # noqa: E402
from ledsim.physics.head_model import HeadModel  # noqa: E402
from ledsim.physics.layout import quad_layout  # noqa: E402
from ledsim.physics.scene import WorldConfig  # noqa: E402
from ledsim.physics.sensor import IrradianceSensor  # noqa: E402
from ledsim.physics.world import LinkWorld  # noqa: E402
from ledsim.physics.world_rows import WorldRows  # noqa: E402
from ledsim.radiometry.link_presets import link_constants  # noqa: E402
from observer.baselines.ekf import ExtendedKalmanFilter  # noqa: E402


def one_axis():
    """(world, sensor, step, reads angles) of the one-axis EKF loop."""
    system = GimbalSystem(WorldConfig(constants=link_constants("luma", 30.0)))
    model = identified_model(system)
    world = LinkWorld(system.config)
    world.reset()
    step = ControlStep(identity_gate, Unsupervised(ExtendedKalmanFilter(model)),
                       AlignmentPID(), system.constants,
                       GimbalMotor(system.inertia, limit=world.config.torque_limit))
    return world, IrradianceSensor(world, seed=0), step, lambda: (world.gimbal_angle,
                                                                  world.gimbal_rate)


def two_axes():
    """The same of the two-axis EKF loop on a quad."""
    c = replace(link_constants("luma", 30.0), receiver_layout=quad_layout(0.1))
    world = LinkWorld(WorldConfig(constants=c))
    model = HeadModel.fit(world)
    world.reset(gimbal_angle=np.zeros(2), gimbal_rate=np.zeros(2))
    step = ControlStep(identity_gate, Unsupervised(ExtendedKalmanFilter(model)),
                       AlignmentPID(phi_ref=0.0), c,
                       GimbalMotor(model.inertia, limit=world.config.torque_limit))
    return world, IrradianceSensor(world, seed=0), step, lambda: (world.gimbal_angles,
                                                                  world.gimbal_rates)


def measure(build, steps: int) -> tuple[float, float]:
    """(microseconds per step of the whole loop, of the control step alone)."""
    world, sensor, step, encoders = build()
    Te = world.config.constants.Te
    spent = 0.0
    with WorldRows([world]) as rows:
        rows.start([sensor], [[]], [None])
        t0 = time.perf_counter()
        for k in range(steps):
            reading = sensor.read()
            q, qdot = encoders()
            s0 = time.perf_counter()
            torque = step(reading.power, k * Te, q, qdot)
            spent += time.perf_counter() - s0
            rows.tick((k + 1) * Te, torques=[torque])
        wall = time.perf_counter() - t0
    return wall / steps * 1e6, spent / steps * 1e6


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--json", metavar="PATH")
    ap.add_argument("--out", metavar="PATH", help="also write the table as markdown")
    args = ap.parse_args()
    runs = {"one axis": [], "two axes": []}
    for _ in range(args.rounds):
        runs["one axis"].append(measure(one_axis, args.steps))
        runs["two axes"].append(measure(two_axes, args.steps))
    med = {k: (statistics.median(w for w, _ in v), statistics.median(s for _, s in v))
           for k, v in runs.items()}
    ratio = (med["two axes"][0] / med["one axis"][0], med["two axes"][1] / med["one axis"][1])
    lines = ["| loop (EKF, luma 30 m, one thread) | whole step [us] | control step [us] |",
             "|---|---|---|"]
    lines += [f"| {k} | {whole:.0f} | {ctl:.0f} |" for k, (whole, ctl) in med.items()]
    lines.append(f"| two axes / one axis | {ratio[0]:.2f} | {ratio[1]:.2f} |")
    print("\n".join(lines))
    if args.out:
        from ledsim.files.outputs import atomic_write_text

        atomic_write_text(Path(args.out), "\n".join([
            "# One axis against two: the cost of a step", "",
            f"`python scripts/bench_axes.py --rounds {args.rounds} --steps {args.steps}`: "
            "the EKF's loop on one axis (the paper's pair) and on two (a quad on a "
            "pan-tilt head), alternately in one process on one thread; medians over the "
            "rounds. The whole step is the sensor's reading, the control step and the "
            "tick; the two-axis sensor reads five photodiodes against two.", "",
            *lines, ""]))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"median_us": med, "ratio": ratio, "rounds": args.rounds,
                       "steps": args.steps}, fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
