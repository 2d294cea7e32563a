"""The scenarios in which the receiver's vehicle flies a mission past a node: a fly-by, a
docking approach and a survey (``--scenario flyby``, ``dock``, ``survey``).

Each places the node (its LED's depth and the way its axis points) and draws the path
from the link's reach: the range at which the aligned link's bit error rate meets the
FEC limit (``ledsim budget``'s ``range_at_fec_limit_m``) in the run's water, at its bit
rate, with its receiver.

=============  ==============================================================
scenario       what the vehicle does
=============  ==============================================================
``flyby-5``    a straight transit at 1 m/s past a seabed node, from 0.9 of the
               reach before it to as far after, 5 m from it at the closest; the
               node's LED points up at 45 deg at that closest point (``flyby``
               is this one)
``flyby-15``   the same, 15 m from the node at the closest
``dock``       an approach at 0.5 m/s from 0.9 of the reach to 2 m off a
               docking station's LED (level, facing the vehicle), then a hold
``survey``     a lawnmower of four 40 m lanes 8 m apart at 1 m/s, 8 m over a
               node whose LED points straight up (the nearest lanes pass 4 m to
               its side), repeated to fill ``--seconds``: the link comes and goes
=============  ==============================================================

The start frame is the run's: x ahead along the vehicle's start heading, at the node
(level with it), y to the left. The node stands ``ahead`` metres along x and ``rise``
above the vehicle (negative: below), so the scene's slant ``--distance`` is the range at
the start.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

from ledsim.agent.guidance import Mission, Waypoint
from ledsim.errors import LedsimError

#: The share of the link's reach a fly-by and an approach start at [-].
START_SHARE = 0.9
#: How long a mission scenario holds its last point when no ``--seconds`` says [s]:
#: a fly-by's vehicle stops out of reach, a docked one delivers.
HOLDS = {"flyby": 5.0, "dock": 20.0, "survey": 5.0}


@dataclass(frozen=True)
class Plan:
    """Where a mission scenario puts the node, and the path.

    Attributes:
        distance: the node's slant range at the start [m] (the run's ``distance``).
        rise: the node's height over the vehicle [m] (negative: below).
        led_yaw: the LED's axis turned about the vertical from facing the vehicle [rad].
        led_pitch: the LED's axis turned up from level [rad].
        mission: the path, in the start frame.
        hold: how long the run holds the path's end [s].
    """

    distance: float
    rise: float
    led_yaw: float
    led_pitch: float
    mission: Mission
    hold: float


@dataclass(frozen=True)
class MissionScenario:
    """A mission past a node (module doc).

    Attributes:
        name: the ``--scenario`` key.
        kind: ``flyby``, ``dock`` or ``survey``.
        closest: a fly-by's range at its closest approach [m].
        description: one line for ``--help``.
    """

    name: str
    kind: str
    closest: float = 0.0
    description: str = ""

    def start_range(self, reach: float) -> float:
        """The node's range at the start [m] when the run names no ``--distance``:
        :data:`START_SHARE` of the link's ``reach`` [m] (the survey's: its pattern's)."""
        if self.kind == "survey":
            return math.hypot(_SURVEY_CORNER, SURVEY_ALTITUDE)
        return START_SHARE * reach

    @property
    def rise(self) -> float:
        """The node's height over the vehicle [m] (negative: below)."""
        if self.kind == "flyby":
            return -self.closest / math.sqrt(2.0)
        return -SURVEY_ALTITUDE if self.kind == "survey" else 0.0

    @property
    def least_distance(self) -> float:
        """The nearest start to the node the scenario can fly [m]: a metre more than
        its depth under the vehicle, or its closest approach, or the dock's stand-off."""
        return max(abs(self.rise), self.closest, DOCK_STANDOFF) + 1.0

    def plan(self, distance: float, seconds: float | None = None) -> Plan:
        """The node and the path for a start ``distance`` [m] from the node (the survey
        repeats its pattern to fill ``seconds`` [s] when given)."""
        if not distance > self.least_distance:
            raise LedsimError(f"--distance {distance:g} is not allowed for --scenario "
                              f"{self.name}: must be over {self.least_distance:g} m")
        return _plan(self, float(distance), seconds)


#: The survey's lanes: their length [m], spacing [m], count, speed [m/s] and height
#: over the node [m].
SURVEY_LANE, SURVEY_SPACING, SURVEY_LANES, SURVEY_SPEED = 40.0, 8.0, 4, 1.0
SURVEY_ALTITUDE = 8.0
_SURVEY_WIDTH = SURVEY_SPACING * (SURVEY_LANES - 1)
_SURVEY_CORNER = 0.5 * math.hypot(SURVEY_LANE, _SURVEY_WIDTH)

FLYBY_SPEED, DOCK_SPEED, DOCK_STANDOFF = 1.0, 0.5, 2.0


@functools.lru_cache(maxsize=64)
def _plan(scenario: MissionScenario, distance: float, seconds: float | None) -> Plan:
    kind = scenario.kind
    if kind == "flyby":
        # The node c/sqrt(2) below and c/sqrt(2) to the side of the track, its LED up at
        # 45 deg at the track's closest point: the vehicle on its axis there.
        z = -scenario.rise
        ahead = math.sqrt(distance**2 - z**2)  # the node's horizontal range at the start
        beta = math.asin(z / ahead)  # the track's turn off the node's bearing
        along = 2.0 * ahead * math.cos(beta)  # to as far past the closest point
        end = Waypoint(along * math.cos(beta), along * math.sin(beta), FLYBY_SPEED)
        return Plan(distance, -z, beta - math.pi / 2, math.pi / 4, Mission((end,)),
                    HOLDS[kind])
    if kind == "dock":
        end = Waypoint(distance - DOCK_STANDOFF, 0.0, DOCK_SPEED)
        return Plan(distance, 0.0, 0.0, 0.0, Mission((end,)), HOLDS[kind])
    # survey: the pattern's corner at the start, its centre over the node
    z = SURVEY_ALTITUDE
    ahead = math.sqrt(distance**2 - z**2)
    gamma = -math.atan2(_SURVEY_WIDTH, SURVEY_LANE)  # the lanes' heading in the frame
    scale = ahead / _SURVEY_CORNER  # a --distance stretches the pattern
    lanes = []
    for k in range(SURVEY_LANES):
        v = k * SURVEY_SPACING
        ends = (0.0, SURVEY_LANE) if k % 2 == 0 else (SURVEY_LANE, 0.0)
        lanes += [(u, v) for u in ends]
    # one pass from the start corner; then back and out again while --seconds lasts
    passes = [lanes[1:], lanes[::-1][1:]]
    one = scale * (SURVEY_LANES * SURVEY_LANE + (SURVEY_LANES - 1) * SURVEY_SPACING)
    count = 1 if seconds is None else max(1, math.ceil(SURVEY_SPEED * seconds / one))
    points = [p for k in range(count) for p in passes[k % 2]]
    c, s = math.cos(gamma), math.sin(gamma)
    waypoints = tuple(Waypoint(scale * (c * u - s * v), scale * (s * u + c * v),
                               SURVEY_SPEED) for u, v in points)
    return Plan(distance, -z, 0.0, math.pi / 2, Mission(waypoints), HOLDS[kind])


def placed(world, scenario: MissionScenario, given: bool, bit_rate: float):
    """``world`` with the node where ``scenario`` puts it: its range at the start (the
    scenario's share of the link's reach, unless ``given``) and its depth (unless one
    is named), and the head in a dome: at 1 m/s the water's drag on an open head
    (about 0.25 N m) is five times its motor's torque, and the pan stalls abeam."""
    distance = world.distance
    if not given:
        from ledsim.radiometry.budget import range_at_fec
        from ledsim.radiometry.link_presets import link_constants

        c = link_constants(world.link, 10.0, world.water, world.attenuation,
                           lens_field=world.lens_field)
        distance = scenario.start_range(range_at_fec(c, bit_rate))
    rise = scenario.rise
    depth = world.transmitter_depth
    if depth is None and rise != 0.0:
        depth = world.depth - rise
    return replace(world, distance=distance, transmitter_depth=depth, receiver_dome=True)


MISSION_SCENARIOS = {s.name: s for s in (
    MissionScenario("flyby-5", "flyby", 5.0,
                    "a 1 m/s transit past a seabed node 5 m off at the closest, from 0.9 "
                    "of the link's reach before it to as far after; its LED up at 45 deg"),
    MissionScenario("flyby-15", "flyby", 15.0,
                    "the fly-by 15 m off the node at the closest"),
    MissionScenario("dock", "dock", 0.0,
                    "a 0.5 m/s approach from 0.9 of the link's reach to 2 m off a dock's "
                    "LED, then a 20 s hold"),
    MissionScenario("survey", "survey", 0.0,
                    "a lawnmower of 40 m lanes 8 m apart, 8 m over a node whose LED "
                    "points up: the link comes and goes"),
)}
#: ``--scenario flyby`` is the 5 m fly-by.
MISSION_SCENARIOS["flyby"] = MISSION_SCENARIOS["flyby-5"]
