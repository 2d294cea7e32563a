"""MuJoCo ids and addresses of the scene's named parts, and the vehicle's sensors' and
thrusters' names (:mod:`ledsim.physics.scene` builds the scene)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ledsim.constants import LinkConstants
from ledsim.physics.layout import ReceiverLayout


@dataclass(frozen=True)
class SceneIds:
    """MuJoCo ids and addresses of the scene's named parts, read once when it compiles
    (for code that works on MuJoCo's arrays directly: the world batch, the rollouts).

    Attributes:
        hull_body, gimbal_body: body ids of the AUV and of the receiver gimbal.
        photodiode_sites: site ids of the layout's photodiodes, in its order; led_site:
            the LED's site id.
        hinge_qpos, hinge_dof: the first gimbal axis's hinge's address in qpos and in qvel.
        motor: actuator id of the first gimbal axis's motor.
        vehicle_sensors: sensordata addresses of the vehicle's sensors, in the order of
            :data:`VEHICLE_SENSORS` (None: the scene lacks one of them).
        thrusters: actuator ids of the hull's surge, sway, heave, pitch and yaw thrusters
            (None: the scene lacks one of them).
        magnetometer: sensordata address of the IMU's magnetometer, the heading
            reference (None: the scene has none; the navigation then has no heading
            reference).
        usbl_site: site id of the USBL transceiver the acoustic fixes are measured from
            (None: the scene has none; a fix's error then does not grow with range).
        missing_sensors: names of :data:`VEHICLE_SENSORS` the scene lacks.
        axes_qpos, axes_dof, motors, encoders: every axis's hinge address in qpos and
            in qvel, its motor's actuator id and its encoder's sensordata address, in
            the layout's order (the first is ``hinge_qpos``, ``hinge_dof``, ``motor``).
    """

    hull_body: int
    gimbal_body: int
    photodiode_sites: tuple[int, ...]
    led_site: int
    hinge_qpos: int
    hinge_dof: int
    motor: int
    vehicle_sensors: tuple[int, ...] | None = None
    thrusters: tuple[int, ...] | None = None
    magnetometer: int | None = None
    usbl_site: int | None = None
    missing_sensors: tuple[str, ...] = ()
    axes_qpos: tuple[int, ...] = ()
    axes_dof: tuple[int, ...] = ()
    motors: tuple[int, ...] = ()
    encoders: tuple[int, ...] = ()

    @classmethod
    def of(cls, m, layout: ReceiverLayout | None = None) -> SceneIds:
        """The ids of model ``m`` built for the receiver ``layout`` (None: the paper's)."""
        layout = LinkConstants().layout if layout is None else layout
        axes = layout.buildable().axes
        hinges = [m.joint(a.joint) for a in axes]
        sensors = [m.sensor(i).name for i in range(m.nsensor)]
        missing = tuple(n for n in VEHICLE_SENSORS if n not in sensors)
        adr = None if missing else tuple(int(m.sensor(n).adr[0]) for n in VEHICLE_SENSORS)
        actuators = [m.actuator(i).name for i in range(m.nu)]
        thrusters = (tuple(int(m.actuator(n).id) for n in THRUSTERS)
                     if all(n in actuators for n in THRUSTERS) else None)
        mag = int(m.sensor(MAGNETOMETER).adr[0]) if MAGNETOMETER in sensors else None
        sites = [m.site(i).name for i in range(m.nsite)]
        usbl = int(m.site("usbl").id) if "usbl" in sites else None
        qpos = tuple(int(h.qposadr[0]) for h in hinges)
        dof = tuple(int(h.dofadr[0]) for h in hinges)
        motors = tuple(int(m.actuator(a.motor).id) for a in axes)
        encoders = tuple(int(m.sensor(a.encoder).adr[0]) if a.encoder in sensors else -1
                         for a in axes)
        return cls(int(m.body("auv").id), int(m.body("gimbal").id),
                   tuple(int(m.site(p.site).id) for p in layout.photodiodes),
                   int(m.site("led").id), qpos[0], dof[0], motors[0], adr, thrusters, mag,
                   usbl, missing, qpos, dof, motors, encoders)


#: The vehicle's MuJoCo sensors by name: the IMU's gyro and accelerometer, the DVL (a
#: velocimeter), the gimbal's encoder (jointpos) and the acoustic position fix (framepos).
VEHICLE_SENSORS = ("imu_gyro", "imu_accel", "dvl_velocity", "gimbal_encoder",
                   "acoustic_fix")
#: The IMU's magnetometer, the navigation's heading reference (optional in a scene).
MAGNETOMETER = "imu_magnetometer"


#: The hull's thrusters by name: surge, sway and heave forces [N], pitch and yaw
#: torques [N m].
THRUSTERS = ("thruster_surge", "thruster_sway", "thruster_heave", "thruster_pitch",
             "thruster_yaw")


class VehicleMotion(NamedTuple):
    """The noise-free values of the vehicle's sensors at one instant (SI units); of N
    worlds at once (:func:`~ledsim.physics.hull.vehicle_motion_rows`), each field has a
    leading axis of N (``encoder`` (N,)).

    Attributes:
        gyro: hull angular velocity in the IMU frame [rad/s], (3,).
        accel: specific force in the IMU frame [m/s^2], (3,) (from the last physics step).
        dvl: hull velocity at the DVL in its frame [m/s], (3,) (z points down).
        encoder: the gimbal hinge angle [rad].
        position: the IMU's position in the world frame [m], (3,).
        magnetometer: the magnetic field in the IMU frame [T], (3,) (None: the scene
            has no magnetometer).
    """

    gyro: np.ndarray
    accel: np.ndarray
    dvl: np.ndarray
    encoder: float
    position: np.ndarray
    magnetometer: np.ndarray | None = None

