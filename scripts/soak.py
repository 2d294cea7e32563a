"""The long fault-injection soak: the hostile-input suites with many more cases.

    python scripts/soak.py [--scale 20] [--streams 10] [--long 600]   # about 12 minutes

Runs the property-based tests of the CLI's numeric options and disturbance specs with
``--scale`` times their examples (``tests/test_properties.py``), the measurement-stream
fuzzer with ``--streams`` noise seeds and random dropout lengths for every estimator and
hostile stream (``tests/test_fuzz_measurements.py``), and the hostile-input, interrupt
and kill tests once. Then the long still-water case: the oracle for ``--long`` seconds
(10 minutes), which must keep availability and FEC share at 0.95 or more in every
minute from the second and the hull within 3 cm rms of its station. Prints, and writes
to ``out/soak.json``, how many hostile cases were tried and how many were handled, and
the long run's figures. Exit status: pytest's, or 1 when the long run misses.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SUITES = ["tests/test_properties.py", "tests/test_fuzz_measurements.py",
          "tests/test_hostile_input.py", "tests/test_interrupts.py",
          "tests/test_cli.py::test_workers_die_with_their_parent"]


class Tally:
    """pytest plugin: one case per test, or per example for the property tests."""

    def __init__(self):
        self.outcomes: Counter = Counter()  # (suite, outcome) -> tests

    def pytest_runtest_logreport(self, report):
        if report.when == "call" or (report.when == "setup" and report.outcome != "passed"):
            self.outcomes[(report.nodeid.split("::")[0], report.outcome)] += 1


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scale", type=int, default=20, help="examples x this (hypothesis)")
    ap.add_argument("--streams", type=int, default=10, help="noise seeds per stream kind")
    ap.add_argument("--long", type=float, default=600.0,
                    help="seconds of the long still-water run (0: none)")
    args = ap.parse_args()
    if args.scale < 1 or args.streams < 1:
        ap.error("--scale and --streams must be >= 1")
    if args.long and args.long < 120:
        ap.error("--long must be 0 or at least 120 s (two minutes)")
    os.environ["LEDSIM_SOAK"] = str(args.scale)
    os.environ["LEDSIM_SOAK_STREAMS"] = str(args.streams)
    os.environ.setdefault("MUJOCO_GL", "osmesa")
    import pytest

    sys.path.insert(0, str(ROOT / "tests"))
    tally = Tally()
    code = pytest.main(["-q", "-p", "no:cacheprovider", *[str(ROOT / s) for s in SUITES]],
                       plugins=[tally])
    import test_properties  # the module pytest ran: its example counter

    examples = sum(test_properties.TRIED.values())
    failed = sum(n for (suite, o), n in tally.outcomes.items() if o == "failed")
    tests = sum(n for (suite, o), n in tally.outcomes.items()
                if "test_properties" not in suite and o in ("passed", "failed"))
    prop_failed = sum(n for (suite, o), n in tally.outcomes.items()
                      if "test_properties" in suite and o == "failed")
    tried = examples + tests
    summary = {"hostile_cases": tried, "handled": tried - failed,
               "property_examples": examples, "property_tests_failed": prop_failed,
               "other_cases": tests, "scale": args.scale, "streams": args.streams}
    long_ok = True
    if args.long:
        summary["still_water"] = still_water(args.long)
        long_ok = summary["still_water"]["met"]
    from ledsim.files.outputs import atomic_write_text

    atomic_write_text(ROOT / "out" / "soak.json", json.dumps(summary, indent=2) + "\n")
    print(f"hostile cases tried: {tried}, handled: {tried - failed} "
          f"({examples} CLI/spec examples, {tests} streams, inputs, interrupts and kills)")
    if args.long:
        s = summary["still_water"]
        print(f"still water, {args.long:g} s, oracle: worst minute from the second: "
              f"availability {s['worst_availability']:.3f}, FEC share "
              f"{s['worst_fec_share']:.3f}; hull {100 * s['hull_error_rms']:.2f} cm rms: "
              f"{'met' if long_ok else 'NOT met'}")
    return int(code) or (0 if long_ok else 1)


def still_water(seconds: float) -> dict:
    """The long still-water case: the oracle, seed 0, a window a minute."""
    from ledsim.loop.closed_loop import run_once
    from ledsim.loop.run_config import RunConfig

    out = run_once(RunConfig(estimator="oracle", seconds=seconds), 0, window=60.0)
    later = out.windows[1:]
    worst_av = min(w.availability for w in later)
    worst_fec = min(w.fec_share for w in later)
    hull = out.metrics.hull_error_rms
    return {"seconds": seconds, "worst_availability": worst_av, "worst_fec_share": worst_fec,
            "hull_error_rms": hull, "navigation_error_rms": out.metrics.navigation_error_rms,
            "met": worst_av >= 0.95 and worst_fec >= 0.95 and hull <= 0.03}


if __name__ == "__main__":
    sys.exit(main())
