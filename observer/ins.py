"""An aided inertial navigation system: the error-state Kalman filter (ESKF) of a vehicle
with an IMU, a DVL, a depth sensor, a magnetometer and acoustic position fixes.

The nominal state is integrated from the IMU's strapdown outputs (the delta angle and
delta velocity over each period Te); a Kalman filter carries the 15 errors of that
integration and corrects it with each aiding sensor, as in Sola, "Quaternion kinematics
for the error-state Kalman filter" (2017), and Farrell, "Aided Navigation" (2008):

    nominal   R' = R Exp(dth - bg Te)                attitude (body to world)
              v' = v + R' (dv - ba Te) - Te g_up     velocity, world frame [m/s]
              p' = p + Te (v + v') / 2               position, world frame [m]
              bg, ba: the gyro's and accelerometer's biases (Gauss-Markov)
    error     dx = (dp, dv, dtheta, dbg, dba)        R_true = R Exp(dtheta) (body frame)

The delta velocity is taken in the IMU's frame at the end of the period (as the
simulated IMU gives it). Gravity levels the attitude through the aiding: a tilt error
dtheta makes the integrated velocity grow by g x dtheta, which the DVL sees, so tilt and
the gyro's horizontal biases are estimated (the accelerometer's horizontal bias is then
only separable from tilt while the vehicle accelerates, which the covariance records).
The magnetometer gives the heading and the gyro's vertical bias.

Aiding (each an update of the error state, then injected into the nominal state):

=============  =========================================  =============================
sensor         measurement model                          noise
=============  =========================================  =============================
DVL            R_dvl^T (R^T v + (w - bg) x l_dvl)         per ping, each axis
depth          depth0 - p_z (positive down)               per reading
magnetometer   R^T m_world                                per reading, each axis
position fix   p at the time it was measured (``delay``   per fix (may grow with range);
               s ago, from the INS's own displacement)    outliers rejected by a gate
=============  =========================================  =============================

Numpy only, any vehicle: ledsim's vehicle (``ledsim.physics.vehicle``) feeds it.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from .rotations import rotation_exp, rotation_log, skew

#: Error-state blocks: position, velocity, attitude, gyro bias, accelerometer bias.
P, V, TH, BG, BA = (slice(0, 3), slice(3, 6), slice(6, 9), slice(9, 12), slice(12, 15))
N_ERROR = 15
#: chi-square(3) at 1 - 1e-4: a fix whose normalised innovation exceeds it is an outlier.
FIX_GATE = 21.11


@dataclass(frozen=True)
class InertialNoise:
    """What the filter knows of its sensors' noise (SI units).

    Attributes:
        gyro_noise_density: angle random walk [rad/s/sqrt(Hz)].
        gyro_bias_instability: stationary spread of the gyro bias [rad/s].
        gyro_bias_time: its correlation time [s].
        accel_noise_density: velocity random walk [m/s^2/sqrt(Hz)].
        accel_bias_instability: stationary spread of the accelerometer bias [m/s^2].
        accel_bias_time: its correlation time [s].
        dvl_noise: one DVL ping's velocity noise, each axis [m/s].
        depth_noise: one depth reading's noise [m].
        magnetometer_noise: one magnetometer reading's noise, each axis [field unit].
    """

    gyro_noise_density: float
    gyro_bias_instability: float
    gyro_bias_time: float
    accel_noise_density: float
    accel_bias_instability: float
    accel_bias_time: float
    dvl_noise: float
    depth_noise: float
    magnetometer_noise: float


@dataclass
class InsState:
    """The filter's estimate: position (3,) [m] and velocity (3,) [m/s] in the world
    frame (z up), attitude (3x3, body to world), gyro bias (3,) [rad/s] and accelerometer
    bias (3,) [m/s^2]."""

    position: np.ndarray
    velocity: np.ndarray
    attitude: np.ndarray
    gyro_bias: np.ndarray
    accel_bias: np.ndarray

    @property
    def heading(self) -> float:
        """Yaw of the body's x axis about world z [rad]."""
        return math.atan2(self.attitude[1, 0], self.attitude[0, 0])

    @property
    def pitch(self) -> float:
        """Pitch of the body's x axis above the horizontal, nose down positive [rad]."""
        return math.asin(max(-1.0, min(1.0, -self.attitude[2, 0])))

    def copy(self) -> InsState:
        return InsState(self.position.copy(), self.velocity.copy(), self.attitude.copy(),
                        self.gyro_bias.copy(), self.accel_bias.copy())


class AidedINS:
    """The error-state Kalman filter of the module docstring.

    Args:
        Te: IMU period [s].
        state: the start's estimate (:class:`InsState`).
        noise: the sensors' noise (:class:`InertialNoise`).
        gravity: gravity's magnitude [m/s^2] (world z up).
        dvl_rotation: the DVL's frame in the body frame (3x3; None: the body frame).
        dvl_lever: the DVL's position from the IMU in the body frame [m], (3,) (None:
            at the IMU).
        magnetic_field: the field in the world frame (3,) [field unit] (None: no
            magnetometer).
        initial_std: standard deviations of the start's position [m], velocity [m/s]
            and attitude [rad] errors; the biases start at their stationary spread.
        history: how many periods of displacement it keeps for late fixes.
    """

    def __init__(self, Te: float, state: InsState, noise: InertialNoise, gravity: float,
                 dvl_rotation=None, dvl_lever=None, magnetic_field=None,
                 initial_std: tuple[float, float, float] = (1e-3, 1e-3, 1e-3),
                 history: int = 600):
        self.Te, self.noise, self.gravity = Te, noise, gravity
        self.state = state.copy()
        self.R_dvl = np.eye(3) if dvl_rotation is None else np.asarray(dvl_rotation, float)
        self.l_dvl = np.zeros(3) if dvl_lever is None else np.asarray(dvl_lever, float)
        self.field = None if magnetic_field is None else np.asarray(magnetic_field, float)
        n = noise
        sp, sv, sa = initial_std
        self.P = np.diag(np.r_[[sp**2] * 3, [sv**2] * 3, [sa**2] * 3,
                               [n.gyro_bias_instability**2] * 3,
                               [n.accel_bias_instability**2] * 3])
        self._decay_g = math.exp(-Te / n.gyro_bias_time)
        self._decay_a = math.exp(-Te / n.accel_bias_time)
        qa = n.accel_noise_density**2 * Te  # velocity noise per period [m^2/s^2]
        Q = np.zeros((N_ERROR, N_ERROR))
        Q[P, P] = np.eye(3) * qa * Te**2 / 4  # half the period's velocity noise moves p
        Q[P, V] = Q[V, P] = np.eye(3) * qa * Te / 2
        Q[V, V] = np.eye(3) * qa
        Q[TH, TH] = np.eye(3) * n.gyro_noise_density**2 * Te
        Q[BG, BG] = np.eye(3) * n.gyro_bias_instability**2 * (1 - self._decay_g**2)
        Q[BA, BA] = np.eye(3) * n.accel_bias_instability**2 * (1 - self._decay_a**2)
        self.Q = Q
        self._F = np.eye(N_ERROR)
        self._F[BG, BG] *= self._decay_g
        self._F[BA, BA] *= self._decay_a
        self._F[P, V] = np.eye(3) * Te
        self._F[TH, BG] = -np.eye(3) * Te
        # The INS's own displacement since the start, per period: a late fix is compared
        # with where the INS was then, p(now) less the displacement since.
        self.displacement = np.zeros(3)
        self._history: deque[np.ndarray] = deque(maxlen=history)
        self.rejected_fixes = 0  # fixes the outlier gate refused

    # -- propagation -----------------------------------------------------------------------

    def propagate(self, delta_angle, delta_velocity) -> InsState:
        """One IMU period: the delta angle (3,) [rad] and delta velocity (3,) [m/s] in the
        body frame (specific force, the end of the period's frame)."""
        s, Te = self.state, self.Te
        dth = np.asarray(delta_angle, dtype=float) - s.gyro_bias * Te
        dv = np.asarray(delta_velocity, dtype=float) - s.accel_bias * Te
        turn = rotation_exp(dth)
        R = s.attitude @ turn
        v = s.velocity + R @ dv
        v[2] -= Te * self.gravity
        step = 0.5 * Te * (s.velocity + v)
        s.position = s.position + step
        s.velocity, s.attitude = v, R
        self.displacement = self.displacement + step
        self._history.append(self.displacement)
        # The error's transition (first order in Te).
        F = self._F
        Rdv = R @ skew(dv)
        F[V, TH] = -Rdv @ turn.T
        F[V, BG] = Rdv * Te
        F[V, BA] = -R * Te
        F[P, TH] = 0.5 * Te * F[V, TH]
        F[P, BG] = 0.5 * Te * F[V, BG]
        F[P, BA] = 0.5 * Te * F[V, BA]
        F[TH, TH] = turn.T
        self.P = F @ self.P @ F.T + self.Q
        return s

    # -- aiding ------------------------------------------------------------------------------

    def _correct(self, residual: np.ndarray, H: np.ndarray, Rm: np.ndarray,
                 gate: float | None = None) -> float:
        """The Kalman update with ``residual`` (measured less predicted), its Jacobian
        ``H`` on the error state and its noise ``Rm``; refused (the state untouched) when
        the normalised innovation squared exceeds ``gate``. Returns that NIS."""
        PHt = self.P @ H.T
        S = H @ PHt + Rm
        Sinv = np.linalg.inv(S)
        nis = float(residual @ Sinv @ residual)
        if gate is not None and nis > gate:
            return nis
        K = PHt @ Sinv
        dx = K @ residual
        IKH = np.eye(N_ERROR) - K @ H
        self.P = IKH @ self.P @ IKH.T + K @ Rm @ K.T
        self._inject(dx)
        return nis

    def _inject(self, dx: np.ndarray) -> None:
        s = self.state
        s.position = s.position + dx[P]
        s.velocity = s.velocity + dx[V]
        s.attitude = s.attitude @ rotation_exp(dx[TH])
        s.gyro_bias = s.gyro_bias + dx[BG]
        s.accel_bias = s.accel_bias + dx[BA]

    def update_dvl(self, velocity, gyro) -> float:
        """A DVL ping: the velocity (3,) [m/s] in the DVL's frame, and the gyro's reading
        (3,) [rad/s] at the ping (for its lever arm). Returns the NIS."""
        s = self.state
        omega = np.asarray(gyro, dtype=float) - s.gyro_bias
        v_body = s.attitude.T @ s.velocity
        lever = skew(self.l_dvl)
        predicted = self.R_dvl.T @ (v_body - lever @ omega)
        H = np.zeros((3, N_ERROR))
        H[:, V] = self.R_dvl.T @ s.attitude.T
        H[:, TH] = self.R_dvl.T @ skew(v_body)
        H[:, BG] = self.R_dvl.T @ lever
        n = self.noise
        gyro_var = n.gyro_noise_density**2 / (2 * self.Te)
        Rm = np.eye(3) * n.dvl_noise**2 + gyro_var * (lever @ lever.T)
        return self._correct(np.asarray(velocity, dtype=float) - predicted, H, Rm)

    def update_depth(self, depth: float, surface: float) -> None:
        """A depth reading [m] (positive down) below the height ``surface`` [m] where
        depth is 0 (a scalar update on p_z)."""
        r = float(depth) - (surface - self.state.position[2])
        ph = self.P[:, 2].copy()  # P H^T with H = -e_z, sign apart
        S = ph[2] + self.noise.depth_noise**2
        self.P -= np.outer(ph, ph) / S  # the optimal gain's update, symmetric as it is
        self._inject(ph * (-r / S))

    def update_magnetometer(self, field) -> float:
        """A magnetometer reading (3,) in the body frame [field unit]. Returns the NIS."""
        if self.field is None:
            raise ValueError("this INS has no magnetic field to compare a reading with")
        s = self.state
        predicted = s.attitude.T @ self.field
        H = np.zeros((3, N_ERROR))
        H[:, TH] = skew(predicted)
        Rm = np.eye(3) * self.noise.magnetometer_noise**2
        return self._correct(np.asarray(field, dtype=float) - predicted, H, Rm)

    def update_position(self, fix, std: float, delay: float = 0.0,
                        gate: float | None = FIX_GATE) -> bool:
        """An acoustic fix of the position (3,) [m], world frame, with standard deviation
        ``std`` [m] each axis, measured ``delay`` [s] ago. Returns whether it was taken:
        a fix whose normalised innovation exceeds ``gate`` is an outlier and refused
        (None: every fix is taken)."""
        back = min(int(round(delay / self.Te)), len(self._history) - 1)
        since = (self.displacement - self._history[-1 - back]) if back > 0 else 0.0
        then = self.state.position - since
        H = np.zeros((3, N_ERROR))
        H[:, P] = np.eye(3)
        nis = self._correct(np.asarray(fix, dtype=float) - then, H, np.eye(3) * std**2, gate)
        taken = gate is None or nis <= gate
        self.rejected_fixes += not taken
        return taken

    # -- reading -----------------------------------------------------------------------------

    def error_of(self, truth: InsState) -> np.ndarray:
        """The error state (15,) of the estimate against ``truth`` (truth less estimate;
        the attitude as R_est^T R_true's rotation vector)."""
        s = self.state
        return np.r_[truth.position - s.position, truth.velocity - s.velocity,
                     rotation_log(s.attitude.T @ truth.attitude),
                     truth.gyro_bias - s.gyro_bias, truth.accel_bias - s.accel_bias]

    def nees(self, truth: InsState) -> float:
        """Normalised estimation error squared of the estimate against ``truth``:
        chi-square with 15 degrees of freedom for a consistent filter."""
        e = self.error_of(truth)
        return float(e @ np.linalg.solve(self.P, e))
