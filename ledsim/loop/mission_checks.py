"""The checks of a run whose vehicle flies a path (``--mission FILE`` or a mission
scenario: :mod:`ledsim.loop.mission_scenarios`), each refused in one line."""

from __future__ import annotations

from ledsim.errors import LedsimError
from ledsim.loop.mission_scenarios import MISSION_SCENARIOS
from ledsim.physics.scene import transmitter_rise

#: The nearest a mission may bring the receiver's gimbal to the LED [m].
MIN_MISSION_RANGE = 1.0


def check_mission(cfg) -> None:
    """A mission is flown on the station keeping's thrusters, keeps the hull off the LED
    (:data:`MIN_MISSION_RANGE`), and a mission scenario runs on a physical link, places
    its own node and is the run's only path."""
    from ledsim.agent.guidance import led_in_start_frame

    scenario = MISSION_SCENARIOS.get(cfg.scenario)
    what = f"--mission {cfg.mission!r}" if scenario is None else \
        f"--scenario {cfg.scenario}"
    if scenario is not None:
        if cfg.link == "paper":
            raise LedsimError(f"{what} flies past a node in the sea: it needs a physical "
                              "--link (aquaoptical, luma, bluecomm-200), not paper")
        if cfg.mission is not None:
            raise LedsimError(f"--mission {cfg.mission!r} and {what} are both paths: "
                              "choose one")
        if cfg.transmitter_aimed:
            raise LedsimError(f"{what} points its node's LED itself: drop "
                              "--transmitter-aimed")
        rise = scenario.rise
        if abs((cfg.depth - rise) - (cfg.transmitter_depth or cfg.depth)) > 1e-9:
            raise LedsimError(f"{what} puts the node {-rise:g} m below the vehicle "
                              f"(--transmitter-depth {cfg.depth - rise:g}), not at "
                              f"--transmitter-depth {cfg.transmitter_depth:g}: drop it")
    if not cfg.station_keeping:
        raise LedsimError(f"{what} is flown by the station keeping's thrusters: drop "
                          "--no-station-keeping")
    mission = cfg.mission_plan
    rise = transmitter_rise(cfg.depth, cfg.transmitter_depth, cfg.distance)
    r, x, y = mission.closest_approach(led_in_start_frame(cfg.distance, rise), rise)
    if r < MIN_MISSION_RANGE:
        raise LedsimError(f"{what} passes {r:.2f} m from the LED, at "
                          f"({x:.2f}, {y:.2f}) m: at least {MIN_MISSION_RANGE:g} m")
