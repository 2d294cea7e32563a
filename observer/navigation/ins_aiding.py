"""The aiding updates of :class:`~observer.navigation.ins.AidedINS`, over the rows of its
vehicles: the Kalman correction with a DVL ping, a depth reading, a magnetometer
reading or an acoustic fix, each for the vehicles ``rows`` that have one this step.
Stacked matrix products and inverses give every row what the filter of one vehicle
computes."""

from __future__ import annotations

import numpy as np

from observer import jit
from observer.navigation.rotations import libm_square, rotation_exp, skew
from observer.rows import matvec as _mv
from observer.rows import transposed as _T

#: Error-state blocks: position, velocity, attitude, gyro bias, accelerometer bias.
P, V, TH, BG, BA = (slice(0, 3), slice(3, 6), slice(6, 9), slice(9, 12), slice(12, 15))
N_ERROR = 15
#: chi-square(3) at 1 - 1e-4: a fix whose normalised innovation exceeds it is an outlier.
FIX_GATE = 21.11

compiled_ins = jit.lazy("observer.navigation.compiled_ins")


def _like(v, shape_of: np.ndarray) -> np.ndarray:
    """``v`` as a contiguous float array of ``shape_of``'s shape (broadcast where it is
    not already one: ``np.broadcast_to`` alone costs a step's 10 us)."""
    v = np.asarray(v, dtype=float)
    if v.shape != shape_of.shape:
        v = np.broadcast_to(v, shape_of.shape)
    return np.ascontiguousarray(v)


class InsAiding:
    """The updates, mixed into :class:`~observer.navigation.ins.AidedINS` (which holds ``states``,
    ``Ps``, ``noise``, ``field``, the DVL's geometry and the displacement history)."""

    def _correct(self, rows, residual: np.ndarray, H: np.ndarray, Rm: np.ndarray,
                 gate: float | None = None) -> np.ndarray:
        """The Kalman update of the vehicles ``rows`` with ``residual`` (measured less
        predicted, (M, 3)), its Jacobian ``H`` on the error state (M, 3, 15) and its noise
        ``Rm`` (3, 3) or (M, 3, 3); a vehicle whose normalised innovation squared exceeds
        ``gate`` is refused (its state untouched). Returns the NIS (M,)."""
        Pr = self.Ps[rows]
        PHt = Pr @ _T(H)
        S = H @ PHt + Rm
        Sinv = np.linalg.inv(S)
        nis = ((residual[:, None, :] @ Sinv) @ residual[:, :, None])[:, 0, 0]
        take = np.ones(len(nis), dtype=bool) if gate is None else nis <= gate
        if not take.any():
            return nis
        K = PHt @ Sinv
        dx = _mv(K, residual)
        IKH = np.eye(N_ERROR) - K @ H
        new = IKH @ Pr @ _T(IKH) + K @ Rm @ _T(K)
        rows = np.asarray(rows)[take]
        self.Ps[rows] = new[take]
        self._inject_rows(rows, dx[take])
        return nis

    def _inject_rows(self, rows, dx: np.ndarray) -> None:
        # New arrays, not writes into the old: an estimate read before stays as it was.
        s = self.states
        if isinstance(rows, slice) and rows == slice(None):
            s.position, s.velocity = s.position + dx[:, P], s.velocity + dx[:, V]
            s.attitude = s.attitude @ rotation_exp(dx[:, TH])
            s.gyro_bias, s.accel_bias = s.gyro_bias + dx[:, BG], s.accel_bias + dx[:, BA]
            return
        for name, part in (("position", P), ("velocity", V), ("gyro_bias", BG),
                           ("accel_bias", BA)):
            x = getattr(s, name).copy()
            x[rows] = x[rows] + dx[:, part]
            setattr(s, name, x)
        att = s.attitude.copy()
        att[rows] = att[rows] @ rotation_exp(dx[:, TH])
        s.attitude = att

    def dvl_rows(self, rows: np.ndarray, velocity: np.ndarray, gyro: np.ndarray):
        """DVL pings of the vehicles ``rows``: velocities (M, 3) [m/s] in the DVL's
        frame, the gyro's readings (M, 3) [rad/s] at the pings. Returns the NIS (M,)."""
        s = self.states
        att, vel = s.attitude[rows], s.velocity[rows]
        omega = gyro - s.gyro_bias[rows]
        v_body = _mv(_T(att), vel)
        lever, RdT = self._lever, self.R_dvl.T
        predicted = _mv(RdT, v_body - _mv(lever, omega))
        H = np.zeros((len(rows), 3, N_ERROR))
        H[:, :, V] = RdT @ _T(att)
        H[:, :, TH] = RdT @ skew(v_body)
        H[:, :, BG] = RdT @ lever
        return self._correct(rows, velocity - predicted, H, self._R_dvl_noise)

    def depth_rows(self, depth: np.ndarray, surface) -> None:
        """A depth reading [m] (positive down) of every vehicle, (N,), below the height
        ``surface`` [m] where depth is 0."""
        s = self.states
        if jit.enabled():
            s.position, s.velocity, s.attitude, s.gyro_bias, s.accel_bias = \
                compiled_ins.depth_update(
                    s.position, s.velocity, s.attitude, s.gyro_bias, s.accel_bias, self.Ps,
                    np.ascontiguousarray(depth, dtype=float), _like(surface, depth),
                    self.noise.depth_noise**2)
            return
        r = depth - (surface - s.position[:, 2])
        ph = self.Ps[:, :, 2].copy()  # P H^T with H = -e_z, sign apart
        S = ph[:, 2] + self.noise.depth_noise**2
        self.Ps -= (ph[:, :, None] * ph[:, None, :]) / S[:, None, None]
        self._inject_rows(slice(None), ph * (-r / S)[:, None])

    def magnetometer_rows(self, rows: np.ndarray, field: np.ndarray):
        """Magnetometer readings (M, 3) of the vehicles ``rows``, body frame. Returns the
        NIS (M,)."""
        if self.field is None:
            raise ValueError("this INS has no magnetic field to compare a reading with")
        att = self.states.attitude[rows]
        predicted = _T(att) @ self.field
        H = np.zeros((len(rows), 3, N_ERROR))
        H[:, :, TH] = skew(predicted)
        Rm = np.eye(3) * self.noise.magnetometer_noise**2
        return self._correct(rows, field - predicted, H, Rm)

    def position_rows(self, rows: np.ndarray, fix: np.ndarray, std: np.ndarray,
                      delay: np.ndarray, gate: float | None = FIX_GATE) -> np.ndarray:
        """Acoustic fixes (M, 3) [m] of the vehicles ``rows``, each axis's standard
        deviation ``std`` (M,) [m], measured ``delay`` (M,) [s] ago. Returns which were
        taken (the others' innovations exceed ``gate``)."""
        then = np.empty((len(rows), 3))
        for j, (i, late) in enumerate(zip(np.asarray(rows).tolist(), delay.tolist(),
                                          strict=True)):
            hist = self._histories[i]
            back = min(int(round(late / self.Te)), len(hist) - 1)
            since = (self.displacements[i] - hist[-1 - back]) if back > 0 else 0.0
            then[j] = self.states.position[i] - since
        H = np.zeros((len(rows), 3, N_ERROR))
        H[:, :, P] = np.eye(3)
        Rm = np.eye(3) * libm_square(std)[:, None, None]
        nis = self._correct(rows, fix - then, H, Rm, gate)
        taken = np.ones(len(rows), dtype=bool) if gate is None else nis <= gate
        self.rejected[rows] += ~taken
        return taken
