"""The vehicle: its navigation, its station keeping on the thrusters, and the line of
sight it measures for the gimbal.

Once per control step (:func:`ledsim.physics.tick.prepare`), :meth:`Vehicle.act`:

1. reads its sensors with their noise (:class:`~ledsim.physics.nav_sensors.NavigationSensor`);
2. navigates, starting from the known start, with an aided inertial navigation system
   (:class:`~observer.navigation.ins.AidedINS`, an error-state Kalman filter): the IMU's strapdown
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
   it, anchored on the navigated pose
   (:class:`~observer.navigation.line_of_sight.LineOfSightFilter`);
4. keeps station (unless told not to): a disturbance observer estimates the water's
   force and torque from the accelerometer and gyro (a fast one and a slow twin), the
   thrusters cancel it, and a soft PD on the navigated pose holds the home pose (surge,
   sway, heave, pitch, yaw; each in the hull's frame, within the thrusters' limits of
   the MJCF). Each acts only on what stands out of its own noise (the INS's covariance,
   the IMU's figures): a hull in still water stays still. It never reads the true pose
   after the start.

:meth:`Vehicle.stacked` makes one vehicle object of the vehicles of N worlds (each
started as its own): :meth:`Vehicle.act_rows` then steps them all in one pass, each
row's numbers those its own vehicle gives (:class:`~observer.rows.Rows`).
"""

from __future__ import annotations

import math

import numpy as np

from ledsim.agent.guidance import Mission, PathReference, led_in_start_frame
from ledsim.agent.keeping import StationKeeper, StationKeeping
from ledsim.agent.vehicle_frame import hull_frame, led_bearing
from ledsim.agent.vehicle_row import VehicleRow, target_of
from ledsim.constants import GRAVITY, NavigationNoise
from ledsim.physics.nav_sensors import NavigationReading, NavigationSensor
from ledsim.physics.scene import transmitter_rise
from ledsim.physics.world import LinkWorld
from observer.navigation.ins import FIX_GATE, AidedINS, InertialNoise, InsState
from observer.navigation.line_of_sight import LineOfSight, LineOfSightFilter
from observer.rows import Rows
from observer.rows import matvec as _mv

__all__ = ["LineOfSight", "StationKeeping", "Vehicle", "inertial_noise"]


#: The nearest range [m] a moving vehicle's line of sight and filters take (a mission
#: keeps 1 m off the LED: loop/validation.py).
MIN_RANGE = 0.5


def inertial_noise(n: NavigationNoise) -> InertialNoise:
    """What the navigation filter is told of the sensors: their datasheet figures."""
    return InertialNoise(n.gyro_noise_density, n.gyro_bias_instability, n.gyro_bias_time,
                         n.accel_noise_density, n.accel_bias_instability,
                         n.accel_bias_time, n.dvl_noise, n.depth_noise,
                         n.magnetometer_noise)


class Vehicle(Rows):
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

    ROW_ARRAYS = ("l_gimbal", "led", "_bearing0", "_surface", "_home_position",
                  "_home_heading")
    ROW_LISTS = ("worlds", "paths")
    PARTS = ("sensor", "ins", "keeper", "sight")

    def __init__(self, world: LinkWorld, Te: float, seed: int, distance: float,
                 station_keeping: bool = True, noise: NavigationNoise | None = None,
                 gains: StationKeeping | None = None, rate_time: float = 0.05,
                 bearing_time: float = 2.0, reanchor_rate: float = 3.0,
                 reanchor_time: float = 1.0, reanchor_bearing_time: float = 0.2,
                 mission: Mission | None = None):
        self.single, self.n = True, 1
        self.worlds, self.Te, self.distance = [world], Te, distance
        self.sensor = NavigationSensor(world, Te, seed, noise)
        self.station_keeping = station_keeping and world.ids.thrusters is not None
        self.gains = gains = gains or StationKeeping()
        self.R_dvl, self.l_dvl = world.site_in_hull("dvl")
        l_gimbal = world.gimbal_in_hull()
        self.l_gimbal = l_gimbal[None]
        n = self.sensor.noise
        start = InsState(world.hull_pos.copy(), world.hull_velocity()[3:].copy(),
                         world.hull_rotation, np.zeros(3), np.zeros(3))
        magnetic = world.magnetic_field if world.ids.magnetometer is not None else None
        self.ins = AidedINS(Te, start, inertial_noise(n), GRAVITY, self.R_dvl, self.l_dvl,
                            magnetic, history=int(round(5.0 / Te)) + 2)
        surface = world.hull_pos[2]  # the depth sensor's zero: the start's depth
        home = (world.hull_pos[:2].copy(), world.hull_yaw)
        self._surface, self._home_position = np.array([surface]), home[0][None]
        self._home_heading = np.array([home[1]])
        self.keeper = StationKeeper(world, Te, gains, n, home, surface) \
            if self.station_keeping else None
        # A mission's target from the start pose (agent/guidance.py; None: a station)
        self.paths = [None if mission is None or self.keeper is None else
                      PathReference(mission, home[0], home[1])]
        self._reading: NavigationReading | None = None
        # The LOS rate's noise [rad/s] from the sensors' figures: the DVL's through the
        # navigation's velocity (about a ping's noise over the pings of 0.3 s), the
        # gyro's through the gimbal's lever arm, then the low-pass over rate_time.
        dvl = n.dvl_noise**2 / (2.0 * 0.3 * n.dvl_rate)
        lever2 = float(l_gimbal[0]**2 + l_gimbal[1]**2)
        gyro = n.gyro_noise_density**2 / (2 * Te) * lever2
        rate_noise = math.sqrt(dvl + gyro * Te / (2 * rate_time)) / distance
        self.sight = LineOfSightFilter(Te, distance, rate_noise, rate_time, bearing_time,
                                       reanchor_rate, reanchor_time, reanchor_bearing_time)
        # Where the start put the LED: ahead of the hinge along the hull's axis, the
        # slant distance d less the LED's rise, and to the side (physics/scene.py).
        R0 = world.hull_rotation
        hinge0 = world.hull_pos[:2] + (R0 @ l_gimbal)[:2]
        cfg = world.config
        self._rise = transmitter_rise(cfg.depth, cfg.transmitter_depth, distance)
        ahead, lateral = led_in_start_frame(distance, self._rise, cfg.led_lateral_offset)
        x_dir = R0[:2, 0] / np.linalg.norm(R0[:2, 0])
        self.led = (hinge0 + ahead * x_dir + lateral * np.array([-x_dir[1], x_dir[0]]))[None]
        self._bearing0 = np.zeros(1)
        self._bearing0 = led_bearing(self.ins.states, self.l_gimbal, self.led)

    @classmethod
    def stacked(cls, items):
        out = super().stacked(items)
        for part in cls.PARTS:
            parts = [getattr(i, part) for i in items]
            setattr(out, part, None if parts[0] is None else type(parts[0]).stacked(parts))
        # each vehicle's reading of its start (a pan-tilt's first step reads its gyro)
        readings = [i._reading for i in items]
        out._reading = None if any(r is None for r in readings) else \
            NavigationReading.stacked(readings)
        return out

    def put(self, row: int, item) -> None:
        super().put(row, item)
        for part in self.PARTS:
            if getattr(self, part) is not None:
                getattr(self, part).put(row, getattr(item, part))

    # -- one vehicle's view ------------------------------------------------------------------

    @property
    def world(self) -> LinkWorld:
        return self.worlds[0]

    @property
    def reading(self) -> NavigationReading | None:
        """The (first) vehicle's readings at its last step."""
        r = self._reading
        return None if r is None or not self.single else r.row(0)

    @property
    def surface(self) -> float:
        return float(self._surface[0])

    @property
    def home(self) -> tuple[np.ndarray, float]:
        """The station: horizontal position [m] (2,) and heading [rad]."""
        return self._home_position[0], float(self._home_heading[0])

    @property
    def range(self) -> float:
        """The LED's range from the gimbal's hinge by the navigated pose [m] (the
        told distance unless a mission moves the vehicle)."""
        return float(self.sight.ranges[0])

    @property
    def target(self) -> np.ndarray:
        """Where the vehicle is told to be: its keeper's home, x, y and the depth
        sensor's zero's height [m] (3,) (a mission's target; the station otherwise)."""
        return target_of(self, 0)

    @property
    def navigation(self) -> InsState:
        """The navigation's estimate (:class:`~observer.navigation.ins.InsState`)."""
        return self.ins.state

    @property
    def navigated_position(self) -> np.ndarray:
        """The navigation's position [m] (:attr:`navigation`'s)."""
        return self.ins.state.position

    @property
    def velocity(self) -> np.ndarray:
        """The hull's velocity at the IMU in its own frame, navigated [m/s]."""
        s = self.ins.state
        return s.attitude.T @ s.velocity

    @property
    def los(self) -> LineOfSight:
        """What the vehicle measured of the line of sight at its last step."""
        return self.sight.los

    def row(self, i: int) -> VehicleRow:
        """Vehicle ``i`` of a stacked vehicle, as one run reads it."""
        return VehicleRow(self, i)

    # -- the step ----------------------------------------------------------------------------

    def act(self, t: float) -> LineOfSight | None:
        """Sense, navigate, measure the line of sight and drive the thrusters at ``t``
        [s] (every vehicle of a stacked one); the (first) vehicle's line of sight."""
        self.act_rows(t)
        return self.los if self.single else None

    def act_rows(self, t) -> None:
        """One step of every vehicle at ``t`` [s] (one time, or one per vehicle)."""
        r = self._reading = self.sensor.read_rows()
        ins = self.ins
        ins.propagate_rows(r.delta_angle, r.delta_velocity)
        if r.dvl_fresh.any():
            rows = np.flatnonzero(r.dvl_fresh)
            ins.dvl_rows(rows, r.dvl[rows], r.dvl_gyro[rows])
        ins.depth_rows(r.depth, self._surface)
        if r.magnetometer is not None:
            rows = np.flatnonzero(~np.isnan(r.magnetometer[:, 0]))
            ins.magnetometer_rows(rows, r.magnetometer[rows])
        if not np.isnan(r.fix_time).all():
            rows = np.flatnonzero(~np.isnan(r.fix_time))
            now = t[rows] if np.ndim(t) else t
            ins.position_rows(rows, r.position_fix[rows], r.fix_std[rows],
                              now - r.fix_time[rows], FIX_GATE)
        nav = ins.states
        if self.paths[0] is not None:
            self._follow(t, nav)
        omega, a, velocity, v_g, nav_bearing = hull_frame(r, nav, self)
        self.sight.update_rows(v_g, r.encoder, omega[:, 2], nav_bearing)
        if self.keeper is not None:
            self.keeper.act_rows(nav, ins.Ps, velocity, omega, a)

    def _follow(self, t, nav: InsState) -> None:
        """Move each keeper's home to its mission's target at ``t`` [s], and tell the
        line of sight the range the navigation puts the LED at."""
        k = self.keeper
        for i, path in enumerate(self.paths):
            position, velocity, heading = path.at(float(t[i] if np.ndim(t) else t))
            k.home_position[i], k.home_velocity[i], k.home_heading[i] = \
                position, velocity, heading
        hinge = nav.position[:, :2] + _mv(nav.attitude, self.l_gimbal)[:, :2]
        level = np.hypot(*(self.led - hinge).T)
        self.sight.ranges = np.maximum(np.hypot(level, self._rise), MIN_RANGE)
