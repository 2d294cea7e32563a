"""Whether the photodiodes can see the LED at all, and what in the scene blocks them
when they cannot: checked when a sensor is made, before any run starts."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from ledsim.physics.world import RAY_GROUPS, WorldError


def check_line_of_sight(sensor) -> None:
    """Refuse geometries where the LED can never be seen from the photodiodes of
    ``sensor`` (an :class:`~ledsim.physics.sensor.IrradianceSensor`): behind, or walled
    off, grazing included, naming what cuts the beam."""
    w = sensor.world
    with w.parked_occluder():  # only the scene itself counts
        reading = sensor.read(noise=False)
    led = np.round(w.led_pos, 4).tolist()
    for i, pd in zip(range(sensor.layout.n_photodiodes), sensor.layout.photodiodes, strict=True):
        name = f"photodiode {pd.site!r}"
        if abs(reading.incidence_angle[i]) >= math.pi / 2:
            raise WorldError(f"LED at {led} m is behind {name} (incidence "
                             f"angle {reading.incidence_angle[i]:.2f} rad): no line of "
                             "sight is possible")
        if reading.emission_angle[i] >= math.pi / 2:
            raise WorldError(f"LED at {led} m faces away from {name} "
                             f"(emission angle {reading.emission_angle[i]:.2f} rad): no "
                             "line of sight")
        if reading.visible_fraction[i] < 1:  # grazing too: the scene cuts the beam
            hidden = "hidden" if reading.visible_fraction[i] == 0 else \
                f"{1 - reading.visible_fraction[i]:.0%} hidden"
            raise WorldError(f"the LED, {led_depth(w):g} m deep, is {hidden} from "
                             f"{name} by {blocker(sensor, i)}: no clear line of sight")


def led_depth(w) -> float:
    """The LED's depth under the still surface [m] in the world ``w``."""
    return round(float(w.initial_hull_pos[2] + w.config.depth - w.led_pos[2]), 3)


def blocker(sensor, i: int) -> str:
    """What in the scene cuts a ray from photodiode ``i`` to the LED's aperture: the
    seabed, the receiver's hull, or the scene's geom by name."""
    w = sensor.world
    m, origin = w.model, w.photodiode_pos(i)
    geom = np.zeros(1, dtype=np.int32)
    for point in sensor.aperture_points():
        ray = point - origin
        length = float(np.linalg.norm(ray))
        hit = mujoco.mj_ray(m, w.data, origin, ray / length, RAY_GROUPS, 1,
                            w.ids.gimbal_body, geom)
        if 0.0 <= hit < length:
            break
    else:
        return "the scene"
    name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, int(geom[0])) or ""
    body = int(m.geom_bodyid[geom[0]])
    if name == "seabed":
        return "the seabed (sea_depth, or 2.5 m under the deeper end by default)"
    if body == w.ids.hull_body or int(m.body_rootid[body]) == \
            int(m.body_rootid[w.ids.hull_body]):
        return "the receiver's own vehicle (its hull stands in the beam)"
    label = name or mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, body) or f"#{body}"
    return f"the scene's {label!r}"
