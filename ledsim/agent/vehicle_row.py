"""One vehicle of a stacked :class:`~ledsim.agent.autopilot.Vehicle`, as one run reads
it (its navigation, line of sight, station and target)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from observer.navigation.ins import InsState

if TYPE_CHECKING:
    from ledsim.physics.nav_sensors import NavigationReading
    from observer.navigation.line_of_sight import LineOfSight


class VehicleRow:
    """Vehicle ``i`` of a stacked :class:`Vehicle`: what one run reads of it (its
    navigation, line of sight, station)."""

    def __init__(self, vehicles, i: int):
        self.vehicles, self.i = vehicles, i

    @property
    def station_keeping(self) -> bool:
        return self.vehicles.station_keeping

    @property
    def surface(self) -> float:
        return float(self.vehicles._surface[self.i])

    @property
    def home(self) -> tuple[np.ndarray, float]:
        v = self.vehicles
        return v._home_position[self.i], float(v._home_heading[self.i])

    @property
    def target(self) -> np.ndarray:
        return target_of(self.vehicles, self.i)

    @property
    def range(self) -> float:
        """The LED's range from the gimbal's hinge by the navigated pose [m]."""
        return float(self.vehicles.sight.ranges[self.i])

    @property
    def navigation(self) -> InsState:
        s, i = self.vehicles.ins.states, self.i
        return InsState(s.position[i], s.velocity[i], s.attitude[i], s.gyro_bias[i],
                        s.accel_bias[i])

    @property
    def navigated_position(self) -> np.ndarray:
        """The navigation's position [m] (:attr:`navigation`'s, without building it)."""
        return self.vehicles.ins.states.position[self.i]

    @property
    def los(self) -> LineOfSight:
        return self.vehicles.sight.los_of(self.i)

    @property
    def reading(self) -> NavigationReading | None:
        r = self.vehicles._reading
        return None if r is None else r.row(self.i)


def target_of(v, i: int) -> np.ndarray:
    """Row ``i``'s target (:attr:`Vehicle.target`)."""
    home = v._home_position[i] if v.keeper is None else v.keeper.home_position[i]
    return np.r_[home, v._surface[i]]
