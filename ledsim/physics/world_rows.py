"""N worlds that tick together, one row each: what the closed loop of many seeds and the
native vector env step.

Each row is a world with its sensor, its disturbances and its vehicle (the agent's
autopilot, or None). :meth:`WorldRows.read` reads every sensor in one pass
(:class:`~ledsim.physics.sensor_rows.SensorRows`); once each world's torque is
commanded, :meth:`WorldRows.tick` steps every world's physics in one pass (split over
threads: :class:`~ledsim.physics.tick.PhysicsPass`), prepares each world's next
control step, and lets the vehicles act in one pass over their rows (the vehicles of
all rows stacked as one). A row's numbers do not depend on the others beside it.

It is the one way worlds move, shaped like ``mujoco.rollout`` (rows started, read, and
ticked with their torques): the closed loop of one seed or many, the native vector
env, the single env, :func:`~ledsim.physics.simulation.simulate` and the wave response
all tick their worlds here (one world is a row of one, whose vehicle is its own, not a
copy). A row's torque is a float for a gimbal of one axis, an array over the axes
(shape (n_axes,)) for more.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ledsim.physics.sensor import IrradianceSensor, SensorReading
from ledsim.physics.sensor_rows import SensorRows
from ledsim.physics.tick import PhysicsPass, step_worlds
from ledsim.physics.world import LinkWorld


class WorldRows:
    """The rows of :mod:`this module <ledsim.physics.world_rows>`.

    Args:
        worlds: one world per row (shared model or not), in a fixed order.
        threads: threads stepping the physics (1: the calling thread); the pool starts
            at the first tick and stops on :meth:`close` (a context manager).
    """

    def __init__(self, worlds: Sequence[LinkWorld], threads: int = 1):
        self.worlds = list(worlds)
        self.threads = threads
        self.sensors: SensorRows | None = None
        self.disturbances: list[list] = [[] for _ in self.worlds]
        self.vehicles = None  # the rows' vehicles as one (Vehicle.stacked), or None
        self._physics: PhysicsPass | None = None

    def start(self, sensors: Sequence[IrradianceSensor] | None,
              disturbances: Sequence[list], vehicles: Sequence) -> list:
        """Every row started anew (each world already reset by its owner): its sensor
        (None: rows nobody reads), disturbances and vehicle (None: none). Returns each
        row's vehicle as the row of the stacked vehicles that it now is (or None)."""
        self.sensors = None if sensors is None else SensorRows(sensors)
        self.disturbances = list(disturbances)
        self.vehicles = None
        if len(vehicles) == 1:  # a vehicle is a stack of one already: no copy
            self.vehicles = vehicles[0]
        elif vehicles and vehicles[0] is not None:
            self.vehicles = type(vehicles[0]).stacked(list(vehicles))
        return [self.vehicle(i) for i in range(len(self.worlds))]

    def put(self, i: int, sensor: IrradianceSensor, disturbances: list, vehicle):
        """Row ``i`` started anew (its world restarted); returns its vehicle's row."""
        self.sensors.sensors[i] = sensor
        self.disturbances[i] = disturbances
        if len(self.worlds) == 1:
            self.vehicles = vehicle
        elif self.vehicles is not None:
            self.vehicles.put(i, vehicle)
        return self.vehicle(i)

    def vehicle(self, i: int):
        """Row ``i``'s vehicle, a row of the stacked vehicles (None: no vehicles; the
        vehicle itself for a row of one)."""
        if self.vehicles is None or len(self.worlds) == 1:
            return self.vehicles
        return self.vehicles.row(i)

    def read(self) -> list[SensorReading]:
        """Every row's sensor, in one pass."""
        return self.sensors.read()

    def tick(self, t_next, stepping: np.ndarray | None = None, torques=None):
        """One tick: each row's motor torque [N m] commanded (``torques``, one per row,
        clipped at the limit; None: commanded already), the physics of the ``stepping``
        rows (None: all) one control period, each prepared at its ``t_next`` [s] (one
        time, or one per row), then every vehicle row acts at it. Returns the torques
        applied (None when none were given)."""
        applied = None
        if torques is not None:
            applied = [w.set_torques(t) if isinstance(t, np.ndarray) else w.set_torque(t)
                       for w, t in zip(self.worlds, torques, strict=True)]
        if self._physics is None:
            self._physics = PhysicsPass(self.worlds, self.threads)
        n = len(self.worlds)
        rows = range(n) if stepping is None else np.flatnonzero(stepping)
        if np.ndim(t_next) == 0:  # one time (the closed loop): no array per step
            t = float(t_next)
            ticks = [(self.worlds[i], self.disturbances[i], t) for i in rows]
        else:
            times = np.asarray(t_next, dtype=float)
            ticks = [(self.worlds[i], self.disturbances[i], float(times[i])) for i in rows]
        step_worlds(self._physics, ticks, self.vehicles, t_next)
        return applied

    def close(self) -> None:
        """Stop the physics' threads (a later tick starts them again)."""
        if self._physics is not None:
            self._physics.close()
            self._physics = None

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()
