"""A pan-tilt head's kinematics, for its agent: the pan turns the line of sight less
the further the tilt looks from level.

The head measures and controls its azimuth and elevation in its own frame (the quad's
photodiodes turn with it). The tilt turns the line of sight one for one; the pan, about
the vertical, turns it by cos(tilt) of its own turn, so near the pole (a node straight
below) the pan must swing far for a small step in azimuth and the azimuth's gain from
the pan fades (a gimbal's lock). The agent works in the head's frame and turns into
encoder angles and hinge commands here (the head's kinematics, :func:`pan_gain`,
:func:`to_encoder` and :func:`to_head`, are the plant's: ``physics/head.py``): a pan
offset is the azimuth's over the pan's gain, and the pan's input its share over it.
"""

from __future__ import annotations

import numpy as np

from ledsim.agent.step import ControlStep, GimbalMotor
from ledsim.physics.head import MIN_PAN_GAIN, pan_gain, to_encoder, to_head  # noqa: F401


class HeadMotor(GimbalMotor):
    """The hinges' motors commanded in the head's frame: the pan's input is its
    azimuth's over :func:`pan_gain` at the tilt of the step (:attr:`tilt`, set by
    :class:`HeadControlStep`), so the azimuth follows u as the elevation does."""

    tilt = 0.0

    def _encoder(self, u) -> np.ndarray:
        u = np.array(u, dtype=float)
        u[0] /= pan_gain(self.tilt)
        return u

    def torque(self, u):
        return super().torque(self._encoder(u))

    def applied(self, u):
        a = super().applied(self._encoder(u))
        a[0] *= pan_gain(self.tilt)
        return a

    def hold(self, q, qdot):
        u = super().hold(q, qdot)  # the encoders' PD, in the head's frame
        u[0] *= pan_gain(self.tilt)
        return u


class HeadControlStep(ControlStep):
    """:class:`ControlStep` of a pan-tilt head: its motor is told the tilt each step."""

    def __call__(self, y, t, q=0.0, qdot=0.0, los=None):
        self.actuator.tilt = float(q[1])
        return super().__call__(y, t, q, qdot, los)
