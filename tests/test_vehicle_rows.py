"""Vehicles stacked into one (observer.rows.Rows) step every row exactly as its own
vehicle does: navigation sensors, INS, station keeping and line of sight, through
currents, DVL dropouts, late and outlier fixes, kicks and different starts; a row put
back from a fresh vehicle carries on as that vehicle; and the row-wise kernels give
each row what one vehicle's computes."""

from __future__ import annotations

import numpy as np
import pytest

from ledsim.agent.autopilot import Vehicle
from ledsim.constants import NavigationNoise
from ledsim.physics.disturbances import parse_disturbance
from ledsim.physics.tick import advance, prepare
from ledsim.physics.world import LinkWorld
from observer.navigation.hull_loads import HullLoadObserver
from observer.navigation.rotations import libm_square, rotation_exp, rotation_log, skew

TE = 0.01
NOISE = NavigationNoise(fix_outlier_share=0.3, fix_range_error=0.01, fix_latency=0.7)
CASES = [(0, ("current:speed=0.1,heading=1.2,gust=0.05",), 0.0),
         (1, ("dvl_dropout:start=0.5,duration=1",), 0.2),
         (2, (), -0.3),
         (3, ("kick:start=1,rate=3,hull=1",), 0.1)]


def _start(seed, disturbances, gimbal):
    w = LinkWorld()
    w.reset(gimbal_angle=gimbal)
    ds = [parse_disturbance(d) for d in disturbances]
    for d in ds:
        d.reset(seed)
    w.forward_kinematics()
    v = Vehicle(w, TE, seed, 0.085, station_keeping=True, noise=NOISE)
    prepare(w, ds, 0.0, v)
    return w, ds, v


def _torque(k):
    return 0.002 * np.sin(k / 7)


def _record(w, nav, los, P):
    return np.r_[nav.position, nav.velocity, nav.attitude.ravel(), nav.gyro_bias,
                 nav.accel_bias, P.ravel(), los.rate, los.bearing, los.acceleration,
                 w.hull_pos, w.thrust]


def _alone(seed, disturbances, gimbal, steps):
    w, ds, v = _start(seed, disturbances, gimbal)
    out = []
    for k in range(steps):
        advance(w, ds, _torque(k), (k + 1) * TE, v)
        out.append(_record(w, v.navigation, v.los, v.ins.P))
    return np.array(out), v


def test_stacked_vehicles_step_each_row_as_its_own_vehicle():
    steps = 300
    alone = [_alone(*case, steps)[0] for case in CASES]
    started = [_start(*case) for case in CASES]
    vehicles = Vehicle.stacked([v for _, _, v in started])
    rows = [vehicles.row(i) for i in range(len(CASES))]
    got = [[] for _ in CASES]
    for k in range(steps):
        for w, ds, _ in started:
            w.set_torque(_torque(k))
            w.step()
            prepare(w, ds, (k + 1) * TE)
        vehicles.act_rows((k + 1) * TE)
        for i, (w, _, _) in enumerate(started):
            got[i].append(_record(w, rows[i].navigation, rows[i].los, vehicles.ins.Ps[i]))
    for i, case in enumerate(CASES):
        np.testing.assert_array_equal(np.array(got[i]), alone[i], err_msg=f"row {i}: {case}")
    assert vehicles.sensor.outliers.sum() > 0  # the gate was exercised
    assert rows[2].reading.encoder == pytest.approx(started[2][0].gimbal_angle, abs=1e-3)


def test_a_row_put_back_from_a_fresh_vehicle_carries_on_as_it():
    started = [_start(*case) for case in CASES[:2]]
    vehicles = Vehicle.stacked([v for _, _, v in started])
    for k in range(20):
        for w, ds, _ in started:
            advance(w, ds, 0.0, (k + 1) * TE)
        vehicles.act_rows((k + 1) * TE)
    w, ds, fresh = _start(*CASES[2])  # row 1's world restarts as another vehicle
    vehicles.put(1, fresh)
    assert vehicles.worlds[1] is w and vehicles.sensor.worlds[1] is w
    alone, _ = _alone(*CASES[2], 50)
    row = vehicles.row(1)
    for k in range(50):
        advance(w, ds, _torque(k), (k + 1) * TE)
        advance(started[0][0], started[0][1], 0.0, (k + 21) * TE)
        vehicles.act_rows(np.array([(k + 21) * TE, (k + 1) * TE]))
        np.testing.assert_array_equal(_record(w, row.navigation, row.los, vehicles.ins.Ps[1]),
                                      alone[k], err_msg=f"step {k}")


def test_stacking_refuses_settings_the_rows_cannot_share():
    loads = [HullLoadObserver(TE, np.full(5, m), 1e-3, 1e-3, 0.1, 3.0, 4.0) for m in (1, 2)]
    HullLoadObserver.stacked(loads)  # the masses are rows: fine
    loads[1].deadband = 2.0
    with pytest.raises(ValueError, match="deadband differs"):
        HullLoadObserver.stacked(loads)


def test_row_kernels_give_each_row_what_one_row_gets():
    rng = np.random.default_rng(3)
    phi = rng.standard_normal((200, 3)) * rng.choice([1e-12, 1e-3, 1.0, 3.0], (200, 1))
    exp = rotation_exp(phi)
    for i in range(0, 200, 7):
        np.testing.assert_array_equal(rotation_exp(phi[i]), exp[i])
        np.testing.assert_array_equal(rotation_log(exp[i]), rotation_log(exp)[i])
        np.testing.assert_array_equal(skew(phi[i]), skew(phi)[i])
    x = rng.uniform(-5, 5, 5000)
    assert np.array_equal(libm_square(x), np.array([v**2 for v in x.tolist()]))
