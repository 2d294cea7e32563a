"""The vehicle: its navigation, its station keeping on the thrusters, and the line of
sight it measures for the gimbal.

Once per control step (:func:`ledsim.physics.tick.prepare`), :meth:`Vehicle.act`:

1. reads its sensors with their noise (:class:`~ledsim.physics.navigation.NavigationSensor`);
2. navigates, starting from the known start, with an aided inertial navigation system
   (:class:`~observer.ins.AidedINS`, an error-state Kalman filter): the IMU's strapdown
   outputs integrated, corrected by the DVL's pings, the depth sensor, the
   magnetometer (the heading reference) and the acoustic fixes (late ones where they
   were measured, outliers refused by a gate). It levels the attitude against gravity
   and estimates the gyro's and accelerometer's biases, so its error stays bounded;
3. measures the line-of-sight rate at the receiver, what the hull's motion does to the
   LED's bearing (the transmitter's own motion is unknown to it)::

       v_g  = v + omega x l_g                 the gimbal's velocity, hull frame [m/s]
       u    = (cos q, sin q)                  the receiver's axis (encoder q) ~ the LOS
       w    = (u x (-v_g))_z / d              the LOS rate [rad/s]

   with d the link distance the run is told (``--distance``): sway enters the bearing
   through d, so a wrong d scales this feed-forward, and the photodiodes correct the
   rest. w is low-passed and shrunk by the share of its power that is the sensors'
   noise (a Wiener gain from the noise figures), so a still hull's feed-forward does not
   turn the gimbal by the DVL's noise; the LED's bearing in the hull's frame integrates
   it, anchored on the navigated pose (:class:`~observer.line_of_sight.LineOfSightFilter`);
4. keeps station (unless told not to): a disturbance observer estimates the water's
   force and torque from the accelerometer and gyro (a fast one and a slow twin), the
   thrusters cancel it, and a soft PD on the navigated pose holds the home pose (surge,
   sway, heave, pitch, yaw; each in the hull's frame, within the thrusters' limits of
   the MJCF). Each acts only on what stands out of its own noise (the INS's covariance,
   the IMU's figures): a hull in still water stays still. It never reads the true pose
   after the start.
"""

from __future__ import annotations

import math

import numpy as np

from observer.ins import AidedINS, InertialNoise, InsState
from observer.line_of_sight import LineOfSight, LineOfSightFilter

from ..config import GRAVITY, NavigationNoise
from .keeping import StationKeeper, StationKeeping
from .navigation import GRAVITY_REACTION, NavigationReading, NavigationSensor
from .world import LinkWorld

__all__ = ["LineOfSight", "StationKeeping", "Vehicle", "inertial_noise"]


def inertial_noise(n: NavigationNoise) -> InertialNoise:
    """What the navigation filter is told of the sensors: their datasheet figures."""
    return InertialNoise(n.gyro_noise_density, n.gyro_bias_instability, n.gyro_bias_time,
                         n.accel_noise_density, n.accel_bias_instability,
                         n.accel_bias_time, n.dvl_noise, n.depth_noise,
                         n.magnetometer_noise)


def _cross(a, b) -> np.ndarray:
    """a x b of two 3-vectors (numpy's formula in plain floats: np.cross costs 30 us)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


class Vehicle:
    """The AUV's navigation and station keeping on ``world`` (see the module docstring).

    Args:
        world: the scene (with the vehicle's sensors and thrusters).
        Te: control period [s].
        seed: the run's seed (the sensors' noise).
        distance: the link distance the run is told [m] (the LOS rate's d).
        station_keeping: drive the thrusters (False: they stay idle, the hull drifts).
        noise: the sensors' noise figures (None: the defaults).
        gains: the station keeping's gains (None: the defaults).
        rate_time: time constant of the LOS rate's low-pass [s].
        bearing_time: time constant of the bearing's pull towards the navigation's [s].
        reanchor_rate, reanchor_time, reanchor_bearing_time: once the measured LOS rate
            exceeds ``reanchor_rate`` [rad/s] (a hull strike's: currents and waves stay
            below 1 rad/s), the pull's time constant is ``reanchor_bearing_time`` [s] for
            the next ``reanchor_time`` [s]. After a 3 rad/s hull kick, 8 seeds: the
            KKL's availability 0.739 -> 0.855 (the oracle's 0.847), its recovery 2.35 ->
            0.61 s; the EKF's 0.761 -> 0.850.
    """

    def __init__(self, world: LinkWorld, Te: float, seed: int, distance: float,
                 station_keeping: bool = True, noise: NavigationNoise | None = None,
                 gains: StationKeeping | None = None, rate_time: float = 0.05,
                 bearing_time: float = 2.0, reanchor_rate: float = 3.0,
                 reanchor_time: float = 1.0, reanchor_bearing_time: float = 0.2):
        self.world, self.Te, self.distance = world, Te, distance
        self.sensor = NavigationSensor(world, Te, seed, noise)
        self.station_keeping = station_keeping and world.ids.thrusters is not None
        self.gains = gains = gains or StationKeeping()
        self.R_dvl, self.l_dvl = world.site_in_hull("dvl")
        self.l_gimbal = world.gimbal_in_hull()
        n = self.sensor.noise
        start = InsState(world.hull_pos.copy(), world.hull_velocity()[3:].copy(),
                         world.hull_rotation, np.zeros(3), np.zeros(3))
        magnetic = world.magnetic_field if world.ids.magnetometer is not None else None
        self.ins = AidedINS(Te, start, inertial_noise(n), GRAVITY, self.R_dvl, self.l_dvl,
                            magnetic, history=int(round(5.0 / Te)) + 2)
        self.surface = world.hull_pos[2]  # the depth sensor's zero: the start's depth
        self.home = (world.hull_pos[:2].copy(), world.hull_yaw)
        self.keeper = StationKeeper(world, Te, gains, n, self.home, self.surface) \
            if self.station_keeping else None
        self.reading: NavigationReading | None = None
        # The LOS rate's noise [rad/s] from the sensors' figures: the DVL's through the
        # navigation's velocity (about a ping's noise over the pings of 0.3 s), the
        # gyro's through the gimbal's lever arm, then the low-pass over rate_time.
        dvl = n.dvl_noise**2 / (2.0 * 0.3 * n.dvl_rate)
        lever2 = float(self.l_gimbal[0]**2 + self.l_gimbal[1]**2)
        gyro = n.gyro_noise_density**2 / (2 * Te) * lever2
        rate_noise = math.sqrt(dvl + gyro * Te / (2 * rate_time)) / distance
        self.sight = LineOfSightFilter(Te, distance, rate_noise, rate_time, bearing_time,
                                       reanchor_rate, reanchor_time, reanchor_bearing_time)
        # Where the start put the LED: d ahead of the hinge along the hull's axis.
        R0 = world.hull_rotation
        hinge0 = world.hull_pos[:2] + (R0 @ self.l_gimbal)[:2]
        self.led = hinge0 + distance * R0[:2, 0] / np.linalg.norm(R0[:2, 0])
        self._bearing0 = self._led_in_hull(self.ins.state)[0]

    @property
    def navigation(self) -> InsState:
        """The navigation's estimate (:class:`~observer.ins.InsState`)."""
        return self.ins.state

    @property
    def velocity(self) -> np.ndarray:
        """The hull's velocity at the IMU in its own frame, navigated [m/s]."""
        s = self.ins.state
        return s.attitude.T @ s.velocity

    def navigate(self, r: NavigationReading, t: float) -> InsState:
        """Feed the INS this step's readings ``r`` at time ``t`` [s]."""
        ins = self.ins
        ins.propagate(r.delta_angle, r.delta_velocity)
        if r.dvl_fresh:
            ins.update_dvl(r.dvl, r.dvl_gyro)
        ins.update_depth(r.depth, self.surface)
        if r.magnetometer is not None:
            ins.update_magnetometer(r.magnetometer)
        if r.position_fix is not None:
            ins.update_position(r.position_fix, r.fix_std, delay=t - r.fix_time)
        return ins.state

    def act(self, t: float) -> LineOfSight:
        """Sense, navigate, measure the line of sight and drive the thrusters at ``t``."""
        r = self.reading = self.sensor.read()
        nav = self.navigate(r, t)
        omega = r.gyro - nav.gyro_bias
        # a: the mean acceleration over the step, hull frame [m/s^2]: the velocity
        # increment less its bias and gravity's reaction.
        a = r.delta_velocity / self.Te - nav.accel_bias \
            - nav.attitude.T @ GRAVITY_REACTION
        velocity = self.velocity
        v_g = velocity + _cross(omega, self.l_gimbal)
        nav_bearing = self._led_in_hull(nav)[0] - self._bearing0
        self.sight.update(v_g, r.encoder, float(omega[2]), nav_bearing)
        if self.keeper is not None:
            self.keeper.act(nav, self.ins.P, velocity, omega, a)
        return self.los

    @property
    def los(self) -> LineOfSight:
        """What the vehicle measured of the line of sight at its last step."""
        return self.sight.los

    def _led_in_hull(self, nav: InsState) -> tuple[float, float]:
        """Where the LED is from the gimbal's hinge, by the navigated pose: its bearing
        in the hull's frame [rad] and its range [m] (the LED where the start put it)."""
        heading = nav.heading
        c, s = math.cos(heading), math.sin(heading)
        lx, ly = self.l_gimbal[0], self.l_gimbal[1]
        dx = self.led[0] - (nav.position[0] + c * lx - s * ly)
        dy = self.led[1] - (nav.position[1] + s * lx + c * ly)
        return math.remainder(math.atan2(dy, dx) - heading, 2 * math.pi), math.hypot(dx, dy)
