"""Missions: the receiver's vehicle flies a path of waypoints, then keeps station at the
last one.

A mission is a list of waypoints in the run's start frame (x ahead along the vehicle's
start heading, towards the LED; y to its left; metres from the hull's start), each with
the speed to reach it at. The guidance is a virtual target that moves along the legs at
their speeds (:class:`PathReference`): the station keeping's PD holds the hull on it,
heading along the leg, with the target's velocity fed forward, and its load observer
cancels the water's drag as it cancels a current. At the last waypoint the target stops
and the vehicle keeps station there, heading along the last leg. (A hovering AUV with
surge, sway and heave thrusters tracks the target as a trajectory; Fossen, *Handbook of
Marine Craft Hydrodynamics and Motion Control*, 2nd ed., ch. 12.)

A mission file is JSON or TOML (``.json``, ``.toml``)::

    {"waypoints": [{"x": 20.0, "y": 0.0, "speed": 0.5},
                   {"x": 20.0, "y": 5.0, "speed": 0.3}]}
"""

from __future__ import annotations

import functools
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ledsim.errors import LedsimError

#: The fastest a waypoint may be flown at [m/s] (a REMUS-100-class hull's top speed is
#: about 2.3 m/s; its thrusters, 100 N in surge, leave margin at 2).
MAX_SPEED = 2.0
#: The most waypoints a mission may have, and how far a waypoint may lie [m].
MAX_WAYPOINTS, MAX_REACH = 1000, 5000.0


class MissionError(LedsimError):
    """A mission file that cannot be flown (named, with what is allowed)."""


@dataclass(frozen=True)
class Waypoint:
    """A point of the path in the run's start frame [m] and the speed to reach it at
    [m/s]."""

    x: float
    y: float
    speed: float


@dataclass(frozen=True)
class Mission:
    """Waypoints flown in order from the hull's start."""

    waypoints: tuple[Waypoint, ...]

    @property
    def duration(self) -> float:
        """How long the path takes from the start to the last waypoint [s]."""
        x0 = y0 = t = 0.0
        for w in self.waypoints:
            t += math.hypot(w.x - x0, w.y - y0) / w.speed
            x0, y0 = w.x, w.y
        return t

    def closest_approach(self, point, rise: float = 0.0) -> tuple[float, float, float]:
        """(range [m], x, y) of the path's nearest approach to ``point`` (x, y in the
        start frame [m]), which stands ``rise`` [m] above or below the path."""
        p = np.asarray(point, dtype=float)
        best = (math.inf, 0.0, 0.0)
        a = np.zeros(2)
        for w in self.waypoints:
            b = np.array([w.x, w.y])
            leg = b - a
            s = min(max(float((p - a) @ leg / (leg @ leg)), 0.0), 1.0)
            q = a + s * leg
            r = math.hypot(float(np.hypot(*(p - q))), rise)
            best = min(best, (r, float(q[0]), float(q[1])))
            a = b
        return best

    @classmethod
    def from_file(cls, path: str | Path) -> Mission:
        """The mission in the JSON or TOML file ``path``, checked in one line."""
        return _load(str(path))


@functools.lru_cache(maxsize=16)
def _load(path: str) -> Mission:
    p = Path(path)
    if p.suffix not in (".json", ".toml"):
        raise MissionError(f"--mission {path!r}: a mission is a .json or .toml file")
    if not p.is_file():
        raise MissionError(f"--mission {path!r} does not exist")
    text = p.read_text(errors="replace")
    try:
        if p.suffix == ".json":
            data = json.loads(text)
        else:
            import tomllib

            data = tomllib.loads(text)
    except (ValueError, json.JSONDecodeError) as e:
        raise MissionError(f"--mission {path!r} is not valid {p.suffix[1:].upper()}: "
                           f"{str(e).splitlines()[0]}") from None
    points = data.get("waypoints") if isinstance(data, dict) else None
    if not isinstance(points, list) or not points:
        raise MissionError(f"--mission {path!r} has no list of waypoints (\"waypoints\": "
                           "[{\"x\": X, \"y\": Y, \"speed\": V}, ...])")
    if len(points) > MAX_WAYPOINTS:
        raise MissionError(f"--mission {path!r} has {len(points)} waypoints: at most "
                           f"{MAX_WAYPOINTS}")
    out, last = [], (0.0, 0.0)
    for k, w in enumerate(points):
        where = f"--mission {path!r}: waypoint {k}"
        if not isinstance(w, dict) or set(w) != {"x", "y", "speed"}:
            raise MissionError(f"{where} is not {{\"x\": X, \"y\": Y, \"speed\": V}}: "
                               f"{json.dumps(w, default=str)[:60]}")
        values = {}
        for key in ("x", "y", "speed"):
            v = w[key]
            if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
                raise MissionError(f"{where}: {key} {v!r} is not a finite number")
            values[key] = float(v)
        if not 0.0 < values["speed"] <= MAX_SPEED:
            raise MissionError(f"{where}: speed {values['speed']:g} is not allowed: must "
                               f"be in (0, {MAX_SPEED:g}] m/s")
        if math.hypot(values["x"], values["y"]) > MAX_REACH:
            raise MissionError(f"{where}: ({values['x']:g}, {values['y']:g}) is more than "
                               f"{MAX_REACH:g} m from the start")
        if (values["x"], values["y"]) == last:
            raise MissionError(f"{where} repeats the point before it "
                               f"({values['x']:g}, {values['y']:g})")
        last = (values["x"], values["y"])
        out.append(Waypoint(**values))
    return Mission(tuple(out))


def led_in_start_frame(distance: float, rise: float, lateral: float = 0.0
                       ) -> tuple[float, float]:
    """Where the scene puts the LED in the start frame, horizontally, from the gimbal's
    hinge (x ahead, y left [m]): ``distance`` is the slant range to an LED ``rise`` [m]
    above (below: negative) and ``lateral`` [m] to the left (``physics/scene.py``)."""
    ahead = distance if rise == 0.0 else math.sqrt(distance**2 - rise**2)
    return ahead, lateral


class PathReference:
    """The virtual target of a mission flown from a start pose: where it is at a time,
    how fast it moves and which way it heads.

    Args:
        mission: the waypoints (start frame).
        start: the hull's start position, horizontal [m] (2,), world frame.
        heading: the hull's start heading [rad] (the start frame's x).
    """

    def __init__(self, mission: Mission, start, heading: float):
        c, s = math.cos(heading), math.sin(heading)
        start = np.asarray(start, dtype=float)[:2]
        pts = [start] + [start + np.array([c * w.x - s * w.y, s * w.x + c * w.y])
                         for w in mission.waypoints]
        self.points = np.array(pts)
        legs = np.diff(self.points, axis=0)
        self.lengths = np.hypot(legs[:, 0], legs[:, 1])
        self.directions = legs / self.lengths[:, None]
        self.speeds = np.array([w.speed for w in mission.waypoints])
        self.ends = np.cumsum(self.lengths / self.speeds)  # time at each waypoint [s]
        self.headings = np.arctan2(self.directions[:, 1], self.directions[:, 0])

    @property
    def duration(self) -> float:
        return float(self.ends[-1])

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray, float]:
        """(position [m] (2,), velocity [m/s] (2,), heading [rad]) of the target at
        ``t`` [s]; after the last waypoint, there at rest, heading along the last leg."""
        if t >= self.ends[-1]:
            return self.points[-1].copy(), np.zeros(2), float(self.headings[-1])
        k = int(np.searchsorted(self.ends, t, side="right"))
        begun = 0.0 if k == 0 else float(self.ends[k - 1])
        along = (t - begun) * self.speeds[k]
        v = self.speeds[k] * self.directions[k]
        return self.points[k] + along * self.directions[k], v, float(self.headings[k])

    def positions(self, times) -> np.ndarray:
        """The target's positions [m] at ``times`` [s], (T, 2)."""
        return np.array([self.at(float(t))[0] for t in np.asarray(times, dtype=float)])
