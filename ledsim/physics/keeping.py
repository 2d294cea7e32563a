"""The vehicle's station keeping: thrusters that hold the home pose from the navigation.

A disturbance observer (:class:`~observer.hull_loads.HullLoadObserver`) estimates the
water's force and torque from the IMU and the thrusters cancel it; a soft PD on the
navigated pose holds the pose (surge, sway, heave, pitch, yaw; each in the hull's
frame, within the thrusters' limits of the MJCF). Each acts only on what stands out of
its own noise (the INS's covariance, the IMU's figures), so a hull in still water stays
still. It never reads the true pose after the start.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from observer.hull_loads import HullLoadObserver, soft_deadband
from observer.ins import InsState

from ..config import ConfigError, NavigationNoise
from .world import LinkWorld


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

    Every gain must be >= 0 and finite, the time > 0 (:class:`~ledsim.config.ConfigError`).
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
        for f in fields(self):
            v = getattr(self, f.name)
            timed = f.name.endswith("_time")
            if not (math.isfinite(v) and (v > 0 if timed else v >= 0)):
                raise ConfigError(f"{f.name}={v!r} is not allowed: must be "
                                  f"{'> 0 s' if timed else '>= 0'} and finite")


class StationKeeper:
    """The station keeping of :class:`StationKeeping`'s gains on ``world``'s thrusters.

    Args:
        world: the scene (with its thrusters).
        Te: control period [s].
        gains: the gains and deadbands.
        noise: the IMU's noise figures (the load observer's noise).
        home: the station: horizontal position [m] (2,) and heading [rad].
        surface: the height of the depth sensor's zero [m].
    """

    def __init__(self, world: LinkWorld, Te: float, gains: StationKeeping,
                 noise: NavigationNoise, home: tuple[np.ndarray, float], surface: float):
        self.world, self.Te, self.gains = world, Te, gains
        self.home, self.surface = home, surface
        self.mass = world.hull_inertia()  # surge, sway, heave [kg]; pitch, yaw [kg m^2]
        self.loads = HullLoadObserver(Te, self.mass, noise.accel_noise_density,
                                      noise.gyro_noise_density, gains.observer_time,
                                      gains.slow_observer_time, gains.load_deadband,
                                      limit=world.thrust_limits())
        self.thrust = np.zeros(5)
        self._omega = np.zeros(3)
        self.k = 0
        g = gains
        self._kp = np.array([g.kp, g.kp, g.kp, g.kp_pitch, g.kp_yaw])
        self._kd = np.array([g.kd, g.kd, g.kd, g.kd_pitch, g.kd_yaw])

    def act(self, nav: InsState, covariance: np.ndarray, velocity: np.ndarray,
            omega: np.ndarray, a: np.ndarray) -> np.ndarray:
        """Drive the thrusters from the navigated pose ``nav``, its ``covariance`` (the
        INS's, 15x15), the hull-frame ``velocity`` [m/s], the bias-corrected gyro
        ``omega`` [rad/s] and the hull-frame acceleration ``a`` [m/s^2]; returns the
        thrust applied [N, N m]."""
        alpha = (omega - self._omega) / self.Te if self.k else np.zeros(3)
        measured = self.mass * np.array([*a, alpha[1], alpha[2]]) - self.thrust
        load = self.loads.update(measured)
        self.thrust = self.world.set_thrust(
            self._pd(nav, covariance, velocity, omega) - load)
        self._omega = omega
        self.k += 1
        return self.thrust

    def _pd(self, nav: InsState, P: np.ndarray, velocity: np.ndarray,
            omega: np.ndarray) -> np.ndarray:
        """Surge, sway, heave [N], pitch and yaw [N m] of the PD that holds the home pose
        (hull frame)."""
        g = self.gains
        heading = nav.heading
        c, s = math.cos(heading), math.sin(heading)
        dp = nav.position[:2] - self.home[0]
        err = np.array([c * dp[0] + s * dp[1], -s * dp[0] + c * dp[1],
                        nav.position[2] - self.surface, nav.pitch,
                        math.remainder(heading - self.home[1], 2 * math.pi)])
        rate = np.array([*velocity, omega[1], omega[2]])
        # Act only on what the navigation knows: the part of each error beyond
        # `deadband` of its own standard deviations (the covariance of the INS).
        k = g.deadband
        e, v = err.tolist(), rate.tolist()
        err[:2] *= soft_deadband(e[0]**2 + e[1]**2, 0.5 * float(P[0, 0] + P[1, 1]), k)
        err[2] *= soft_deadband(e[2]**2, float(P[2, 2]), k)
        err[3] *= soft_deadband(e[3]**2, float(P[7, 7]), k)
        err[4] *= soft_deadband(e[4]**2, float(P[8, 8]), k)
        k = g.velocity_deadband
        rate[:2] *= soft_deadband(v[0]**2 + v[1]**2, 0.5 * float(P[3, 3] + P[4, 4]), k)
        rate[2] *= soft_deadband(v[2]**2, float(P[5, 5]), k)
        return -self._kp * err - self._kd * rate
