"""The vehicle's aided INS (observer.navigation.ins): gravity levels it, it is consistent, and it
holds through the faults real navigation meets (late fixes, outliers, DVL dropouts)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ledsim.agent.autopilot import Vehicle
from ledsim.constants import NavigationNoise
from ledsim.physics.disturbances import DisturbanceError, parse_disturbance
from ledsim.physics.nav_sensors import NavigationSensor
from ledsim.physics.tick import advance, prepare
from ledsim.physics.world import LinkWorld
from observer.navigation.ins import InsState
from observer.navigation.rotations import rotation_exp, rotation_log

TE = 0.01


def _drive(seconds: float, seed: int = 0, noise: NavigationNoise | None = None,
           disturbances=(), keep_station: bool = False, on_step=None,
           start_from_prior: bool = False) -> Vehicle:
    """A vehicle on a world with no gimbal torque for ``seconds`` s; with
    ``start_from_prior`` the INS starts off the truth by a draw from its own initial
    covariance (as consistency needs: the truth a draw from the filter's prior)."""
    w = LinkWorld()
    w.reset()
    dist = [parse_disturbance(d) for d in disturbances]
    for d in dist:
        d.reset(seed)
    w.forward_kinematics()
    v = Vehicle(w, TE, seed, 0.085, station_keeping=keep_station, noise=noise)
    if start_from_prior:  # position, velocity, attitude (the biases already are)
        draw = np.random.default_rng(1000 + seed).standard_normal(15)
        draw[9:] = 0.0
        v.ins._inject(-np.linalg.cholesky(v.ins.P) @ draw)  # truth - estimate ~ N(0, P)
    prepare(w, dist, 0.0, v)
    for k in range(int(round(seconds / TE))):
        if on_step is not None:
            on_step(k, w, v)
        advance(w, dist, 0.0, (k + 1) * TE, v)
    return v


def _truth(w: LinkWorld, v: Vehicle) -> InsState:
    b = v.sensor.biases
    return InsState(w.hull_pos.copy(), w.hull_velocity()[3:].copy(), w.hull_rotation,
                    b.gyro, b.accel)


def _chi2_quantile(p: float, dof: int) -> float:
    """Wilson-Hilferty's chi-square quantile (within 0.1 % at 100 degrees of freedom)."""
    from statistics import NormalDist

    z = NormalDist().inv_cdf(p)
    return dof * (1 - 2 / (9 * dof) + z * math.sqrt(2 / (9 * dof))) ** 3


def test_rotation_exp_and_log_are_inverse():
    rng = np.random.default_rng(0)
    for _ in range(20):
        axis = rng.normal(size=3)
        phi = axis / np.linalg.norm(axis) * rng.uniform(1e-6, 3.0)  # angles below pi
        np.testing.assert_allclose(rotation_log(rotation_exp(phi)), phi, atol=1e-9)
        R = rotation_exp(phi)
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)


def test_gravity_levels_the_attitude_a_gyro_bias_would_tilt():
    """A gyro bias alone, 100 deg/h on a still hull: integrated on its own it tilts the
    attitude by 29 mrad in a minute, and gravity then leaks into the velocity (0.28 m/s^2).
    The INS levels against gravity through the DVL, and learns the bias."""
    bias = math.radians(100.0) / 3600.0
    noise = NavigationNoise(gyro_bias_instability=bias, gyro_bias_time=1e6,
                            accel_bias_instability=0.0)
    tilt, gyro_only = [], []
    R_gyro = [None]

    def watch(k, w, v):
        R = w.hull_rotation
        if R_gyro[0] is None:
            R_gyro[0] = R.copy()
        R_gyro[0] = R_gyro[0] @ rotation_exp(v.reading.delta_angle)
        est = v.navigation.attitude
        tilt.append(np.linalg.norm(rotation_log(est.T @ R)[:2]))
        gyro_only.append(np.linalg.norm(rotation_log(R_gyro[0].T @ R)[:2]))

    v = _drive(60.0, seed=3, noise=noise, on_step=watch)
    assert gyro_only[-1] > 0.02  # the mechanism: integrating the gyro alone tilts
    assert max(tilt[-1000:]) < 2e-3  # the INS stays level
    true_bias = v.sensor.biases.gyro
    np.testing.assert_allclose(v.navigation.gyro_bias[:2], true_bias[:2],
                               atol=0.2 * bias)  # learnt from the levelling
    assert np.linalg.norm(v.navigation.velocity) < 0.01


def _mean_nees(runs: int, inflate: float = 1.0) -> np.ndarray:
    """NEES at every 1.5 s of 30 s in a gusty current, averaged over ``runs`` seeds;
    ``inflate``: the filter is told the sensors' noise that many times too large."""
    from dataclasses import replace

    from observer.navigation.ins import AidedINS

    samples = np.arange(150, 3001, 150)
    nees = np.zeros((runs, len(samples)))
    for r in range(runs):
        def watch(k, w, v, r=r):
            if k == 0 and inflate != 1.0:
                old = v.ins
                told = replace(old.noise, **{f: getattr(old.noise, f) * inflate for f in (
                    "gyro_noise_density", "accel_noise_density", "dvl_noise",
                    "magnetometer_noise", "depth_noise")})
                v.ins = AidedINS(TE, old.state, told, old.gravity, old.R_dvl, old.l_dvl,
                                 old.field, history=old._history.maxlen)
                v.ins.P = old.P.copy()
            hit = np.flatnonzero(samples == k)
            if hit.size:
                nees[r, hit[0]] = v.ins.nees(_truth(w, v))

        _drive(30.0 + TE, seed=r, keep_station=True, start_from_prior=True,
               disturbances=("current:speed=0.1,heading=1.2,gust=0.05",), on_step=watch)
    return nees.mean(axis=0)


def test_the_ins_is_consistent_its_nees_within_two_sided_chi_square_bounds():
    """NEES averaged over runs at a time lies in the two-sided 95 % chi-square bounds of
    a consistent filter at most time points: a filter too confident (too small a
    covariance) fails the upper bound, one that inflates its noise the lower."""
    runs = 10
    dof = 15 * runs
    lo, hi = _chi2_quantile(0.025, dof) / runs, _chi2_quantile(0.975, dof) / runs
    mean = _mean_nees(runs)
    inside = np.mean((mean > lo) & (mean < hi))
    assert inside >= 0.8, (mean, lo, hi)
    assert lo < mean.mean() < hi  # the whole run's average, too
    # The test can fail: told twice the noise, the same filter is too cautious.
    assert _mean_nees(runs, inflate=2.0).mean() < lo


def _horizontal_error(w, v) -> float:
    return float(np.linalg.norm(v.navigation.position[:2] - w.hull_pos[:2]))


def test_late_fixes_are_compared_with_where_the_hull_was():
    """Fixes 1 s late on a hull drifting at 0.2 m/s: taken as current they would pull
    it 20 cm back; compared with the INS's own position 1 s ago, they keep it right."""
    errors, start = [], []

    def watch(k, w, v):
        start.append(w.hull_pos[:2].copy()) if k == 0 else None
        if k >= 1000:
            errors.append(_horizontal_error(w, v))

    v = _drive(30.0, seed=2, noise=NavigationNoise(fix_latency=1.0),
               disturbances=("current:speed=0.2,heading=0.7,gust=0.0,hold=0",),
               on_step=watch)
    assert np.linalg.norm(v.world.hull_pos[:2] - start[0]) > 3.0  # it did drift
    assert v.ins.rejected_fixes <= 2
    assert max(errors) < 0.03


def test_outlier_fixes_are_refused_by_the_gate():
    noise = NavigationNoise(fix_outlier_share=0.2, fix_outlier_size=2.0)
    errors = []
    v = _drive(60.0, seed=4, noise=noise, keep_station=True,
               on_step=lambda k, w, v: errors.append(_horizontal_error(w, v)))
    assert v.sensor.outliers >= 8
    # Nearly every outlier refused (a small one passes unseen), few good fixes lost.
    assert 0.7 * v.sensor.outliers <= v.ins.rejected_fixes <= v.sensor.outliers + 2
    assert max(errors) < 0.04


def test_a_dvl_dropout_stops_the_pings_and_the_ins_coasts_through_it():
    errors, fresh, normalised = [], [], []

    def watch(k, w, v):
        errors.append(_horizontal_error(w, v))
        normalised.append(errors[-1] / math.sqrt(v.ins.P[0, 0] + v.ins.P[1, 1]))
        fresh.append(v.reading.dvl_fresh)

    _drive(25.0, seed=1, keep_station=True,
           disturbances=("dvl_dropout:start=5,duration=5,every=12",), on_step=watch)
    t = np.arange(len(fresh)) * TE
    lost = ((t >= 5) & (t < 10)) | ((t >= 17) & (t < 22))
    assert not any(np.asarray(fresh)[lost])
    assert np.sum(np.asarray(fresh)[~lost]) > 8 * 10  # 8 Hz otherwise
    # Coasting, the tilt's uncertainty through gravity moves it by centimetres, and the
    # INS knows it: the error stays within its own covariance.
    assert max(errors) < 0.1 and max(normalised) < 4.0
    assert max(np.asarray(errors)[~lost]) < max(errors)  # it was the dropout


def test_dvl_dropout_specs_are_checked():
    d = parse_disturbance("dvl_dropout:start=30,duration=5,every=60")
    assert [d.lost(t) for t in (29.9, 30.0, 34.9, 35.0, 90.0, 96.0)] == \
        [False, True, True, False, True, False]
    assert not parse_disturbance("dvl_dropout:start=1,duration=2").lost(3.5)
    for bad in ("dvl_dropout:duration=5,every=5", "dvl_dropout:duration=0",
                "dvl_dropout:every=-1", "dvl_dropout:start=1,start=2"):
        with pytest.raises(DisturbanceError):
            parse_disturbance(bad)


def test_a_fix_error_grows_with_the_range_to_the_transceiver():
    w = LinkWorld()
    w.reset()
    w.forward_kinematics()
    r = w.usbl_range()
    assert 3.0 < r < 5.0
    s = NavigationSensor(w, TE, noise=NavigationNoise(fix_range_error=0.01))
    reading = s.read()
    assert reading.fix_std == pytest.approx(math.hypot(0.03, 0.01 * r))
    fixes = []
    for _ in range(400):
        fix = s.read().position_fix
        if fix is not None:
            fixes.append(fix - w.hull_pos)
    assert len(fixes) == 4  # 1 Hz


@pytest.mark.parametrize("bad", [dict(fix_latency=6.0), dict(fix_range_error=0.2),
                                 dict(fix_outlier_share=-0.1),
                                 dict(fix_outlier_size=float("nan")),
                                 dict(magnetometer_rate=0.0)])
def test_the_faults_figures_are_checked(bad):
    from ledsim.constants import ConfigError

    with pytest.raises(ConfigError, match=next(iter(bad))):
        NavigationNoise(**bad)


def test_the_load_observer_knows_its_own_noise_and_passes_only_real_loads():
    """In still water its estimates carry the IMU's noise at the variance it computes,
    and it passes on (nearly) nothing; a steady 2 N current and a gust pass; a strike's
    impulse does not stay in the slow estimate."""
    from observer.navigation.hull_loads import HullLoadObserver

    mass = np.array([30.0, 30.0, 30.0, 4.0, 4.0])
    n = NavigationNoise()
    obs = HullLoadObserver(TE, mass, n.accel_noise_density, n.gyro_noise_density, 0.1,
                           3.0, 4.0, limit=[100, 100, 100, 25, 25])
    rng = np.random.default_rng(0)
    accel_std = n.accel_noise_density / math.sqrt(TE)
    gyro_std = n.gyro_noise_density / math.sqrt(2 * TE)
    omega_prev = np.zeros(2)
    fast, slow, passed = [], [], []
    for _ in range(60_000):
        omega = rng.standard_normal(2) * gyro_std
        measured = np.r_[mass[:3] * rng.standard_normal(3) * accel_std,
                         mass[3:] * (omega - omega_prev) / TE]
        omega_prev = omega
        passed.append(obs.update(measured))
        fast.append(obs.load.copy())
        slow.append(obs.slow_load.copy())
    fast, slow = np.array(fast[1000:]), np.array(slow[1000:])
    np.testing.assert_allclose(slow.var(axis=0), obs.slow_variance, rtol=0.15)
    np.testing.assert_allclose((fast - slow).var(axis=0), obs.gust_variance, rtol=0.1)
    assert np.mean(np.abs(passed[1000:])) < 0.01 * np.sqrt(obs.gust_variance).mean()
    steady = np.r_[0.0, 2.0, 0.0, 0.0, 0.0]
    for _ in range(1500):  # 15 s of a 2 N sideways current
        out = obs.update(steady)
    assert out[1] == pytest.approx(2.0, rel=0.01)
    kick = obs.update(np.r_[0.0, 2.0, 0.0, 0.0, 1200.0])  # a yaw strike, one step
    assert kick[4] > 100.0  # the fast estimate brakes it
    assert obs.slow_load[4] < 0.1  # the slow one believes no more than 25 N m of it
