"""The vehicle's compiled kernels (the INS's propagation and depth update, the hull's load
observer, the station keeping's PD) against their numpy references: kernel by kernel on
random inputs, and the whole vehicle stepped on both paths through currents, DVL
dropouts, late and outlier fixes and kicks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ledsim.agent.autopilot import inertial_noise
from ledsim.agent.keeping import StationKeeping
from ledsim.constants import NavigationNoise
from ledsim.physics.tick import advance
from observer import jit
from observer.navigation.hull_loads import HullLoadObserver
from observer.navigation.ins import AidedINS
from observer.navigation.ins_state import InsState
from observer.navigation.rotations import rotation_exp
from tests.test_vehicle_rows import _start

pytestmark = pytest.mark.skipif(not jit.installed(), reason="numba is not installed")

TE = 0.01
N = 4


def _ins(rng) -> AidedINS:
    """N filters at random states with a random, well-conditioned covariance."""
    state = InsState(rng.normal(0, 3, (N, 3)), rng.normal(0, 0.5, (N, 3)),
                     rotation_exp(rng.normal(0, 1, (N, 3))), rng.normal(0, 1e-3, (N, 3)),
                     rng.normal(0, 1e-2, (N, 3)))
    ins = AidedINS(TE, state, inertial_noise(NavigationNoise()), 9.81)
    A = rng.normal(0, 1e-2, (N, 15, 15))
    ins.Ps = A @ A.swapaxes(1, 2) + np.eye(15) * 1e-6
    return ins


def _snapshot(ins: AidedINS) -> list[np.ndarray]:
    s = ins.states
    return [s.position, s.velocity, s.attitude, s.gyro_bias, s.accel_bias, ins.Ps,
            ins._F, ins.displacements]


def _both(act, make):
    """``act`` on a fresh object from ``make`` on the reference path, then on the compiled."""
    out = []
    for compiled in (False, True):
        obj = make()
        with jit.use(compiled):
            out.append(act(obj))
    return out


@pytest.mark.parametrize("scale", [1e-12, 1e-4, 0.05])
def test_ins_propagation_and_depth_update_match_the_reference(scale):
    rng = np.random.default_rng(7)
    da, dv = rng.normal(0, scale, (N, 3)), rng.normal(0, 10 * scale, (N, 3))
    depth, surface = rng.normal(2, 0.1, N), rng.normal(0, 0.1, N)

    def act(ins):
        for _ in range(5):
            ins.propagate_rows(da, dv)
            ins.depth_rows(depth, surface)
        return [a.copy() for a in _snapshot(ins)]

    ref, got = _both(act, lambda: _ins(np.random.default_rng(3)))
    for name, a, b in zip(("position", "velocity", "attitude", "gyro_bias", "accel_bias",
                           "P", "F", "displacement"), ref, got, strict=True):
        np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-15 * np.abs(a).max(),
                                   err_msg=name)


def test_load_observer_matches_the_reference_with_its_clip_and_deadband():
    rng = np.random.default_rng(1)
    measured = rng.normal(0, 1, (40, N, 5)) * np.array([1, 1, 1, 0.1, 0.1]) \
        + np.where(rng.random((40, N, 1)) < 0.1, 500.0, 0.0)  # strikes the clip holds

    def make():
        loads = [HullLoadObserver(TE, np.array([60, 80, 90, 5, 6.0]), 1e-2, 1e-3, 0.1,
                                  3.0, 4.0, limit=np.array([50, 50, 50, 5, 5.0]))
                 for _ in range(N)]
        return HullLoadObserver.stacked(loads)

    ref, got = _both(lambda o: np.array([o.update_rows(m) for m in measured]), make)
    np.testing.assert_allclose(got, ref, rtol=1e-13, atol=1e-15)
    assert (ref == 0).any() and (ref != 0).any()  # both sides of the deadband were met


CASES = [(0, ("current:speed=0.1,heading=1.2,gust=0.05",), 0.0),
         (1, ("dvl_dropout:start=0.5,duration=1",), 0.2),
         (2, ("kick:start=1,rate=3,hull=1",), 0.1)]


def _vehicle_run(seed, disturbances, gimbal, steps=250):
    w, ds, v = _start(seed, disturbances, gimbal)
    out = []
    for k in range(steps):
        advance(w, ds, 0.002 * math.sin(k / 7), (k + 1) * TE, v)
        nav, los = v.navigation, v.los
        out.append(np.r_[nav.position, nav.velocity, nav.attitude.ravel(), v.ins.P.ravel(),
                         los.rate, los.bearing, w.hull_pos, w.thrust])
    return np.array(out)


@pytest.mark.parametrize("case", CASES, ids=["current", "dvl_dropout", "hull_kick"])
def test_the_vehicle_steps_alike_on_both_paths(case):
    ref, got = _both(lambda _: _vehicle_run(*case), lambda: None)
    scale = np.abs(ref).max(axis=0) + 1e-12
    np.testing.assert_allclose(got / scale, ref / scale, rtol=0, atol=1e-9)


def test_station_keeping_pd_matches_the_reference_across_the_heading_wrap():
    from ledsim.agent.compiled_keeping import pd
    from ledsim.agent.keeping import PDInputs, _pd_terms
    from observer.rowops import FLOATS

    rng = np.random.default_rng(5)
    g = StationKeeping()
    kp = np.array([g.kp, g.kp, g.kp, g.kp_pitch, g.kp_yaw])
    kd = np.array([g.kd, g.kd, g.kd, g.kd_pitch, g.kd_yaw])
    n = 200
    att = rotation_exp(rng.normal(0, 2, (n, 3)))
    pos, vel, omega = (rng.normal(0, s, (n, 3)) for s in (0.05, 0.02, 0.05))
    P = np.zeros((n, 15, 15))
    P[:, range(15), range(15)] = rng.uniform(0, 1e-3, (n, 15))
    home, heading0 = rng.normal(0, 0.05, (n, 2)), rng.uniform(-4, 4, n)
    surface, hv = rng.normal(0, 0.05, n), rng.normal(0, 0.1, (n, 2))
    got = pd(att, pos, P, vel, omega, home, heading0, surface, hv, kp, kd, g.deadband,
             g.velocity_deadband)
    for i in range(n):
        d = P[i].diagonal()[[0, 1, 2, 7, 8, 3, 4, 5]]
        x = PDInputs(att[i, 1, 0], att[i, 0, 0], att[i, 2, 0], *pos[i], *home[i], heading0[i],
                     surface[i], *d, *vel[i], omega[i, 1], omega[i, 2], *hv[i])
        np.testing.assert_allclose(got[i], _pd_terms(FLOATS, g, kp, kd, x), rtol=1e-12,
                                   atol=1e-14)


def test_a_line_of_sight_constant_set_after_construction_reaches_both_paths():
    """The filter's constants are one array the kernel reads: a pull set afterwards
    moves the compiled step as it moves the reference."""
    from observer.navigation.line_of_sight import LineOfSightFilter

    rng = np.random.default_rng(7)
    inputs = [(rng.normal(scale=0.2, size=(1, 3)), rng.normal(scale=0.1, size=1),
               rng.normal(scale=0.05, size=1), rng.normal(scale=0.1, size=1))
              for _ in range(200)]
    bearings = {}
    for compiled in (False, True):
        for pull in (None, 0.5):
            f = LineOfSightFilter(0.01, 20.0, 1e-3)
            if pull is not None:
                f.k_bearing = pull
                assert f.k_bearing == pull
            with jit.use(compiled):
                for args in inputs:
                    f.update_rows(*args)
            bearings[compiled, pull] = f.bearing.copy()
    assert not np.allclose(bearings[False, None], bearings[False, 0.5])
    for pull in (None, 0.5):
        np.testing.assert_allclose(bearings[True, pull], bearings[False, pull], rtol=1e-12,
                                   atol=1e-15)
