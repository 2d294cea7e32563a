"""The scene of a physical link, metres of water: the bench's MJCF edited through
``MjSpec`` so that its LED stands on a docking station, its occluder and overview
camera scale with the distance, and its fog follows the water.

Only for a physical link (``LinkConstants.link`` set): the paper's bench keeps its own
8.5 cm scene, so its numbers and its video stay as they were.
"""

from __future__ import annotations

import mujoco
import numpy as np

#: Contrast falls to 5 % (exp(-3)) at the far end of the fog: 3 / c [m].
FOG_CONTRASTS = 3.0
#: Half size of the occluder plate per metre of link [m/m] (at least the bench's 3 cm).
OCCLUDER_PER_METRE = 0.01


#: How far the seabed must lie below the deeper end of the link [m]: room for the hull
#: (its keel and fin, 0.3 m below its centre) and the LED's docking station.
SEABED_CLEARANCE = 0.5
#: The deepest sea [m] (the Challenger Deep).
DEEPEST_SEA = 11000.0


def seabed_check(sea_depth: float, depth: float, transmitter_depth: float | None,
                 names: tuple[str, str, str] = ("sea_depth", "depth", "transmitter_depth")):
    """The range check (:func:`~ledsim.errors.check_ranges`' row) of a ``sea_depth`` [m]:
    deeper than both ends (the receiver at ``depth``, the LED at ``transmitter_depth``,
    None: level) by :data:`SEABED_CLEARANCE`; ``names``: what the message calls them."""
    deepest = max(depth, depth if transmitter_depth is None else transmitter_depth)
    least = deepest + SEABED_CLEARANCE
    where = f"{names[1]} {depth:g} m" if transmitter_depth is None else \
        f"{names[1]} {depth:g} m, {names[2]} {transmitter_depth:g} m"
    return (names[0], sea_depth, least <= sea_depth <= DEEPEST_SEA,
            f"in [{least:g}, {DEEPEST_SEA:g}] m: the seabed lies at least "
            f"{SEABED_CLEARANCE:g} m below both ends ({where})")


def place_seabed(spec: mujoco.MjSpec, sea_depth: float | None, depth: float, rise: float,
                 error: type[Exception]) -> None:
    """Put the scene's ``seabed`` geom at ``sea_depth`` [m] under the still surface (the
    receiver at ``depth`` [m], its hull at world z = 0), or, with None, keep the scene's
    seabed under the receiver and lower it by as much as the LED stands below the
    receiver (``rise`` [m] < 0), so that the LED can stand anywhere in the water. A
    scene without a seabed is left as it is, unless ``sea_depth`` asks for one
    (``error``, naming the scene's missing geom)."""
    bed = spec.geom("seabed")
    if bed is None:
        if sea_depth is not None:
            raise error("sea_depth needs a geom named 'seabed' in the scene, which has none")
        return
    x, y, z = (float(v) for v in bed.pos)
    bed.pos = [x, y, depth - sea_depth if sea_depth is not None else z + min(0.0, rise)]


def _look_at(eye: np.ndarray, target: np.ndarray) -> list[float]:
    """MJCF ``xyaxes`` of a camera at ``eye`` looking at ``target``, level horizon."""
    forward = target - eye
    forward = forward / np.linalg.norm(forward)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right = right / np.linalg.norm(right)
    up = np.cross(right, forward)
    return [*right.tolist(), *up.tolist()]


def apply_sea(spec: mujoco.MjSpec, attenuation: float, receiver: np.ndarray,
              led: np.ndarray, depth: float) -> None:
    """Edit ``spec`` for a link from ``receiver`` to ``led`` (world positions [m]) in
    water of beam attenuation ``attenuation`` [1/m], the receiver ``depth`` [m] below
    the surface (the overview camera stays under it, half way up)."""
    distance = float(np.linalg.norm(led - receiver))
    mid = 0.5 * (receiver + led)
    # The fog: linear in MuJoCo, from the receiver's eye to where the contrast is 5 %.
    spec.visual.map.fogstart = 0.0
    spec.visual.map.fogend = fog_end(attenuation)
    spec.visual.map.zfar = max(float(spec.visual.map.zfar), 4.0)
    spec.stat.extent = max(float(spec.stat.extent), 1.5 * distance)
    # The overview camera sees both vehicles: off to the side and above the midpoint.
    # (half the link to the side with an 80 deg field: each end 45 deg off its axis, as
    # near as the whole link allows; in turbid water the fog hides them, as it would)
    cam = spec.camera("overview")
    eye = mid + np.array([0.0, -0.5 * distance - 1.5, 0.12 * distance + 0.6])
    eye[2] = min(eye[2], receiver[2] + 0.5 * depth)  # under a wave's trough too
    cam.pos = eye.tolist()
    cam.alt.type = mujoco.mjtOrientation.mjORIENTATION_XYAXES
    cam.alt.xyaxes = _look_at(eye, mid)
    cam.fovy = 80.0
    # The seabed reaches past both ends.
    spec.geom("seabed").size = [max(20.0, 1.5 * distance), max(20.0, 1.5 * distance), 0.1]
    # The occluder (a school of fish, a diver) grows with the link and parks above it.
    half = max(0.03, OCCLUDER_PER_METRE * distance)
    plate = spec.geom("occluder_plate")
    plate.size = [0.002, half, half]
    spec.body("occluder").pos = [mid[0], mid[1], mid[2] + 0.5 + 3.0 * half]
    # The docking station under the LED: a frame and a base, for the eye only (group
    # 3: the light rays ignore it).
    tx = spec.body("transmitter")
    for name, pos, size in (("station_base", [0.35, 0.0, -1.2], [0.5, 0.5, 0.05]),
                            ("station_post", [0.35, 0.0, -0.6], [0.04, 0.04, 0.6]),
                            ("station_arm", [0.18, 0.0, 0.0], [0.17, 0.03, 0.03])):
        geom = tx.add_geom()
        geom.name, geom.type = name, mujoco.mjtGeom.mjGEOM_BOX
        geom.pos, geom.size = pos, size
        geom.group, geom.contype, geom.conaffinity = 3, 0, 0
        geom.density = 0.0
        geom.rgba = [0.55, 0.57, 0.6, 1.0]
        geom.fluid_ellipsoid = 0.0


def fog_end(attenuation: float) -> float:
    """The video's fog's far end in water of beam attenuation ``attenuation`` [m]."""
    return FOG_CONTRASTS / max(attenuation, 1e-3)


