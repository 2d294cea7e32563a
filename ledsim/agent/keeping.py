"""The vehicle's station keeping: thrusters that hold the home pose from the navigation.

A disturbance observer (:class:`~observer.navigation.hull_loads.HullLoadObserver`) estimates the
water's force and torque from the IMU and the thrusters cancel it; a soft PD on the
navigated pose holds the pose (surge, sway, heave, pitch, yaw; each in the hull's
frame, within the thrusters' limits of the MJCF). Each acts only on what stands out of
its own noise (the INS's covariance, the IMU's figures), so a hull in still water stays
still. It never reads the true pose after the start.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import NamedTuple

import numpy as np

from ledsim.constants import ConfigError, NavigationNoise
from ledsim.errors import check_ranges
from ledsim.physics.hull import set_thrust_rows
from ledsim.physics.world import LinkWorld
from observer import jit
from observer.navigation.hull_loads import HullLoadObserver, soft_deadband
from observer.navigation.ins import InsState
from observer.rowops import columns, ops
from observer.rows import Rows

compiled_keeping = jit.lazy("ledsim.agent.compiled_keeping")


@dataclass(frozen=True)
class StationKeeping:
    """The station keeping's gains, per axis of the hull's frame (surge, sway, heave;
    pitch, yaw).

    A disturbance observer estimates the force and torque the water puts on the hull,
    ``M a - thrust`` low-passed over ``observer_time`` (a from the IMU's velocity
    increments, pitch and yaw's from the gyro), and the thrusters cancel it: this
    rejects currents and gusts without stiff position gains. A soft PD on the navigated
    pose then holds the pose; being soft, it lets through little of the navigation's
    noise (the acoustic fixes' centimetres, the DVL's millimetres per second), which
    would otherwise shake the hull.

    Attributes:
        kp [N/m], kd [N s/m]: surge, sway and heave PD on position and velocity.
        kp_pitch, kp_yaw [N m/rad], kd_pitch, kd_yaw [N m s/rad]: pitch and heading PD.
        observer_time: time constant of the disturbance observer [s].
        slow_observer_time: time constant of its slow twin [s], which holds a steady
            load (a current) with less noise; the fast one adds what it sees beyond
            that (a gust) once it stands out of its noise.
        deadband: the PD acts on the part of each navigated error (position, depth,
            pitch, heading) beyond this many of the navigation's own standard
            deviations (its covariance), as a soft deadband [-]; 0: on all of it.
        velocity_deadband: the same for the navigated velocity [-].
        load_deadband: the thrusters cancel the part of the disturbance observer's
            estimate beyond this many standard deviations of its own noise (the IMU's,
            through the observer) [-]; 0: all of it.

    The deadbands keep a hull in still water still: without them it follows the
    navigation's noise (the DVL's, through the velocity and position; the
    accelerometer's and gyro's, through the observer) by millimetres, which at a short
    link is a large angle. They let a hull that something did push coast within them:
    over minutes of still water it wanders a little more than the navigation's error
    (docs/station_keeping.md gives both).

    Every gain must be >= 0 and finite, the time > 0 (:class:`~ledsim.constants.ConfigError`).
    """

    kp: float = 15.0
    kd: float = 40.0
    kp_pitch: float = 40.0
    kd_pitch: float = 20.0
    kp_yaw: float = 40.0
    kd_yaw: float = 20.0
    observer_time: float = 0.1
    slow_observer_time: float = 3.0
    deadband: float = 2.0
    velocity_deadband: float = 2.5
    load_deadband: float = 4.0

    def __post_init__(self) -> None:
        values = [(f.name, getattr(self, f.name), f.name.endswith("_time"))
                  for f in fields(self)]
        check_ranges([(n, v, v > 0 if timed else v >= 0,
                       f"{'> 0 s' if timed else '>= 0'} and finite")
                      for n, v, timed in values], ConfigError, "=")


class StationKeeper(Rows):
    """The station keeping of :class:`StationKeeping`'s gains on ``world``'s thrusters.

    Args:
        world: the scene (with its thrusters).
        Te: control period [s].
        gains: the gains and deadbands.
        noise: the IMU's noise figures (the load observer's noise).
        home: the station: horizontal position [m] (2,) and heading [rad].
        surface: the height of the depth sensor's zero [m].

    Stacked (:class:`~observer.rows.Rows`), one keeper drives N hulls
    (:meth:`act_rows`), each as its own would.
    """

    ROW_ARRAYS = ("thrust", "_omega", "k", "home_position", "home_heading", "surface",
                  "_mass", "home_velocity")
    ROW_LISTS = ("worlds",)

    def __init__(self, world: LinkWorld, Te: float, gains: StationKeeping,
                 noise: NavigationNoise, home: tuple[np.ndarray, float], surface: float):
        self.single, self.n = True, 1
        self.worlds, self.Te, self.gains = [world], Te, gains
        self.home_position = np.asarray(home[0], dtype=float)[None].copy()
        self.home_heading = np.array([float(home[1])])
        # The home's velocity, world frame [m/s] (a mission's moving target; 0: a station)
        self.home_velocity = np.zeros((1, 2))
        self.surface = np.array([float(surface)])
        mass = world.hull_inertia()  # surge, sway, heave [kg]; pitch, yaw [kg m^2]
        self._mass = mass[None]  # the gimbal's pose at the start changes it a little
        self.loads = HullLoadObserver(Te, mass, noise.accel_noise_density,
                                      noise.gyro_noise_density, gains.observer_time,
                                      gains.slow_observer_time, gains.load_deadband,
                                      limit=world.thrust_limits())
        self.thrust = np.zeros((1, 5))
        self._omega = np.zeros((1, 3))
        self.k = np.zeros(1, dtype=np.int64)
        g = gains
        self._kp = np.array([g.kp, g.kp, g.kp, g.kp_pitch, g.kp_yaw])
        self._kd = np.array([g.kd, g.kd, g.kd, g.kd_pitch, g.kd_yaw])

    @property
    def mass(self) -> np.ndarray:
        """The hull's mass [kg] and pitch and yaw inertia [kg m^2], (5,) ((N, 5))."""
        return self._mass[0] if self.single else self._mass

    @classmethod
    def stacked(cls, items):
        out = super().stacked(items)
        out.loads = HullLoadObserver.stacked([i.loads for i in items])
        return out

    def put(self, row: int, item) -> None:
        super().put(row, item)
        self.loads.put(row, item.loads)

    def act_rows(self, nav: InsState, P: np.ndarray, velocity: np.ndarray,
                 omega: np.ndarray, a: np.ndarray) -> np.ndarray:
        """Drive every hull's thrusters (each argument with a leading axis of N) from the
        navigated pose ``nav``, its covariance ``P`` (the INS's, 15x15), the hull-frame
        ``velocity`` [m/s], the bias-corrected gyro ``omega`` [rad/s] and the hull-frame
        acceleration ``a`` [m/s^2]; returns the thrust applied [N, N m], (N, 5)."""
        if jit.enabled():
            load = self.loads.update_rows(compiled_keeping.measured(
                omega, self._omega, self.k, a, self._mass, self.thrust, self.Te))
            g = self.gains
            command = compiled_keeping.pd(
                nav.attitude, nav.position, P, velocity, omega, self.home_position,
                self.home_heading, self.surface, self.home_velocity, self._kp, self._kd,
                float(g.deadband), float(g.velocity_deadband)) - load
        else:
            alpha = (omega - self._omega) / self.Te
            if not self.k.all():  # a first step has no earlier rate
                alpha = np.where(self.k[:, None] > 0, alpha, 0.0)
            measured = self._mass * np.concatenate([a, alpha[:, 1:]], axis=1) - self.thrust
            load = self.loads.update_rows(measured)
            command = self._pd(nav, P, velocity, omega) - load
        self.thrust = set_thrust_rows(self.worlds, command)
        self._omega = omega
        self.k = self.k + 1
        return self.thrust

    def _pd(self, nav: InsState, P: np.ndarray, velocity: np.ndarray,
            omega: np.ndarray) -> np.ndarray:
        """Surge, sway, heave [N], pitch and yaw [N m] of the PD that holds the home pose
        (hull frame), (N, 5)."""
        n, att, pos = self.n, nav.attitude, nav.position
        d = P[:, _DIAG, _DIAG]  # the variances of x, y, z, pitch, yaw, vx, vy, vz
        cols = columns(n, att[:, 1, 0], att[:, 0, 0], att[:, 2, 0], pos[:, 0], pos[:, 1],
                       pos[:, 2], self.home_position[:, 0], self.home_position[:, 1],
                       self.home_heading, self.surface, *d.T, *velocity.T, omega[:, 1],
                       omega[:, 2], self.home_velocity[:, 0], self.home_velocity[:, 1])
        out = _pd_terms(ops(n), self.gains, self._kp, self._kd, PDInputs(*cols))
        return np.array([out]) if n == 1 else np.array(out).T


#: P's diagonal entries the deadbands read (x, y, z, pitch, yaw; vx, vy, vz).
_DIAG = np.array([0, 1, 2, 7, 8, 3, 4, 5])


class PDInputs(NamedTuple):
    """What the station-keeping PD reads of one hull (floats) or of N (columns): the
    navigated attitude's entries R[1,0], R[0,0], R[2,0] and position [m]; home (x, y
    [m], heading [rad], depth of the surface [m]); the navigation's variances of x, y,
    z [m^2], pitch, yaw [rad^2], vx, vy, vz [m^2/s^2]; the hull-frame velocity [m/s]
    and the pitch and yaw rates [rad/s]; the home's velocity, world frame (x, y [m/s]:
    a mission's target; 0 at a station)."""

    r10: object
    r00: object
    r20: object
    px: object
    py: object
    pz: object
    hx: object
    hy: object
    heading0: object
    surface: object
    var_x: object
    var_y: object
    var_z: object
    var_pitch: object
    var_yaw: object
    var_vx: object
    var_vy: object
    var_vz: object
    ux: object
    uy: object
    uz: object
    wy: object
    wz: object
    hvx: object = 0.0
    hvy: object = 0.0


def _pd_terms(o, g: StationKeeping, kp, kd, x: PDInputs):
    """The PD's five terms of one hull (floats) or of N (columns), ``o`` the arithmetic
    (:mod:`observer.rowops`): the navigated pose's error from home, each error and
    velocity shrunk by its soft deadband (the part beyond ``deadband`` of the
    navigation's own standard deviations: ``max(0, 1 - (k^2 var / e^2)^2)``)."""
    (r10, r00, r20, px, py, pz, hx, hy, heading0, surface, vx_, vy_, vz_, vpitch, vyaw,
     vvx, vvy, vvz, ux, uy, uz, wy, wz, hvx, hvy) = x
    heading = o.atan2(r10, r00)
    pitch = o.asin(o.maximum(-1.0, o.minimum(1.0, -r20)))
    c, s = o.cos(heading), o.sin(heading)
    dx, dy = px - hx, py - hy
    err = [c * dx + s * dy, -s * dx + c * dy, pz - surface, pitch,
           o.remainder(heading - heading0, 2 * math.pi)]
    # the velocity relative to the home's, in the hull's frame (0 at a station)
    rate = [ux - (c * hvx + s * hvy), uy - (-s * hvx + c * hvy), uz, wy, wz]
    k, kv = g.deadband, g.velocity_deadband
    e2 = [o.square(e) for e in err]
    v2 = [o.square(v) for v in rate[:3]]
    share = [soft_deadband(e2[0] + e2[1], 0.5 * (vx_ + vy_), k),
             soft_deadband(e2[2], vz_, k), soft_deadband(e2[3], vpitch, k),
             soft_deadband(e2[4], vyaw, k)]
    vshare = [soft_deadband(v2[0] + v2[1], 0.5 * (vvx + vvy), kv),
              soft_deadband(v2[2], vvz, kv)]
    err = [err[0] * share[0], err[1] * share[0], err[2] * share[1], err[3] * share[2],
           err[4] * share[3]]
    rate = [rate[0] * vshare[0], rate[1] * vshare[0], rate[2] * vshare[1], rate[3], rate[4]]
    return [-kp[i] * err[i] - kd[i] * rate[i] for i in range(5)]
