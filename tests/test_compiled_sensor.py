"""The ray sensor's compiled reading (ledsim/physics/compiled_sensor.py) has the
reference's bits: the paper's bench, a yaw gimbal and a pan-tilt head on a physical
link (an elevation cone), shadowed rays, daylight and a moving transmitter."""

from __future__ import annotations

import copy
import dataclasses
import math

import numpy as np
import pytest

from ledsim.loop.closed_loop import ClosedLoop
from ledsim.loop.run_config import RunConfig
from ledsim.physics.tick import prepare
from observer import jit

pytestmark = pytest.mark.skipif(not jit.installed(), reason="numba is not installed")


@pytest.mark.parametrize("kw", [
    dict(),
    dict(disturbances=("occlusion:start=0.1,duration=0.5",)),
    dict(link="luma", gimbal="yaw", distance=11, disturbances=("flicker",)),
    dict(link="luma", water="coastal", distance=7,
         disturbances=("flicker", "transmitter:sway=0.005,yaw=0.1")),
], ids=["paper", "occlusion", "yaw-luma", "head-luma"])
def test_the_compiled_reading_is_the_references_to_the_bit(kw):
    loop = ClosedLoop(RunConfig(scenario="align", seconds=1, **kw), range(1))
    run = loop.runs[0]
    sensor, seen = run.sensor, set()
    for k in range(80):
        state = copy.deepcopy(sensor.rng.bit_generator.state)
        readings = []
        for compiled in (False, True):
            sensor.rng.bit_generator.state = copy.deepcopy(state)
            with jit.use(compiled):
                readings.append(sensor.read())
        ref, got = readings
        for f in dataclasses.fields(ref):
            a, b = np.asarray(getattr(ref, f.name)), np.asarray(getattr(got, f.name))
            assert a.tobytes() == b.tobytes(), (k, f.name, a, b)
        seen.add(float(np.min(ref.visible_fraction)))
        run.world.set_torque(0.002 * math.sin(0.05 * k))
        run.world.step()
        prepare(run.world, run.disturbances, (k + 1) * loop.Te)
    if "occlusion" in str(kw):
        assert min(seen) < 1.0  # some rays were stopped


def test_a_perturbed_kernel_constant_changes_the_reading():
    """The comparison above can fail: the receiver's c1 off by one part in 1e12 in the
    kernel's constants moves the powers."""
    run = ClosedLoop(RunConfig(scenario="align", seconds=1), range(1)).runs[0]
    with jit.use(True):
        clean = run.sensor.read(noise=False).power_clean
        run.sensor._reader.optics[5] *= 1 + 1e-12
        moved = run.sensor.read(noise=False).power_clean
    assert clean.tobytes() != moved.tobytes()
