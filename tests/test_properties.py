"""Property-based tests (hypothesis) of the CLI's numeric options and disturbance specs:
any input is either accepted inside its physical range or refused in one line."""

import contextlib
import io
import math
import os
from collections import Counter

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ledsim.cli import build_parser
from ledsim.physics.disturbances import DISTURBANCES, RANGES, DisturbanceError, parse_disturbance

NUMBERS = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10**20, 10**20),
                    st.sampled_from(["nan", "inf", "-inf", "1e308", "-0", "abc", "", "0x10"]))
PARSER = build_parser()
#: ``scripts/soak.py`` multiplies the examples; TRIED counts them per test.
SOAK = int(os.environ.get("LEDSIM_SOAK", "1"))
TRIED: Counter = Counter()
FLOAT_FLAGS = [("run", "--distance", (0.01, 500)), ("run", "--attenuation", (0, 100)),
               ("run", "--noise-scale", (0.001, 100)),
               ("run", "--torque-limit", (0, 10)), ("run", "--seconds", (0, 3600)),
               ("simulate", "--gimbal-angle", (-math.pi, math.pi)),
               ("simulate", "--torque-frequency", (0, 50)),
               ("simulate", "--led-yaw-deg", (-180, 180)), ("evaluate", "--dphi-deg", (-89, 89))]
INT_FLAGS = [("run", "--seeds", (1, 10_000)), ("run", "--particles", (1, 1_000_000)),
             ("run", "--workers", (1, 64)), ("simulate", "--seed", (0, 2**32 - 1))]


def parse(command, flag, value):
    extra = ["--scenario", "if1"] if command == "evaluate" else []
    return PARSER.parse_args([command, *extra, "--out", "x", f"{flag}={value}"])


def accepted(command, flag, value):
    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err):
            parse(command, flag, value)
        return True
    except SystemExit as exc:
        text = err.getvalue()
        assert exc.code == 2 and len(text.strip().splitlines()) == 1 and flag in text, text
        return False


@pytest.mark.parametrize("command,flag,bounds", FLOAT_FLAGS)
@settings(max_examples=60 * SOAK, deadline=None)
@given(value=NUMBERS)
def test_float_flags_accept_exactly_finite_values_in_range(command, flag, bounds, value):
    TRIED[f"{command} {flag}"] += 1
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    ok = math.isfinite(number) and bounds[0] <= number <= bounds[1]
    if accepted(command, flag, value):
        assert ok or number == bounds[0]  # a closed upper end, an open or closed lower one
    else:
        assert not ok or number == bounds[0]


@pytest.mark.parametrize("command,flag,bounds", INT_FLAGS)
@settings(max_examples=60 * SOAK, deadline=None)
@given(value=NUMBERS)
def test_integer_flags_accept_exactly_integers_in_range(command, flag, bounds, value):
    TRIED[f"{command} {flag}"] += 1
    text = str(value)
    try:
        number = int(text)
    except ValueError:
        number = None
    ok = number is not None and bounds[0] <= number <= bounds[1]
    assert accepted(command, flag, text) == ok


@settings(max_examples=300 * SOAK, deadline=None)
@given(name=st.sampled_from(sorted(DISTURBANCES)), key=st.sampled_from(sorted(RANGES)),
       value=NUMBERS)
def test_disturbance_specs_are_built_or_refused_by_name(name, key, value):
    TRIED["disturbance spec"] += 1
    spec = f"{name}:{key}={value}"
    try:
        d = parse_disturbance(spec)
    except DisturbanceError as exc:
        assert "\n" not in str(exc) and (key in str(exc) or name in str(exc))
        return
    got = getattr(d, key)
    lo, hi, _, lo_open = RANGES[key]
    assert math.isfinite(got) and (lo < got if lo_open else lo <= got) and got <= hi
