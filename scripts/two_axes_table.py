"""One axis against two: the paper's yaw gimbal with its pair, and the pan-tilt head
with its quad, on the same physical link (issue 48).

    python scripts/two_axes_table.py [--seeds 2] [--seconds 10] [--workers 2]  # ~25 min
    python scripts/two_axes_table.py --quick   # the elevations alone, 1 seed: ~3 min

For ``--link`` (default luma, in its preset water) at 0.5 of its range at the FEC limit
(``ledsim budget``), the receiver 20 m deep: the `align` scenario with ``ledsim run``'s
defaults (link supervision, station keeping, the vehicle's IMU: the yaw gimbal's
line-of-sight feed-forward, the pan-tilt's gyro), for the KKL, the EKF, the particle
filter and the oracle:

- the LED 0, 10, 20, 30 and 80 deg below the receiver, its axis aimed at it (a node on
  the seabed that faces the vehicle: ``--transmitter-aimed``), and level at 0.9 of the
  range;
- head, beam and following seas (headings pi, pi/2, 0) of 0.5 and 1.5 m at 6 s, the
  receiver at 3 and 10 m (strip theory);
- the hull kicked at 3 rad/s in yaw, pitch and roll;
- the quad's opposite pointing photodiodes 5 % apart in gain (``--channel-mismatch
  0.05``, the estimators told it as calibrated; the yaw's pair matched);
- scintillation (index 0.1, the photodiodes' fading 0.99 correlated);
- a lensed receiver (``--lens-field-deg 10``) at 0.5 and 0.9 of its own FEC range (the
  yaw's shipped KKLs know only the bare detector: "-").

Per row and head: availability on the data detector (the pair's pd1, the quad's pd0),
its pointing loss [dB], the silent-error share, the losses declared after the first
acquisition (and the false ones), and the pointing RMSE over the steady window [rad]
(the pan-tilt's angle between the estimated and the true direction; the yaw's phi).
Fixed seeds 0..N-1. Writes docs/two_axes.md and out/two_axes/results.json.
"""

from __future__ import annotations

import argparse
import json
import math
import os
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
ESTIMATORS = ("kkl", "ekf", "pf", "oracle")
HEADS = ("yaw", "pan-tilt")
DEPTH = 20.0
#: The row whose quad's opposite photodiodes differ by 5 % (the yaw's pair is matched).
MISMATCH = "5 % mismatch between opposite photodiodes"
#: The rows of the lensed receiver (``--lens-field-deg 10``), at its own FEC range.
LENS = "lens, 10 deg field"
LENS_FIELD = 10.0


def cases(quick: bool) -> list[tuple[str, float, float | None, float, tuple[str, ...]]]:
    """(label, receiver depth [m], LED depth [m] (None: level), share of the FEC range,
    disturbances) of every row."""
    rows = [(f"LED {e} deg below", DEPTH, None if e == 0 else "below:" + str(e), 0.5, ())
            for e in (0, 10, 20, 30, 80)]
    if quick:
        return rows
    rows.append(("level, 0.9 of the range", DEPTH, None, 0.9, ()))
    rows.append((MISMATCH, DEPTH, None, 0.5, ()))
    # the photodiodes' own fading (0.99 correlated) puts 0.03 rad of noise on a fix
    rows.append(("scintillation, index 0.1", DEPTH, None, 0.5, ("scintillation",)))
    rows += [(f"{LENS}, {share} of its range", DEPTH, None, share, ()) for share in (0.5, 0.9)]
    for z in (3.0, 10.0):
        for h in (0.5, 1.5):
            for name, heading in (("head", math.pi), ("beam", math.pi / 2),
                                  ("following", 0.0)):
                rows.append((f"{name} seas {h} m, {z:g} m deep", z, None, 0.5,
                             (f"waves:height={h},period=6,heading={heading:.4f}",)))
    rows += [(f"{axis} kick 3 rad/s", DEPTH, None, 0.5,
              (f"kick:start=4,rate=3,hull=1,axis={axis}",)) for axis in ("yaw", "pitch",
                                                                      "roll")]
    return rows


def one(job) -> dict:
    """One (case, head, estimator) over the seeds: the summary's figures."""
    os.environ.setdefault("MUJOCO_GL", "osmesa")
    from ledsim.errors import LedsimError
    from ledsim.loop.closed_loop import run_batch
    from ledsim.loop.run_config import RunSpec

    label, head, est, spec_kw, seeds = job
    spec = RunSpec(**spec_kw, gimbal=head, estimator=est)
    try:
        spec.validate()
    except LedsimError:  # a run the head refuses (the yaw's KKL behind a lens): "-"
        return {"case": label, "head": head, "estimator": est, "distance": spec.distance,
                "transmitter_depth": spec.transmitter_depth, "availability": None,
                "pointing_loss_db": None, "silent_error_share": None, "losses": None,
                "false_losses": None, "pointing_rmse": None}
    outs = run_batch(spec, list(range(seeds)))
    m = [o.metrics for o in outs]

    def mean(values):
        values = [v for v in values if v is not None and not math.isnan(v)]
        return sum(values) / len(values) if values else None

    pointing = "pointing" if head == "pan-tilt" else "x1"
    return {"case": label, "head": head, "estimator": est,
            "distance": spec.distance, "transmitter_depth": spec.transmitter_depth,
            "availability": mean(x.availability for x in m),
            "pointing_loss_db": mean(x.pointing_loss_db for x in m),
            "silent_error_share": mean(x.silent_error_share for x in m),
            "losses": sum(x.loss_events for x in m),
            "false_losses": sum(x.false_loss_events for x in m),
            "pointing_rmse": mean(x.rmse_steady[pointing] for x in m)}


def fec_range(link: str, lens_field_deg: float | None = None) -> float:
    """The aligned link's range at the FEC limit [m] (``ledsim budget``), with the
    receiver's lens of that half-power field [deg] (None: bare)."""
    from ledsim.radiometry.budget import range_at_fec
    from ledsim.radiometry.link_presets import link_constants, preset_named

    lens = None if lens_field_deg is None else math.radians(lens_field_deg)
    return range_at_fec(link_constants(link, lens_field=lens), preset_named(link).bit_rate)


def jobs_of(args) -> list:
    fec, lensed = fec_range(args.link), fec_range(args.link, LENS_FIELD)
    jobs = []
    for label, depth, led, share, dist in cases(args.quick):
        lens = label.startswith(LENS)
        d = round(share * (lensed if lens else fec), 2)
        tx = None
        if led is not None:
            tx = round(depth + d * math.sin(math.radians(float(led.split(":")[1]))), 2)
        kw = dict(link=args.link, distance=d, depth=depth, transmitter_depth=tx,
                  transmitter_aimed=tx is not None, disturbances=dist, seconds=args.seconds)
        for head in HEADS:
            extra = {"channel_mismatch": 0.05} if label == MISMATCH and head != "yaw" \
                else {"lens_field_deg": LENS_FIELD} if lens else {}
            for est in ESTIMATORS:
                jobs.append((label, head, est, {**kw, **extra}, args.seeds))
    return jobs


def cell(x, fmt: str) -> str:
    return "-" if x is None else format(x, fmt)


def write(rows: list[dict], args, fec: float) -> Path:
    out = Path(args.out)
    lines = [f"# One axis against two: `{args.link}`, the yaw gimbal and the pan-tilt head",
             "",
             f"Generated by `python scripts/two_axes_table.py --link {args.link} --seeds "
             f"{args.seeds} --seconds {args.seconds:g}`"
             + (" --quick" if args.quick else "") + ": the `align` scenario with `ledsim "
             f"run`'s defaults, the receiver {DEPTH:g} m deep (but in the seas), at 0.5 of "
             f"the link's FEC range ({fec:.1f} m; behind the {LENS_FIELD:g} deg lens "
             f"{fec_range(args.link, LENS_FIELD):.1f} m) unless the row says. Both heads "
             "use the "
             "vehicle's IMU: the yaw gimbal its line-of-sight feed-forward, the pan-tilt "
             "head its gyro (each hinge's load cancelled and told to the estimator, the "
             "encoders in an inertial frame: `agent/pan_tilt.py`). "
             "Mean over the seeds; losses summed, false ones in brackets. Pointing RMSE: "
             "the steady window's, the pan-tilt's the angle between the estimated and "
             "the true direction, the yaw's phi.",
             "",
             "| case | estimator | yaw: availability | loss [dB] | silent | losses | "
             "pan-tilt: availability | loss [dB] | silent | losses | RMSE [rad] | "
             "vs its oracle |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    by = {(r["case"], r["head"], r["estimator"]): r for r in rows}
    for label in dict.fromkeys(r["case"] for r in rows):
        oracle = by[(label, "pan-tilt", "oracle")]["availability"]
        for est in ESTIMATORS:
            a, b = by[(label, "yaw", est)], by[(label, "pan-tilt", est)]
            ratio = None if not oracle else b["availability"] / oracle
            losses = "-" if a["losses"] is None else f"{a['losses']} ({a['false_losses']})"
            lines.append(
                f"| {label} | {est} | {cell(a['availability'], '.3f')} | "
                f"{cell(a['pointing_loss_db'], '.3f')} | "
                f"{cell(a['silent_error_share'], '.3f')} | "
                f"{losses} | {cell(b['availability'], '.3f')} | "
                f"{cell(b['pointing_loss_db'], '.3f')} | "
                f"{cell(b['silent_error_share'], '.3f')} | "
                f"{b['losses']} ({b['false_losses']}) | {cell(b['pointing_rmse'], '.2e')} | "
                f"{cell(ratio, '.3f')} |")
    out.write_text("\n".join(lines) + "\n")
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--link", default="luma")
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", default=str(ROOT / "docs" / "two_axes.md"))
    args = ap.parse_args()
    if args.quick:
        args.seeds = 1

    jobs = jobs_of(args)
    with ProcessPoolExecutor(args.workers) as pool:
        rows = []
        for k, row in enumerate(pool.map(one, jobs), 1):
            rows.append(row)
            print(f"{k}/{len(jobs)} {row['case']} {row['head']} {row['estimator']}: "
                  f"{cell(row['availability'], '.3f')}", flush=True)
    results = ROOT / "out" / "two_axes"
    results.mkdir(parents=True, exist_ok=True)
    (results / "results.json").write_text(json.dumps(rows, indent=1))
    print(write(rows, args, fec_range(args.link)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
