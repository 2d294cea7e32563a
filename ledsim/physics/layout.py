"""The receiver as data: its photodiodes and its gimbal's axes.

A :class:`ReceiverLayout` says which photodiodes the receiver head carries (the scene's
site of each, the name of its power in traces and results, and how its normal is turned
from the reference normal) and which axes the gimbal turns about (the scene's joint,
motor and encoder of each). The measurement ``y`` has one entry per photodiode, in the
layout's order; the state has an angle and a rate per axis.

The paper's receiver (eq. eq-4a) is :func:`paper_layout`: two photodiodes on one axis,
the second's normal turned by Delta phi, so that its incidence angle is phi + Delta phi.
It is the only layout the runs support: the observers' training, the control laws and
the ONNX export are built for it, and :meth:`ReceiverLayout.validate` says so for any
other. The scene builds more (:meth:`ReceiverLayout.buildable`): a second axis (tilt,
in elevation) that it lacks, with its motor and encoder, and photodiodes on it.

This module is where a series is tied to its position; everything else names them
(:meth:`ReceiverLayout.power_columns`, :meth:`ReceiverLayout.state_columns`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ledsim.errors import LedsimError


class LayoutError(LedsimError):
    """A receiver layout that cannot be built or is not supported."""


@dataclass(frozen=True)
class Photodiode:
    """One photodiode of the receiver head.

    Attributes:
        site: the scene's site at its centre, z axis along its normal (its lens geom,
            when the scene has one, is ``<site>_lens``).
        series: the name of its measured power in traces and results ("p1").
        offset: its incidence angle less the reference photodiode's [rad]: its normal
            is the reference normal turned by ``-offset`` about the gimbal's axis.
        tilt: the same about the second axis (elevation) [rad]; 0 on a one-axis gimbal.
    """

    site: str
    series: str
    offset: float
    tilt: float = 0.0


@dataclass(frozen=True)
class GimbalAxis:
    """One axis the receiver gimbal turns about.

    Attributes:
        name: what the axis is ("azimuth").
        joint, motor, encoder: the scene's hinge joint, its motor (actuator) and its
            encoder (a ``jointpos`` sensor).
        angle, rate: the names of the state's angle [rad] and rate [rad/s] about it
            (the incidence angle of the reference photodiode and its derivative).
        direction: the hinge's axis in the frame of the body before it (the hull's
            yoke for the first axis), for a joint the scene lacks and builds.
    """

    name: str
    joint: str
    motor: str
    encoder: str
    angle: str = "phi"
    rate: str = "phidot"
    direction: tuple[float, float, float] = (0.0, 0.0, 1.0)


@dataclass(frozen=True)
class ReceiverLayout:
    """The receiver's photodiodes and the gimbal's axes (see the module's text)."""

    photodiodes: tuple[Photodiode, ...]
    axes: tuple[GimbalAxis, ...]

    def __post_init__(self) -> None:
        if not self.photodiodes:
            raise LayoutError("a receiver layout needs at least one photodiode")
        if not self.axes:
            raise LayoutError("a receiver layout needs at least one gimbal axis")
        for kind, names in (("site", [p.site for p in self.photodiodes]),
                            ("series", [p.series for p in self.photodiodes]),
                            ("axis", [a.name for a in self.axes])):
            if len(set(names)) != len(names):
                raise LayoutError(f"photodiode or axis {kind} names {names!r} repeat: "
                                  "each must be unique")
        if self.n_axes < 2 and any(p.tilt for p in self.photodiodes):
            raise LayoutError("a photodiode's tilt turns it about a second axis: this "
                              "layout has one")

    @classmethod
    def from_dict(cls, d: dict) -> ReceiverLayout:
        """The layout ``dataclasses.asdict`` of one describes (JSON metadata)."""
        return cls(tuple(Photodiode(**p) for p in d["photodiodes"]),
                   tuple(GimbalAxis(**{**a, "direction": tuple(a.get("direction", (0, 0, 1)))})
                         for a in d["axes"]))

    @property
    def n_photodiodes(self) -> int:
        return len(self.photodiodes)

    @property
    def n_axes(self) -> int:
        return len(self.axes)

    @property
    def tilted(self) -> bool:
        """A photodiode's normal can leave the pan plane (a tilt offset, or a tilt axis
        that turns the head): each photodiode's azimuth and elevation are then about
        its own up (:func:`~ledsim.physics.incidence.photodiode_up`)."""
        return self.n_axes > 1 or any(p.tilt for p in self.photodiodes)

    @property
    def n_state(self) -> int:
        """An angle and a rate per axis."""
        return 2 * self.n_axes

    @property
    def offsets(self) -> tuple[float, ...]:
        """Each photodiode's incidence angle less the reference's [rad]."""
        return tuple(p.offset for p in self.photodiodes)

    @property
    def power_series(self) -> tuple[str, ...]:
        """The names of the measured powers, in the order of ``y``."""
        return tuple(p.series for p in self.photodiodes)

    @property
    def state_series(self) -> tuple[str, ...]:
        """The names of the state's entries, in the order of ``x``."""
        return tuple(n for a in self.axes for n in (a.angle, a.rate))

    @property
    def reference(self) -> int:
        """Index of the reference photodiode (offset 0, and tilt 0 where there is one:
        the boresight's data detector of a quad): its incidence angle is phi, and the
        link's data (availability, the link budget) ride on it."""
        for i, p in enumerate(self.photodiodes):
            if p.offset == 0.0 and p.tilt == 0.0:
                return i
        return self.offsets.index(0.0)

    def buildable(self) -> ReceiverLayout:
        """Refuse what the scene cannot build: more than two axes (pan, tilt)."""
        if self.n_axes > 2:
            raise LayoutError(f"{self.n_axes} gimbal axes cannot be built: the scene "
                              "turns the head about one axis (pan) or two (pan, tilt)")
        return self

    def validate(self) -> ReceiverLayout:
        """Refuse what a run cannot use yet: one axis and a photodiode with offset 0
        (the reference) are needed (the estimators and control laws have one axis)."""
        if self.n_axes != 1:
            raise LayoutError(f"{self.n_axes} gimbal axes are not supported yet: the "
                              "estimators and control laws have one axis")
        if 0.0 not in self.offsets:
            raise LayoutError(f"offsets {list(self.offsets)!r} have no reference "
                              "photodiode: one offset must be 0")
        return self

    def power_columns(self, array, suffix: str = "", prefix: str = "") -> dict[str, np.ndarray]:
        """``{prefix + series + suffix: column}`` of an array whose last axis is the
        photodiodes."""
        a = np.asarray(array)
        return {prefix + p.series + suffix: a[..., i] for i, p in enumerate(self.photodiodes)}

    def state_columns(self, array, suffix: str = "") -> dict[str, np.ndarray]:
        """``{name + suffix: column}`` of an array whose last axis is the state."""
        a = np.asarray(array)
        return {n + suffix: a[..., i] for i, n in enumerate(self.state_series)}

    def reference_power(self, array) -> np.ndarray:
        """The reference photodiode's column of an array over the photodiodes (its power,
        distance, emission angle...)."""
        return np.asarray(array)[..., self.reference]

    def angle(self, x) -> np.ndarray:
        """The first axis's angle [rad] of states ``x`` (last axis the state)."""
        return np.asarray(x)[..., 0]

    def angles(self, x) -> np.ndarray:
        """Every axis's angle [rad] of states ``x`` (angles, then rates), the axes on
        the first axis: shape ``(n_axes,) + x.shape[:-1]``."""
        return np.moveaxis(np.asarray(x)[..., :self.n_axes], -1, 0)

    def rates(self, x) -> np.ndarray:
        """Every axis's rate [rad/s] of states ``x``, the axes on the first axis."""
        return np.moveaxis(np.asarray(x)[..., self.n_axes:], -1, 0)

    def rate(self, x) -> np.ndarray:
        """The first axis's rate [rad/s] of states ``x`` (last axis the state)."""
        return np.asarray(x)[..., self.n_axes]

    def pointing_error(self, xhat, x) -> np.ndarray:
        """How far the estimates ``xhat`` point from the states ``x`` [rad]: on one axis
        the signed angle error, on more the angle between the two directions to first
        order (the root of the axes' squared errors)."""
        if self.n_axes == 1:
            return self.angle(xhat) - self.angle(x)
        return np.sqrt(np.sum(np.square(self.angles(xhat) - self.angles(x)), axis=0))


#: The paper's gimbal: one vertical hinge (azimuth), its motor and its encoder.
AZIMUTH = GimbalAxis("azimuth", "gimbal_hinge", "gimbal_motor", "gimbal_encoder")
#: The tilt of a pan-tilt head, built on the pan (``physics/head.py``). Its hinge turns
#: about -y, so that, as on the pan, a positive encoder angle turns the head towards a
#: lower line of sight: elevation = elevation_home - q, and a torque tau gives
#: elevation'' = -tau / I on both axes.
ELEVATION = GimbalAxis("elevation", "tilt_hinge", "tilt_motor", "tilt_encoder",
                       angle="theta", rate="thetadot", direction=(0.0, -1.0, 0.0))


@functools.lru_cache(maxsize=16)
def paper_layout(dphi: float) -> ReceiverLayout:
    """The paper's receiver (eq. eq-4a): photodiodes ``pd1`` (incidence angle phi) and
    ``pd2`` (phi + ``dphi`` [rad]) on the azimuth axis."""
    return ReceiverLayout((Photodiode("pd1", "p1", 0.0), Photodiode("pd2", "p2", dphi)),
                          (AZIMUTH,))


@functools.lru_cache(maxsize=16)
def quad_layout(spread: float) -> ReceiverLayout:
    """A quad on a pan-tilt head: a data detector ``pd0`` on the boresight (the
    reference: availability and the link budget ride on it), and four pointing
    photodiodes ``pq1``-``pq4`` turned by +-``spread`` [rad] in azimuth and in
    elevation, whose powers give both angles (the paper's pair, one dimension up)."""
    return ReceiverLayout((Photodiode("pd0", "p0", 0.0),
                           Photodiode("pq1", "q1", spread), Photodiode("pq2", "q2", -spread),
                           Photodiode("pq3", "q3", 0.0, spread),
                           Photodiode("pq4", "q4", 0.0, -spread)),
                          (AZIMUTH, ELEVATION))
