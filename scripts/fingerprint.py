"""A fingerprint of the closed loop's numbers, for refactors that must change none.

    python scripts/fingerprint.py [--json PATH] [--compare PATH]     # about a minute

Runs short closed-loop runs (every loop estimator, every disturbance kind, without the
IMU, without station keeping, at other distances and noise) and hashes every series of
each trace (the true state, the estimate, the powers, the torque, the flags) and the
run's metrics, bit for bit. Equal fingerprints before and after a change mean the
change moved no number of those runs; ``--compare`` names the runs that moved.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

import numpy as np

from ledsim.loop.closed_loop import run_once
from ledsim.loop.config import LOOP_ESTIMATORS, RunConfig
from ledsim.results import to_jsonable

KINDS = ("vibration:frequency=3,torque=0.5,force=2", "current:speed=0.3,gust=0.05",
         "waves:height=1,period=6", "transmitter:sway=0.005,yaw=0.1",
         "occlusion:start=1,duration=0.5", "kick:start=1,rate=8",
         "kick:start=1,rate=3,hull=1", "dvl_dropout:start=0.5,duration=1")
#: The series hashed: the run's own (what the estimator was given is hashed with the
#: estimates it gives back, so a new kept series does not move a fingerprint).
CORE = ("t", "phi", "phidot", "phi_hat", "phidot_hat", "p1", "p2", "torque", "lost")
CASES = ([(f"{e}", dict(estimator=e)) for e in LOOP_ESTIMATORS]
         + [(f"kkl {k}", dict(disturbances=(k,))) for k in KINDS]
         + [(f"ekf {k}", dict(estimator="ekf", disturbances=(k,))) for k in KINDS[:5]]
         + [("kkl no imu", dict(imu=False)), ("kkl still hull", dict(station_keeping=False)),
            ("kkl d=0.2", dict(distance=0.2)), ("kkl noise x3", dict(noise_scale=3.0)),
            ("kkl unsupervised", dict(supervision=False)),
            ("ekf nominal d=0.15", dict(estimator="ekf", distance=0.15,
                                        filter_distance="nominal")),
            ("oracle if2", dict(estimator="oracle", scenario="if2"))])


def fingerprint(seconds: float = 2.0, seed: int = 1) -> dict[str, str]:
    """``{case: sha256}`` of each case's trace series and metrics."""
    out = {}
    for name, kw in CASES:
        o = run_once(RunConfig(seconds=seconds, particles=300, **kw), seed, keep_trace=True)
        h = hashlib.sha256()
        series = o.trace.series()
        for key in CORE:
            h.update(key.encode())
            h.update(np.ascontiguousarray(series[key]).tobytes())
        h.update(json.dumps(to_jsonable(o.metrics), sort_keys=True).encode())
        out[name] = h.hexdigest()[:16]
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", help="write the fingerprints here")
    ap.add_argument("--compare", help="a fingerprint file to compare with")
    args = ap.parse_args()
    prints = fingerprint()
    for name, h in prints.items():
        print(f"{h}  {name}")
    if args.json:
        Path(args.json).write_text(json.dumps(prints, indent=2) + "\n")
    if args.compare:
        old = json.loads(Path(args.compare).read_text())
        moved = [n for n in prints if old.get(n) != prints[n]]
        print(f"{len(moved)} of {len(prints)} runs moved" + (": " + ", ".join(moved)
                                                           if moved else ""))
        return 1 if moved else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
