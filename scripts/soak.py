"""The long fault-injection soak: the hostile-input suites with many more cases.

    python scripts/soak.py [--scale 20] [--streams 10]     # about 10 minutes on 2 cores

Runs the property-based tests of the CLI's numeric options and disturbance specs with
``--scale`` times their examples (``tests/test_properties.py``), the measurement-stream
fuzzer with ``--streams`` noise seeds and random dropout lengths for every estimator and
hostile stream (``tests/test_fuzz_measurements.py``), and the hostile-input, interrupt
and kill tests once. Prints, and writes to ``out/soak.json``, how many hostile cases
were tried and how many were handled. Exit status: pytest's.
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
    args = ap.parse_args()
    if args.scale < 1 or args.streams < 1:
        ap.error("--scale and --streams must be >= 1")
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
    from ledsim.outputs import atomic_write_text

    atomic_write_text(ROOT / "out" / "soak.json", json.dumps(summary, indent=2) + "\n")
    print(f"hostile cases tried: {tried}, handled: {tried - failed} "
          f"({examples} CLI/spec examples, {tests} streams, inputs, interrupts and kills)")
    return int(code)


if __name__ == "__main__":
    sys.exit(main())
