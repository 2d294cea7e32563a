"""Headless simulation loop at the control period Te, with physics substeps.

One pass at step k (t = k Te): the sensor samples y_k and the true state
x_k = (phi, phidot) of photodiode 1 on a world prepared for t (disturbances acted,
kinematics updated), the gimbal torque u_k is chosen (a profile, or a controller fed with
the sensor reading), and the world's tick (a row of one of
:class:`~ledsim.physics.world_rows.WorldRows`) moves physics on by Te in ``substeps``
MuJoCo steps and prepares the next step.
"""

from __future__ import annotations

import csv
import math
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from ledsim.constants import LinkConstants
from ledsim.errors import LedsimError
from ledsim.files.outputs import atomic_write_bytes
from ledsim.physics.layout import ReceiverLayout
from ledsim.physics.sensor import IrradianceSensor, SensorReading
from ledsim.physics.tick import prepare
from ledsim.physics.world import LinkWorld
from ledsim.physics.world_rows import WorldRows


class ProfileError(LedsimError):
    """Unknown torque profile or bad parameter."""


TORQUE_PROFILES = ("zero", "sine", "step", "chirp")


def torque_profile(name: str, amplitude: float = 0.005, frequency: float = 0.5,
                   start: float = 0.5) -> Callable[[float], float]:
    """Open-loop gimbal torque u(t) [N m].

    ``zero``; ``sine``: amplitude sin(2 pi frequency t); ``step``: amplitude from ``start``;
    ``chirp``: sine sweeping from 0.1 to ``frequency`` Hz over 10 s.
    """
    if name == "zero":
        return lambda t: 0.0
    if name == "sine":
        return lambda t: amplitude * math.sin(2 * math.pi * frequency * t)
    if name == "step":
        return lambda t: amplitude if t >= start else 0.0
    if name == "chirp":
        return lambda t: amplitude * math.sin(
            2 * math.pi * (0.1 * t + (frequency - 0.1) * t * t / 20.0))
    raise ProfileError(f"unknown torque profile {name!r}: choose from zero, sine, step, chirp")


@dataclass
class SimulationResult(SensorReading):
    """Time series of a run: the fields of :class:`SensorReading`, one row per control
    step (phi [rad], phidot [rad/s], gimbal_angle [rad], gimbal_rate [rad/s]: (N,);
    power, power_clean [W], incidence_angle, emission_angle [rad], distance [m],
    visible_fraction: (N, n_pd); hull_pos [m]: (N, 3)), and

    Attributes:
        t: time of each step [s], (N,).
        torque: the motor torque applied [N m], (N,).
        occluded: (N, 2) bool, any aperture ray of the photodiode blocked.
    """

    t: np.ndarray
    torque: np.ndarray
    occluded: np.ndarray

    #: The order of the series in files (``save_npz``, ``save_csv``).
    SERIES = ("t", "phi", "phidot", "gimbal_angle", "gimbal_rate", "torque", "power",
              "power_clean", "incidence_angle", "emission_angle", "distance",
              "visible_fraction", "occluded", "hull_pos")

    @classmethod
    def from_steps(cls, t: np.ndarray, geo: np.ndarray, state: np.ndarray,
                   gimbal: np.ndarray, torque: np.ndarray, power: np.ndarray,
                   power_clean: np.ndarray, hull: np.ndarray,
                   layout: ReceiverLayout | None = None) -> SimulationResult:
        """From per-step arrays: ``geo`` (N, 4, n_pd) distance, theta, phi and visible
        fraction of each photodiode; ``state`` (the true state) and ``gimbal`` (the
        encoder's angle and rate) (N, n_state), named by ``layout`` (None: the paper's)."""
        lay = LinkConstants().layout if layout is None else layout
        head = {} if lay.n_axes != 2 else {"elevation": lay.angles(state)[1],
                                           "elevation_rate": lay.rates(state)[1]}
        return cls(t=t, phi=lay.angle(state), phidot=lay.rate(state), **head,
                   gimbal_angle=lay.angle(gimbal), gimbal_rate=lay.rate(gimbal),
                   torque=torque, power=power,
                   power_clean=power_clean, incidence_angle=geo[:, 2],
                   emission_angle=geo[:, 1], distance=geo[:, 0],
                   visible_fraction=geo[:, 3], occluded=geo[:, 3] < 1.0, hull_pos=hull)

    @property
    def x(self) -> np.ndarray:
        """True state (phi, phidot), shape (N, 2); on a pan-tilt head (azimuth,
        elevation, their rates), shape (N, 4)."""
        if self.elevation is not None:
            return np.stack([self.phi, self.elevation, self.phidot, self.elevation_rate],
                            axis=-1)
        return np.stack([self.phi, self.phidot], axis=-1)

    def arrays(self) -> dict[str, np.ndarray]:
        return {name: getattr(self, name) for name in self.SERIES}

    def save_npz(self, path: Path) -> None:
        atomic_write_bytes(Path(path), lambda tmp: np.savez_compressed(
            open(tmp, "wb"), **self.arrays()))

    def csv_columns(self) -> dict[str, np.ndarray]:
        cols = {}
        for name, a in self.arrays().items():
            if a.ndim == 1:
                cols[name] = a
            else:
                suffix = "xyz" if name == "hull_pos" else "12"
                for j in range(a.shape[1]):
                    cols[f"{name}_{suffix[j]}"] = a[:, j]
        return cols

    def save_csv(self, path: Path) -> None:
        cols = self.csv_columns()

        def write(tmp):
            with open(tmp, "w", newline="") as fh:
                writer = csv.writer(fh)
                writer.writerow(list(cols))
                for row in zip(*cols.values(), strict=True):
                    writer.writerow([f"{v:.9g}" if isinstance(v, float) else int(v)
                                     for v in row])

        atomic_write_bytes(Path(path), write)


def simulate(world: LinkWorld, sensor: IrradianceSensor, seconds: float,
             torque: Callable[[float], float] | None = None,
             disturbances: Sequence = (),
             controller: Callable[[SensorReading, float], float] | None = None,
             progress: bool = False, vehicle=None) -> SimulationResult:
    """Run the world for ``seconds`` at the control period Te.

    Args:
        world, sensor: the scene and its photodiode sensor (state as it is now).
        seconds: duration [s].
        torque: open-loop torque profile u(t) [N m] (ignored when ``controller`` is set).
        disturbances: :class:`~ledsim.physics.disturbances.Disturbance` objects, already
            ``reset`` for this run.
        controller: ``controller(reading, t) -> torque`` for closed-loop runs.
        progress: show a progress bar.
        vehicle: a :class:`~ledsim.agent.autopilot.Vehicle` that senses, navigates and
            keeps station each step (None: the hull only feels the disturbances).
    """
    Te = world.config.constants.Te
    n = int(round(seconds / Te))
    torque = torque or (lambda t: 0.0)
    lay = sensor.layout
    geo = np.empty((n, 4, lay.n_photodiodes))  # d, theta, phi, visible fraction
    state = np.empty((n, lay.n_state))
    gimbal = np.empty((n, lay.n_state))
    applied = np.empty(n)
    hull = np.empty((n, 3))
    power = np.empty((n, lay.n_photodiodes)) if controller else None
    t0 = world.time
    prepare(world, disturbances, t0, vehicle)
    rows = WorldRows([world])  # the world as a row of one: the one tick
    rows.start([sensor], [list(disturbances)], [vehicle])
    for k in tqdm(range(n), disable=not progress, desc="simulate", leave=False,
                  file=sys.stderr):
        t = t0 + k * Te
        if controller is None:
            geo[k] = sensor.geometry()
            state[k] = geo[k, 2, lay.reference], sensor.incidence_rate(lay.reference)
            u = torque(t)
        else:
            r = sensor.read()
            geo[k] = r.distance, r.emission_angle, r.incidence_angle, r.visible_fraction
            state[k] = r.phi, r.phidot
            power[k] = r.power
            u = controller(r, t)
        gimbal[k] = world.gimbal_angle, world.gimbal_rate
        hull[k] = world.hull_pos
        applied[k] = rows.tick(t0 + (k + 1) * Te, torques=(u,))[0]
    clean = sensor.clean_power(geo[:, 0], geo[:, 1], geo[:, 2], geo[:, 3])
    if power is None and sensor.signal_noise:
        power = sensor.measurement_noise.measure(clean, sensor.rng)
    elif power is None:
        power = clean + sensor.rng.standard_normal(clean.shape) * sensor.noise_std
    return SimulationResult.from_steps(t0 + np.arange(n) * Te, geo, state, gimbal, applied,
                                       power, clean, hull, lay)
