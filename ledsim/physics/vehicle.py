"""The vehicle: its navigation, its station keeping on the thrusters, and the line of
sight it measures for the gimbal.

Once per control step (:func:`ledsim.physics.tick.prepare`), :meth:`Vehicle.act`:

1. reads its sensors with their noise (:class:`~ledsim.physics.navigation.NavigationSensor`);
2. navigates, starting from the known start: the attitude by integrating the gyro, the
   heading and horizontal position by dead reckoning on the gyro and DVL corrected by
   the acoustic fixes (:class:`~observer.navigation.DeadReckoning`), the depth from the
   pressure sensor, and the hull's velocity from the DVL smoothed by the accelerometer
   (a complementary filter over ``velocity_time``);
3. measures the line-of-sight rate at the receiver, what the hull's motion does to the
   LED's bearing (the transmitter's own motion is unknown to it)::

       v_g  = v + omega x l_g                 the gimbal's velocity, hull frame [m/s]
       u    = (cos q, sin q)                  the receiver's axis (encoder q) ~ the LOS
       w    = (u x (-v_g))_z / d              the LOS rate [rad/s]

   with d the link distance the run is told (``--distance``): sway enters the bearing
   through d, so a wrong d scales this feed-forward, and the photodiodes correct the
   rest. w is low-passed and shrunk by the share of its power that is the sensors'
   noise (a Wiener gain from the noise figures), so a still hull's feed-forward does not
   turn the gimbal by the DVL's noise;
4. keeps station (unless told not to): a disturbance observer estimates the water's
   force and torque from the accelerometer and gyro, the thrusters cancel it, and a soft
   PD on the navigated pose holds the home pose (surge, sway, heave, pitch, yaw; each in
   the hull's frame, within the thrusters' limits of the MJCF). It never reads the true
   pose after the start.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from observer.navigation import DeadReckoning

from ..config import ConfigError, NavigationNoise
from .navigation import GRAVITY_REACTION, NavigationReading, NavigationSensor
from .world import LinkWorld


@dataclass
class LineOfSight:
    """What the vehicle measured of the line of sight this step.

    Attributes:
        rate: the LED's bearing rate at the receiver from the hull's motion [rad/s].
        acceleration: its change over the last step [rad/s^2]: the input the hull's
            motion adds to phi'' (the gimbal itself is inertially free on its hinge).
        hull_rate: the gyro's yaw rate [rad/s].
        bearing: how far the LED's bearing in the hull's frame has turned since the
            start [rad]: the integral of ``rate - hull_rate``, pulled over
            ``bearing_time`` towards the bearing the navigated pose gives (the LED where
            the start put it), so a large excursion of the hull leaves no lasting error.
    """

    rate: float = 0.0
    acceleration: float = 0.0
    hull_rate: float = 0.0
    bearing: float = 0.0

    @property
    def incidence_rate(self) -> float:
        """phidot [rad/s] from the encoder rate is ``rate - hull_rate - qdot``."""
        return self.rate - self.hull_rate


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

    Every gain must be >= 0 and finite, the time > 0 (:class:`~ledsim.config.ConfigError`).
    """

    kp: float = 15.0
    kd: float = 40.0
    kp_pitch: float = 40.0
    kd_pitch: float = 20.0
    kp_yaw: float = 40.0
    kd_yaw: float = 20.0
    observer_time: float = 0.1

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            timed = f.name == "observer_time"
            if not (math.isfinite(v) and (v > 0 if timed else v >= 0)):
                raise ConfigError(f"{f.name}={v!r} is not allowed: must be "
                                  f"{'> 0 s' if timed else '>= 0'} and finite")


def _cross(a, b) -> np.ndarray:
    """a x b of two 3-vectors (numpy's formula in plain floats: np.cross costs 30 us)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def _rotate(R: np.ndarray, omega: np.ndarray, dt: float) -> np.ndarray:
    """R turned by the body rate ``omega`` [rad/s] for ``dt`` [s] (Rodrigues)."""
    angle = float(np.linalg.norm(omega)) * dt
    if angle < 1e-12:
        return R
    k = omega / np.linalg.norm(omega)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return R @ (np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K)


class Vehicle:
    """The AUV's navigation and station keeping on ``world`` (see the module docstring).

    Args:
        world: the scene (with the vehicle's sensors and thrusters).
        Te: control period [s].
        seed: the run's seed (the sensors' noise).
        distance: the link distance the run is told [m] (the LOS rate's d).
        station_keeping: drive the thrusters (False: they stay idle, the hull drifts).
        noise: the sensors' noise figures (None: the defaults).
        gains: the station keeping's gains.
        velocity_time: time constant of the DVL/accelerometer velocity filter [s].
        fix_gain: share of an acoustic fix taken into the navigated position [-].
        rate_time: time constant of the LOS rate's low-pass [s].
        bearing_time: time constant of the bearing's pull towards the navigation's [s].
    """

    def __init__(self, world: LinkWorld, Te: float, seed: int, distance: float,
                 station_keeping: bool = True, noise: NavigationNoise | None = None,
                 gains: StationKeeping = StationKeeping(), velocity_time: float = 0.3,
                 fix_gain: float = 0.05, rate_time: float = 0.05,
                 bearing_time: float = 2.0):
        self.world, self.Te, self.distance = world, Te, distance
        self.sensor = NavigationSensor(world, Te, seed, noise)
        self.station_keeping = station_keeping and world.ids.thrusters is not None
        self.gains = gains
        self.k_velocity = min(1.0, 1.0 / (self.sensor.noise.dvl_rate * velocity_time))
        self.attitude = world.hull_rotation  # hull frame in the world, from the gyro
        self.R_dvl, self.l_dvl = world.site_in_hull("dvl")
        self.l_gimbal = world.gimbal_in_hull()
        self.navigation = DeadReckoning(Te, world.hull_pos[:2], world.hull_yaw, self.R_dvl,
                                        self.l_dvl, fix_gain=fix_gain)
        self.home = (world.hull_pos[:2].copy(), world.hull_yaw)
        self.velocity = self.attitude.T @ world.hull_velocity()[3:]  # hull frame [m/s]
        self.mass = world.hull_inertia()  # surge, sway, heave [kg]; pitch, yaw [kg m^2]
        self.load = np.zeros(5)  # the water's force and torque, estimated [N, N m]
        self.thrust = np.zeros(5)
        self.los = LineOfSight()
        self.reading: NavigationReading | None = None
        self._omega = np.zeros(3)
        self.k = 0  # steps taken
        # The LOS rate: low-passed over rate_time, and its power over 0.5 s; the
        # noise it carries [rad/s] from the sensors' figures: the DVL's through the
        # velocity filter, the gyro's through the gimbal's lever arm, then the low-pass.
        n = self.sensor.noise
        self.k_rate, self.k_power = min(1.0, Te / rate_time), min(1.0, Te / 0.5)
        dvl = n.dvl_noise**2 / (2.0 * velocity_time * n.dvl_rate)
        lever2 = float(self.l_gimbal[0]**2 + self.l_gimbal[1]**2)
        gyro = n.gyro_noise_density**2 / (2 * Te) * lever2
        self.rate_noise = math.sqrt(dvl + gyro * Te / (2 * rate_time)) / distance
        self._raw = self._power = 0.0
        # Where the start put the LED: d ahead of the hinge along the hull's axis.
        self.k_bearing = min(1.0, Te / bearing_time)
        hinge0 = world.hull_pos[:2] + (self.attitude @ self.l_gimbal)[:2]
        self.led = hinge0 + distance * self.attitude[:2, 0] / np.linalg.norm(
            self.attitude[:2, 0])
        self._bearing0 = 0.0
        self._bearing0 = self._nav_bearing(self.navigation.state)

    def act(self, t: float) -> LineOfSight:
        """Sense, navigate, measure the line of sight and drive the thrusters at ``t``."""
        r = self.reading = self.sensor.read()
        omega = r.gyro
        self.attitude = _rotate(self.attitude, r.delta_angle / self.Te, self.Te)
        # The IMU's velocity increment holds gravity's reaction too: take it off with the
        # attitude. a: the mean acceleration over the step, hull frame [m/s^2].
        a = r.delta_velocity / self.Te - self.attitude.T @ GRAVITY_REACTION
        self.velocity = self.velocity + self.Te * (a - _cross(omega, self.velocity))
        if r.dvl_fresh:  # a ping: blend it in, its lever arm at the ping's rate
            v_dvl = self.R_dvl @ r.dvl - _cross(r.dvl_gyro, self.l_dvl)
            self.velocity += self.k_velocity * (v_dvl - self.velocity)
        nav = self.navigation.update(omega, r.dvl, r.position_fix, velocity=self.velocity,
                                     delta_yaw=r.delta_angle[2])
        v_g = self.velocity + _cross(omega, self.l_gimbal)
        c, s = math.cos(r.encoder), math.sin(r.encoder)
        raw = (-c * v_g[1] + s * v_g[0]) / self.distance
        self._raw += self.k_rate * (raw - self._raw)
        self._power += self.k_power * (self._raw**2 - self._power)
        # Shrink by what of the rate's power is the sensors' noise (a Wiener gain): a
        # still hull's feed-forward would only turn the gimbal by that noise.
        rate = self._raw * max(0.0, 1.0 - self.rate_noise**2 / max(self._power, 1e-30))
        accel = (rate - self.los.rate) / self.Te if self.k else 0.0
        bearing = self.los.bearing + self.Te * (rate - float(omega[2]))
        bearing += self.k_bearing * math.remainder(self._nav_bearing(nav) - bearing,
                                                   2 * math.pi)
        self.los = LineOfSight(rate, accel, float(omega[2]), bearing)
        if self.station_keeping:
            alpha = (omega - self._omega) / self.Te if self.k else np.zeros(3)
            measured = self.mass * np.array([*a, alpha[1], alpha[2]]) - self.thrust
            self.load += min(1.0, self.Te / self.gains.observer_time) * (measured - self.load)
            self.thrust = self.world.set_thrust(
                self._thrust(nav.position, -r.depth, nav.heading, omega) - self.load)
        self._omega = omega
        self.k += 1
        return self.los

    def _nav_bearing(self, nav) -> float:
        """The LED's bearing in the hull's frame from the navigated pose, less the
        start's [rad]."""
        c, s = math.cos(nav.heading), math.sin(nav.heading)
        lx, ly = self.l_gimbal[0], self.l_gimbal[1]
        hinge = nav.position + np.array([c * lx - s * ly, s * lx + c * ly])
        dx, dy = self.led - hinge
        return math.remainder(math.atan2(dy, dx) - nav.heading - self._bearing0,
                              2 * math.pi)

    def _thrust(self, position: np.ndarray, height: float, heading: float,
                omega: np.ndarray) -> np.ndarray:
        """Surge, sway, heave [N], pitch and yaw [N m] of the PD that holds the home pose
        (hull frame), from the navigated horizontal ``position`` [m], ``height`` above
        the start [m] (the pressure sensor), ``heading`` [rad], the attitude and the
        gyro's ``omega`` [rad/s]."""
        g = self.gains
        c, s = math.cos(heading), math.sin(heading)
        dp = position - self.home[0]
        pitch = math.asin(max(-1.0, min(1.0, -self.attitude[2, 0])))
        err = np.array([c * dp[0] + s * dp[1], -s * dp[0] + c * dp[1], height, pitch,
                        math.remainder(heading - self.home[1], 2 * math.pi)])
        rate = np.array([*self.velocity, omega[1], omega[2]])
        kp = np.array([g.kp, g.kp, g.kp, g.kp_pitch, g.kp_yaw])
        kd = np.array([g.kd, g.kd, g.kd, g.kd_pitch, g.kd_yaw])
        return -kp * err - kd * rate
