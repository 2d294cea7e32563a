"""A fingerprint of the closed loop's numbers, for refactors that must change none.

    python scripts/fingerprint.py [--json PATH] [--compare PATH]     # about a minute

Runs short closed-loop runs (every loop estimator, every disturbance kind, without the
IMU, without station keeping, at other distances and noise) and hashes every series of
each trace (the true state, the estimate, the powers, the torque, the flags) and the
run's metrics, bit for bit. Equal fingerprints before and after a change mean the
change moved no number of those runs; ``--compare`` names the runs that moved and what
in them, over the series and metrics both files have (a new results key is listed, not
counted as a move; a file of an earlier release, one digest a run, is compared by
digest).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

import numpy as np

from ledsim.files.results import to_jsonable
from ledsim.loop.closed_loop import run_once
from ledsim.loop.registry import LOOP_ESTIMATORS, SCANNING_ESTIMATORS
from ledsim.loop.run_config import RunConfig

KINDS = ("vibration:frequency=3,torque=0.5,force=2", "current:speed=0.3,gust=0.05",
         "waves:height=1,period=6", "transmitter:sway=0.005,yaw=0.1",
         "occlusion:start=1,duration=0.5", "kick:start=1,rate=8",
         "kick:start=1,rate=3,hull=1", "dvl_dropout:start=0.5,duration=1")
#: The series hashed: the run's own (what the estimator was given is hashed with the
#: estimates it gives back, so a new kept series does not move a fingerprint).
CORE = ("t", "phi", "phidot", "phi_hat", "phidot_hat", "p1", "p2", "torque", "lost")
CASES = ([(f"{e}", dict(estimator=e)) for e in LOOP_ESTIMATORS
          if e not in SCANNING_ESTIMATORS]  # those scan a pan-tilt head: not the bench's
         + [(f"kkl {k}", dict(disturbances=(k,))) for k in KINDS]
         + [(f"ekf {k}", dict(estimator="ekf", disturbances=(k,))) for k in KINDS[:5]]
         + [("kkl no imu", dict(imu=False)), ("kkl still hull", dict(station_keeping=False)),
            ("kkl d=0.2", dict(distance=0.2)), ("kkl noise x3", dict(noise_scale=3.0)),
            ("kkl unsupervised", dict(supervision=False)),
            ("ekf nominal d=0.15", dict(estimator="ekf", distance=0.15,
                                        filter_distance="nominal")),
            ("oracle if2", dict(estimator="oracle", scenario="if2")),
            # Physical links: the scheduled KKL's gain tracking, the sea, the vehicle.
            # (the yaw gimbal, named: a physical link's default is the pan-tilt)
            ("kkl luma 30 m", dict(link="luma", gimbal="yaw", distance=30.0)),
            ("ekf luma 30 m waves", dict(estimator="ekf", link="luma", gimbal="yaw",
                                         distance=30.0,
                                         depth=10.0,
                                         disturbances=("waves:height=1,period=8",)))])


def _flat(value, prefix: str = "") -> dict[str, object]:
    """``{"a.b": leaf}`` of a nested JSON-able value."""
    if isinstance(value, dict):
        out: dict[str, object] = {}
        for k, v in value.items():
            out.update(_flat(v, f"{prefix}{k}."))
        return out
    return {prefix[:-1]: value}


def _sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()[:16]


def fingerprint(seconds: float = 2.0, seed: int = 1) -> dict[str, dict]:
    """Per case: ``digest`` (one sha256 of the trace series and the metrics, as earlier
    releases wrote), ``series`` (a sha256 of each series) and ``metrics`` (each metric's
    value, flattened), so that a comparison can skip keys one side does not have."""
    out = {}
    for name, kw in CASES:
        o = run_once(RunConfig(seconds=seconds, particles=300, **kw), seed, keep_trace=True)
        h = hashlib.sha256()
        series = o.trace.series()
        hashes = {}
        for key in CORE:
            data = np.ascontiguousarray(series[key]).tobytes()
            h.update(key.encode())
            h.update(data)
            hashes[key] = _sha(data)
        metrics = to_jsonable(o.metrics)
        h.update(json.dumps(metrics, sort_keys=True).encode())
        out[name] = {"digest": h.hexdigest()[:16], "series": hashes,
                     "metrics": _flat(metrics)}
    return out


def moved_keys(old, new: dict) -> list[str] | None:
    """The series and metrics of one case that differ between ``old`` and ``new``, over
    the keys both have; None when they cannot be told apart key by key (``old`` is a
    bare digest of an earlier release: then the digests are compared)."""
    if isinstance(old, str):
        return None if old == new["digest"] else ["digest"]
    moved = [k for k in old["series"] if k in new["series"]
             and old["series"][k] != new["series"][k]]
    return moved + [k for k in old["metrics"] if k in new["metrics"]
                    and old["metrics"][k] != new["metrics"][k]]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", help="write the fingerprints here")
    ap.add_argument("--compare", help="a fingerprint file to compare with")
    args = ap.parse_args()
    prints = fingerprint()
    for name, p in prints.items():
        print(f"{p['digest']}  {name}")
    if args.json:
        Path(args.json).write_text(json.dumps(prints, indent=2) + "\n")
    if args.compare:
        old = json.loads(Path(args.compare).read_text())
        moved, added = [], []
        for name, p in prints.items():
            if name not in old:
                added.append(name)
                continue
            keys = moved_keys(old[name], p)
            if keys:
                moved.append(f"{name} ({', '.join(keys)})")
            elif not isinstance(old[name], str):
                new_keys = sorted(set(p["metrics"]) - set(old[name]["metrics"]))
                if new_keys:
                    print(f"  {name}: new keys, not compared: {', '.join(new_keys)}")
        compared = len(prints) - len(added)
        print(f"{len(moved)} of {compared} runs moved" + (": " + "; ".join(moved)
                                                         if moved else ""))
        if added:
            print(f"not in {args.compare}: {', '.join(added)}")
        return 1 if moved else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
