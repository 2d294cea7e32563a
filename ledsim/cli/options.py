"""Numeric command-line options: finite, in a physical range, refused in one line."""

from __future__ import annotations

import argparse
import math

from ledsim.constants import MIN_BIT_RATE, MIN_DISTANCE, MIN_NOISE_SCALE


def number(lo: float, hi: float, unit: str = "", *, integer: bool = False,
           lo_open: bool = False):
    """An argparse type: a finite number in [lo, hi] (``lo_open``: (lo, hi]), so that
    a non-finite, absurd or unphysical value is refused before any work, in one line."""
    fmt = "{}" if integer else "{:g}"
    allowed = f"{'(' if lo_open else '['}{fmt.format(lo)}, {fmt.format(hi)}] {unit}".rstrip()

    def parse(text: str):
        try:
            value = int(text) if integer else float(text)
        except ValueError:
            kind = "an integer" if integer else "a number"
            raise argparse.ArgumentTypeError(f"{text!r} is not {kind}") from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"{text!r} is not allowed: must be finite")
        if not ((lo < value) if lo_open else (lo <= value)) or value > hi:
            raise argparse.ArgumentTypeError(f"{text} is not allowed: must be in {allowed}")
        return value

    return parse


DISTANCE = number(MIN_DISTANCE, 500.0, "m")
ATTENUATION = number(0.0, 100.0, "1/m")
BIT_RATE = number(MIN_BIT_RATE, 1e10, "bit/s")
DEPTH = number(1.0, 500.0, "m")
TRANSMITTER_DEPTH = number(0.2, 500.0, "m")
SEA_DEPTH = number(1.5, 11000.0, "m")  # the run checks it against both ends
SECONDS = number(0.0, 3600.0, "s", lo_open=True)
SEED = number(0, 2**32 - 1, integer=True)
SEEDS = number(1, 10_000, integer=True)
PARTICLES = number(1, 1_000_000, integer=True)
WORKERS = number(1, 64, integer=True)
DPHI_DEG = number(-89.0, 89.0, "deg")
TORQUE_LIMIT = number(0.0, 10.0, "N m", lo_open=True)
NOISE_SCALE = number(MIN_NOISE_SCALE, 100.0)
