"""False losses: does the supervisor declare the link lost while the data still explain
the estimate? Long runs of the cases that used to, counted per 10 minutes.

    python scripts/false_losses.py [--minutes 3] [--seeds 1] [--workers 2]   # ~25 min
    python scripts/false_losses.py --quick       # 1 minute each, to try a change

Each case runs ``ledsim run``'s defaults (link supervision, station keeping, the IMU)
for ``--minutes`` (the waves and the scintillation for 10 at least), fixed seeds 0..N-1:

- waves of 1.5 m and 8 s from 1.2 rad, the receiver 4 m deep (luma at 30 m);
- moderate scintillation (index 0.1), 10 m deep, at 0.5 of luma's FEC range;
- a 0.15 m/s current across the link in harbour water at 0.9 of the FEC range;
- the LED opening from 2 m at 0.5 m/s to 0.9 of the FEC range in clear ocean;
- an 8 rad/s kick of the gimbal, which must still be a loss (its detection time is
  kept), and a 0.5 s occlusion, which must still be held (the time to the gate's first
  withheld sample is kept).

Per row (sums over the seeds): the losses declared after the first acquisition
(``loss_events``), the false ones (``false_loss_events``: declared while the geometry
allowed the link, no occluder shaded it, and the estimator's own phi was within 0.1 rad
of the truth), both per 10 minutes, the re-seeds, and the whole run's phi RMSE of the
reported estimate (the held one while lost), lost share, silent-error share and
availability (means over the seeds). Writes docs/false_losses.md and
out/false_losses/results.json.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "osmesa")
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from ledsim.experiment.montecarlo import pin_blas_threads  # noqa: E402

pin_blas_threads()

import numpy as np  # noqa: E402

from ledsim.experiment.montecarlo import run_jobs  # noqa: E402
from ledsim.files.outputs import atomic_write_text  # noqa: E402
from ledsim.loop.losses import FALSE_LOSS_ERROR  # noqa: E402
from ledsim.radiometry.budget import range_at_fec  # noqa: E402
from ledsim.radiometry.link_presets import link_constants, preset_named  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent


def fec_range(link: str, water: str) -> float:
    """The range [m] of ``link`` in ``water`` at the FEC limit, aligned."""
    return range_at_fec(link_constants(link, water=water), preset_named(link).bit_rate)


def cases(minutes: float) -> list[dict]:
    """Every case: a label, the run's settings, its estimators and its length [s]."""
    luma = fec_range("luma", "clear-ocean")
    harbour = fec_range("luma", "harbour")
    opening_until = (0.9 * luma - 2.0) / 0.5
    long = max(minutes, 10.0) if minutes >= 3 else minutes
    every_minute = int(60 * minutes)
    return [
        {"label": "waves 1.5 m, 8 s, from 1.2 rad, 4 m deep", "depth": 4.0,
         "disturbances": ("waves:height=1.5,period=8,heading=1.2",),
         "estimators": ("kkl", "ekf", "pf"), "seconds": 60 * long},
        {"label": "scintillation index 0.1, 10 m deep, 0.5 of the range",
         "distance": 0.5 * luma, "disturbances": ("scintillation",),
         "estimators": ("kkl", "ekf", "pf"), "seconds": 60 * long},
        {"label": f"current 0.15 m/s across, harbour, {0.9 * harbour:.1f} m",
         "water": "harbour", "distance": 0.9 * harbour,
         "disturbances": ("current:speed=0.15,heading=1.5708",),
         "estimators": ("kkl", "ekf")},
        {"label": f"LED opening from 2 m at 0.5 m/s to {0.9 * luma:.0f} m",
         "distance": 2.0,
         "disturbances": (f"transmitter:drift=0.5,sway=0,drift_until={opening_until:.2f}",),
         "estimators": ("kkl", "ekf")},
        {"label": "gimbal kick 8 rad/s at 30 s", "link": "paper",
         "disturbances": ("kick:start=30,rate=8",), "estimators": ("kkl", "ekf"),
         "seconds": 60.0, "true_losses": True},
        {"label": "occlusion 0.5 s at 30 s", "link": "paper",
         "disturbances": ("occlusion:start=30,duration=0.5",),
         "estimators": ("kkl", "ekf"), "seconds": 60.0, "true_losses": True},
    ] if every_minute else []


def one(job) -> dict:
    """One (case, estimator) over the seeds: the counts and the means."""
    from ledsim.loop.report import run_seeds
    from ledsim.loop.run_config import RunConfig

    case, est, seeds, seconds = job
    # the yaw gimbal's table (a physical link's default head is the pan-tilt)
    settings = {"link": "luma", "gimbal": "yaw",
                **{k: case[k] for k in ("depth", "distance", "water", "link") if k in case}}
    cfg = RunConfig(estimator=est, seeds=seeds, workers=1, seconds=seconds,
                    disturbances=case["disturbances"], **settings)
    _, outs = run_seeds(cfg, progress=False)
    m = [o.metrics for o in outs]
    return {"case": case["label"], "estimator": est, "seeds": seeds, "seconds": seconds,
            "loss_events": sum(x.loss_events for x in m),
            "false_loss_events": sum(x.false_loss_events for x in m),
            "reseeds": sum(x.reseeds for x in m),
            "detection_delay": [x.detection_delay for x in m],
            "held_delay": [x.held_delay for x in m],
            "rmse_x1": float(np.mean([x.rmse["x1"] for x in m])),
            "lost_share": float(np.mean([x.lost_share for x in m])),
            "silent_error_share": float(np.mean([x.silent_error_share for x in m])),
            "availability": float(np.mean([x.availability for x in m])),
            "true_losses": bool(case.get("true_losses", False))}


def per_ten_minutes(count: int, row: dict) -> float:
    return 600.0 * count / (row["seconds"] * row["seeds"])


def table(rows: list[dict], command: str) -> str:
    lines = [
        "# False losses: long runs of the cases that used to declare them",
        "",
        f"Generated by `{command}`: `ledsim run --gimbal yaw`'s defaults (link supervision, "
        "station keeping, the IMU), luma at 30 m unless the case says otherwise; sums over the "
        "seeds. A loss is false when it is declared while the geometry allowed the link, "
        "no occluder shaded a photodiode, and the estimator's own phi was within "
        f"{FALSE_LOSS_ERROR:g} rad of the truth (`false_loss_events` in `results.json`). "
        "Losses count those declared after the first acquisition. The phi RMSE is the "
        "whole run's, of the estimate the run reports (while lost: the last trusted "
        "estimate carried on the encoder). The kick and the occlusion (the bench) must "
        "still be detected: the kick as a loss (detection [s]: from the event to the "
        "flag); the occlusion, shorter than the dropout gate's 1 s hold, is no loss but "
        "is held on the encoder (held [s]: from the event to the first sample the gate "
        "withheld or the first flag, `held_delay` in `results.json`).",
        "",
        "| case | estimator | minutes | losses | false losses | false per 10 min | "
        "re-seeds | detection [s] | held [s] | phi RMSE [rad] | lost share | "
        "silent errors | availability |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        delays = [d for d in r["detection_delay"] if d is not None]
        det = f"{np.mean(delays):.2f}" if r["true_losses"] and delays else "-"
        helds = [d for d in r.get("held_delay", []) if d is not None]
        held = f"{np.mean(helds):.2f}" if r["true_losses"] and helds else "-"
        lines.append(
            f"| {r['case']} | {r['estimator']} | {r['seconds'] * r['seeds'] / 60:.0f} | "
            f"{r['loss_events']} | {r['false_loss_events']} | "
            f"{per_ten_minutes(r['false_loss_events'], r):.1f} | {r['reseeds']} | {det} | {held} | "
            f"{r['rmse_x1']:.2e} | {r['lost_share']:.4f} | "
            f"{r['silent_error_share']:.4f} | {r['availability']:.3f} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--minutes", type=float, default=3.0, help="length of a run [min]")
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--quick", action="store_true", help="1 minute a run, no files")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "false_losses.md")
    args = ap.parse_args()
    minutes = 1.0 if args.quick else args.minutes
    jobs = [(case, est, args.seeds, case.get("seconds", 60.0 * minutes))
            for case in cases(minutes) for est in case["estimators"]]
    rows = run_jobs(one, jobs, args.workers, "false losses",
                    sizes=[j[3] * j[2] for j in jobs])
    command = "python scripts/false_losses.py" + (
        "" if (args.minutes, args.seeds) == (3.0, 1) else
        f" --minutes {args.minutes:g} --seeds {args.seeds}")
    text = table(rows, command)
    print(text)
    if not args.quick:
        atomic_write_text(args.out, text)
        out = ROOT / "out" / "false_losses"
        out.mkdir(parents=True, exist_ok=True)
        atomic_write_text(out / "results.json", json.dumps(rows, indent=2))


if __name__ == "__main__":
    main()
