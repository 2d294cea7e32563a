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

Numpy only, any vehicle: ledsim's vehicle (``ledsim.agent.autopilot``) feeds it. One
filter runs one vehicle, or the vehicles of N worlds at once (a state with a leading
axis of N): every row computed as the filter of one computes it (stacked matrix
products run each row through the same BLAS kernel), so a vehicle's navigation does not
depend on the batch it runs in.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from observer import jit
from observer.navigation.ins_aiding import BA, BG, FIX_GATE, N_ERROR, TH, InsAiding, P, V
from observer.navigation.ins_state import InertialNoise, InsState
from observer.navigation.rotations import rotation_exp, rotation_log, skew
from observer.rows import Rows
from observer.rows import matvec as _mv
from observer.rows import transposed as _T

compiled_ins = jit.lazy("observer.navigation.compiled_ins")


class AidedINS(InsAiding, Rows):
    """The error-state Kalman filter of the module docstring.

    Args:
        Te: IMU period [s].
        state: the start's estimate (:class:`InsState`); with a leading axis of N on
            every field, the filters of N vehicles (then ``state``, ``P`` and the
            methods' arguments and results have that axis too).
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
        self.single = np.ndim(state.position) == 1
        st = state.copy()
        if self.single:
            st = InsState(*(x[None] for x in (st.position, st.velocity, st.attitude,
                                               st.gyro_bias, st.accel_bias)))
        self.states, self.n = st, len(st.position)
        self.R_dvl = np.eye(3) if dvl_rotation is None else np.asarray(dvl_rotation, float)
        self.l_dvl = np.zeros(3) if dvl_lever is None else np.asarray(dvl_lever, float)
        self.field = None if magnetic_field is None else np.asarray(magnetic_field, float)
        n = noise
        sp, sv, sa = initial_std
        P0 = np.diag(np.r_[[sp**2] * 3, [sv**2] * 3, [sa**2] * 3,
                           [n.gyro_bias_instability**2] * 3,
                           [n.accel_bias_instability**2] * 3])
        self.Ps = np.repeat(P0[None], self.n, axis=0)
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
        F = np.eye(N_ERROR)
        F[BG, BG] *= self._decay_g
        F[BA, BA] *= self._decay_a
        F[P, V] = np.eye(3) * Te
        F[TH, BG] = -np.eye(3) * Te
        self._F = np.repeat(F[None], self.n, axis=0)
        # The DVL's model: its lever arm's matrix and its noise.
        self._lever = skew(self.l_dvl)
        gyro_var = n.gyro_noise_density**2 / (2 * Te)
        self._R_dvl_noise = np.eye(3) * n.dvl_noise**2 + gyro_var * (self._lever @ self._lever.T)
        # The INS's own displacement since the start, per period: a late fix is compared
        # with where the INS was then, p(now) less the displacement since.
        self.displacements = np.zeros((self.n, 3))
        self._histories = [deque(maxlen=history) for _ in range(self.n)]
        self.rejected = np.zeros(self.n, dtype=int)  # fixes the outlier gate refused

    ROW_ARRAYS = ("Ps", "_F", "displacements", "rejected")
    ROW_LISTS = ("_histories",)
    _STATE = ("position", "velocity", "attitude", "gyro_bias", "accel_bias")

    @classmethod
    def stacked(cls, items):
        out = super().stacked(items)
        out.states = InsState(*(np.concatenate([getattr(i.states, f) for i in items])
                                for f in cls._STATE))
        return out

    def put(self, row: int, item) -> None:
        super().put(row, item)
        for f in self._STATE:
            mine = getattr(self.states, f).copy()
            mine[row] = getattr(item.states, f)[0]
            setattr(self.states, f, mine)

    @property
    def _history(self) -> deque:
        """The displacement history of the (first) vehicle."""
        return self._histories[0]

    # -- one vehicle's view ------------------------------------------------------------------

    def _one(self, rows):
        return rows[0] if self.single else rows

    @property
    def state(self) -> InsState:
        s = self.states
        if not self.single:
            return s
        return InsState(s.position[0], s.velocity[0], s.attitude[0], s.gyro_bias[0],
                        s.accel_bias[0])

    @property
    def P(self) -> np.ndarray:
        """The error covariance (15, 15) ((N, 15, 15) for N vehicles)."""
        return self._one(self.Ps)

    @P.setter
    def P(self, value) -> None:
        self.Ps = np.array(value, dtype=float).reshape(self.Ps.shape)

    @property
    def displacement(self) -> np.ndarray:
        return self._one(self.displacements)

    @property
    def rejected_fixes(self):
        """Fixes the outlier gate refused (one count per vehicle)."""
        return int(self.rejected[0]) if self.single else self.rejected

    def _rows(self, x) -> np.ndarray:
        return np.asarray(x, dtype=float)[None] if self.single else np.asarray(x, float)

    # -- propagation -----------------------------------------------------------------------

    def propagate(self, delta_angle, delta_velocity) -> InsState:
        """One IMU period: the delta angle (3,) [rad] and delta velocity (3,) [m/s] in the
        body frame (specific force, the end of the period's frame)."""
        self.propagate_rows(self._rows(delta_angle), self._rows(delta_velocity))
        return self.state

    def propagate_rows(self, delta_angle: np.ndarray, delta_velocity: np.ndarray) -> None:
        """:meth:`propagate` of every vehicle, (N, 3) each."""
        s, Te = self.states, self.Te
        if jit.enabled():
            s.position, s.velocity, s.attitude, self.Ps, self.displacements = \
                compiled_ins.propagate(s.position, s.velocity, s.attitude, s.gyro_bias,
                                       s.accel_bias, self.Ps, self._F, self.Q,
                                       np.ascontiguousarray(delta_angle, dtype=float),
                                       np.ascontiguousarray(delta_velocity, dtype=float),
                                       Te, self.gravity, self.displacements)
            for h, d in zip(self._histories, self.displacements, strict=True):
                h.append(d)
            return
        dth = delta_angle - s.gyro_bias * Te
        dv = delta_velocity - s.accel_bias * Te
        turn = rotation_exp(dth)
        R = s.attitude @ turn
        v = s.velocity + _mv(R, dv)
        v[:, 2] -= Te * self.gravity
        step = 0.5 * Te * (s.velocity + v)
        s.position = s.position + step
        s.velocity, s.attitude = v, R
        self.displacements = self.displacements + step
        for h, d in zip(self._histories, self.displacements, strict=True):
            h.append(d)
        # The error's transition (first order in Te).
        F = self._F
        Rdv = R @ skew(dv)
        F[:, V, TH] = -Rdv @ _T(turn)
        F[:, V, BG] = Rdv * Te
        F[:, V, BA] = -R * Te
        F[:, P, TH] = 0.5 * Te * F[:, V, TH]
        F[:, P, BG] = 0.5 * Te * F[:, V, BG]
        F[:, P, BA] = 0.5 * Te * F[:, V, BA]
        F[:, TH, TH] = _T(turn)
        self.Ps = F @ self.Ps @ _T(F) + self.Q

    # -- aiding (one vehicle's or every vehicle's reading; InsAiding holds the math) --------

    def _inject(self, dx: np.ndarray) -> None:
        """Correct every vehicle's nominal state by the error ``dx`` (15,) ((N, 15))."""
        self._inject_rows(slice(None), self._rows(dx))

    def _targets(self, rows):
        return np.arange(self.n) if rows is None else np.asarray(rows)

    def update_dvl(self, velocity, gyro, rows=None):
        """A DVL ping: the velocity (3,) [m/s] in the DVL's frame, and the gyro's reading
        (3,) [rad/s] at the ping (for its lever arm); ``rows``: which of N vehicles
        pinged (None: all). Returns the NIS."""
        return self._one(self.dvl_rows(self._targets(rows), self._rows(velocity),
                                       self._rows(gyro)))

    def update_depth(self, depth, surface) -> None:
        """A depth reading [m] (positive down) below the height ``surface`` [m] where
        depth is 0 (a scalar update on p_z); one per vehicle."""
        self.depth_rows(np.asarray(depth, dtype=float).reshape(self.n),
                        np.asarray(surface, dtype=float))

    def update_magnetometer(self, field, rows=None):
        """A magnetometer reading (3,) in the body frame [field unit]; ``rows``: which
        of N vehicles read one (None: all). Returns the NIS."""
        return self._one(self.magnetometer_rows(self._targets(rows), self._rows(field)))

    def update_position(self, fix, std, delay=0.0, gate: float | None = FIX_GATE,
                        rows=None):
        """An acoustic fix of the position (3,) [m], world frame, with standard deviation
        ``std`` [m] each axis, measured ``delay`` [s] ago; ``rows``: which of N vehicles
        got one (None: all). Returns whether it was taken: a fix whose normalised
        innovation exceeds ``gate`` is an outlier and refused (None: every fix is
        taken)."""
        rows = self._targets(rows)
        taken = self.position_rows(rows, self._rows(fix),
                                   np.broadcast_to(np.asarray(std, float), len(rows)),
                                   np.broadcast_to(np.asarray(delay, float), len(rows)),
                                   gate)
        return bool(taken[0]) if self.single else taken

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
