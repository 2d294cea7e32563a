"""Acquisition at the torque limit (``--acquisition minimum-time``, the default) against
the warm-up start (``warm-up``): starts inside and outside the field of view, kicks,
hull strikes and occlusions, with and without the IMU, and which part delivers each
figure (the pair's inversion, the encoder's slew, the estimator).

    python scripts/acquisition.py [--seeds 10]      # about 10 minutes on 2 cores

Writes docs/acquisition.md. Seeds 0..N-1 of 10 s ``align`` runs (events at 3 s).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from ledsim.agent.laws import intensity_maximum
from ledsim.files.outputs import atomic_write_text
from ledsim.loop.closed_loop import ClosedLoop
from ledsim.loop.run_config import RunConfig
from ledsim.loop.run_metrics import first_settled
from ledsim.physics.world import LinkWorld

ROOT = Path(__file__).resolve().parent.parent
STARTS = (0.3, -0.45, 1.0)
ESTIMATORS = ("kkl", "ekf", "oracle")
ACQUISITIONS = ("warm-up", "minimum-time")
EVENTS = ("kick:start=3,rate=12", "kick:start=3,rate=3,hull=1",
          "occlusion:start=3,duration=0.5", "occlusion:start=3,duration=2")


def batch(cfg: RunConfig, seeds: int, keep_trace: bool = False):
    """The outcomes of seeds 0..seeds-1 and each run's acquisition log (None: none)."""
    loop = ClosedLoop(cfg, list(range(seeds)), threads=2)
    outs = loop.run(keep_trace)
    logs = [getattr(getattr(r.step.supervisor, "fast", None), "log", None)
            for r in loop.runs]
    return outs, logs


def spread(values, fmt="{:.2f}") -> str:
    """'mean [min, max]' of the values that are not None, and how many are missing."""
    ok = [v for v in values if v is not None]
    if not ok:
        return "never"
    text = f"{fmt.format(np.mean(ok))} [{fmt.format(min(ok))}, {fmt.format(max(ok))}]"
    return text + (f" ({len(values) - len(ok)} never)" if len(ok) < len(values) else "")


def starts_table(seeds: int, bar) -> list[str]:
    rows = ["| estimator | start [rad] | acquisition | alignment time [s] | availability "
            "| silent errors (largest) |", "|---|---|---|---|---|---|"]
    for est in ESTIMATORS:
        for a in STARTS:
            for acq in ACQUISITIONS:
                outs, _ = batch(RunConfig(estimator=est, initial_angle=a, acquisition=acq),
                                seeds)
                m = [o.metrics for o in outs]
                rows.append(f"| {est} | {a:g} | {acq} "
                            f"| {spread([x.alignment_time for x in m])} "
                            f"| {np.mean([x.availability for x in m]):.3f} "
                            f"| {max(x.silent_error_share for x in m):.3f} |")
                bar.update()
    return rows


def events_table(seeds: int, bar) -> list[str]:
    rows = ["| event at 3 s | IMU | estimator | acquisition | back within [s] "
            "| availability |", "|---|---|---|---|---|---|"]
    for ev in EVENTS:
        for imu in (True, False):
            for est in ("kkl", "oracle"):
                for acq in ACQUISITIONS:
                    outs, _ = batch(RunConfig(estimator=est, acquisition=acq, imu=imu,
                                              disturbances=(ev,)), seeds)
                    m = [o.metrics for o in outs]
                    rows.append(f"| {ev} | {'on' if imu else 'off'} | {est} | {acq} "
                                f"| {spread([x.recovery_time for x in m])} "
                                f"| {np.mean([x.availability for x in m]):.3f} |")
                    bar.update()
    return rows


def credit_table(seeds: int, bar) -> list[str]:
    """Stages of the KKL's minimum-time start, and the bang-bang bound of its slew."""
    world = RunConfig().world_config()
    accel = world.torque_limit / LinkWorld(world).hinge_inertia()  # [rad/s^2]
    phi_ref = intensity_maximum(world.constants)
    Te = world.constants.Te
    rows = ["| start [rad] | first usable sample [ms] | fix good enough to go [ms] "
            "| at the target [ms] | slew (go to target) [ms] | bang-bang bound [ms] "
            "| handed over to the KKL [ms] | aligned (1 deg for 0.5 s) [ms] |",
            "|---|---|---|---|---|---|---|---|"]
    for a in STARTS:
        outs, logs = batch(RunConfig(initial_angle=a, acquisition="minimum-time"), seeds)
        first = [log[0] for log in logs]

        def ms(v):
            return None if v is None else 1e3 * v * Te

        slew = [None if f.go is None or f.reached is None else f.reached - f.go
                for f in first]
        bound = 1e3 * 2 * math.sqrt(abs(a - phi_ref) / accel)
        rows.append(f"| {a:g} | {spread([ms(f.first_seen) for f in first], '{:.0f}')} "
                    f"| {spread([ms(f.go) for f in first], '{:.0f}')} "
                    f"| {spread([ms(f.reached) for f in first], '{:.0f}')} "
                    f"| {spread([ms(s) for s in slew], '{:.0f}')} | {bound:.0f} "
                    f"| {spread([ms(f.arrived) for f in first], '{:.0f}')} "
                    f"| {spread([None if o.metrics.alignment_time is None else 1e3 * o.metrics.alignment_time for o in outs], '{:.0f}')} |")  # noqa: E501
        bar.update()
    return rows


def convergence_table(seeds: int, bar) -> list[str]:
    """How long each estimator alone takes to forget its initial guess: the gimbal held
    still 0.3 rad off (``open-loop``: no input), no supervision, no re-seed."""
    rows = ["| estimator | within 0.1 rad [s] | within 1 deg for 0.5 s [s] |",
            "|---|---|---|"]
    for est in ("kkl", "ekf", "ukf"):
        outs, _ = batch(RunConfig(estimator=est, scenario="open-loop", supervision=False,
                                  seconds=5.0), seeds, keep_trace=True)
        coarse, fine = [], []
        for o in outs:
            s = o.trace.series()
            err = np.abs(s["phi_hat"] - s["phi"])
            coarse.append(first_settled(err < 0.1, Te=0.01, hold=0.5))
            fine.append(first_settled(err < math.radians(1.0), Te=0.01, hold=0.5))
        rows.append(f"| {est} | {spread(coarse)} | {spread(fine)} |")
        bar.update()
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--out", default=str(ROOT / "docs" / "acquisition.md"))
    args = ap.parse_args()
    n = args.seeds
    total = (len(ESTIMATORS) * len(STARTS) * 2 + len(EVENTS) * 8 + len(STARTS) + 3)
    with tqdm(total=total, desc="acquisition", unit="row") as bar:
        starts = starts_table(n, bar)
        events = events_table(n, bar)
        credit = credit_table(n, bar)
        conv = convergence_table(n, bar)
    text = "\n".join([
        "# Acquisition at the torque limit", "",
        f"Generated by `python scripts/acquisition.py --seeds {n}`: seeds 0-{n - 1} of "
        "10 s `align` runs, the vehicle keeping station, every figure a mean [min, max] "
        "over the seeds. `--acquisition warm-up` holds the gimbal for 1 s "
        "while the estimator forgets its initial guess, then slews under the cascade PI "
        "at its 0.3 rad/s limit; `--acquisition minimum-time` (the default) fixes the beam "
        "from the "
        "pair of powers carried on the encoder, slews there at the torque limit and "
        "hands over on arrival (`ledsim/agent/slew.py`). Alignment time: first time "
        "|phi - phi_ref| < 1 deg for 0.5 s. Silent errors: share of the run with the "
        "estimate more than 0.2 rad off and the link not flagged.", "",
        "## Starts", "", *starts, "",
        "## Kicks, hull strikes and occlusions", "",
        "Back within: from the end of the event to the first time the receiver is "
        "aligned for 0.5 s (`recovery_time`).", "", *events, "",
        "## Which part delivers each figure", "",
        "The KKL's minimum-time starts, stage by stage (ms from the start): the pair's "
        "inversion gives the first usable sample and the fix (`BeamFix`, its standard "
        "error under 0.1 rad to go, refined on the way), the encoder carries the slew "
        "(`TimeOptimalSlew`), "
        "and the estimator is restarted on arrival from the fix (standard error under "
        "0.006 rad; in weaker light under 0.018 rad after 0.3 s at the target, or, "
        "after 1 s there, the estimator's own estimate once the fix agrees with it). "
        "The bound is bang-bang at the torque limit over |phi0 - phi_ref|, "
        "the water's drag ignored.", "", *credit, "",
        "How long each estimator alone takes to forget its initial guess, with the "
        "gimbal held 0.3 rad off (`open-loop` scenario, no supervision, no re-seed): "
        "what the warm-up waits for, and what the minimum-time start no longer waits "
        "for.", "", *conv, ""])
    atomic_write_text(Path(args.out), text)
    print(text)


if __name__ == "__main__":
    main()
