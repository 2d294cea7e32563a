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

import math

import numpy as np

from ledsim.agent.step import ControlStep, GimbalMotor
from ledsim.physics.head import MIN_PAN_GAIN, pan_gain, to_encoder, to_head  # noqa: F401
from observer.supervision.gimbal_load import LoadObserver

#: How long the head holds the LED, and how far over the level it sees the beam at
#: the data detector reads, before its look tells where the node is [s], [-].
LOOK_TIME, LOOK_LEVEL = 1.0, 5.0
#: The node's direction must be known this well [rad] (three deviations) for its turn
#: to be told to the estimators (a node believed 5 m off turns wrongly by its whole
#: turn at 5 m, and the fly-by delivered 0.53 of the oracle's bits).
TURN_SPREAD = 0.05


class HeadMotor(GimbalMotor):
    """The hinges' motors commanded in the head's frame: the pan's input is its
    azimuth's over :func:`pan_gain` at the tilt of the step (:attr:`tilt`, set by
    :class:`HeadControlStep`), so the azimuth follows u as the elevation does."""

    tilt = 0.0

    def torque(self, u):
        return super().torque(to_encoder(u, (0.0, self.tilt)))

    def applied(self, u):
        return to_head(super().applied(to_encoder(u, (0.0, self.tilt))), (0.0, self.tilt))

    def hold(self, q, qdot):
        return to_head(super().hold(q, qdot), (0.0, self.tilt))  # the encoders' PD


class HeadControlStep(ControlStep):
    """:class:`ControlStep` of a pan-tilt head: its motor is told the tilt each step,
    and with the vehicle's gyro (``los``: the hull's angular rate, (3,) [rad/s] in its
    own frame) the step stabilises the head as the one-axis step does its gimbal:

    - each hinge's load (the water's torque on the head, that its model does not
      explain) is estimated from its inertial rate, the encoder's plus the hull's about
      that hinge, by a :class:`~observer.supervision.gimbal_load.LoadObserver` on that
      axis's model (``axes``), cancelled by the motor and told to the estimator as part
      of its input;
    - the supervisor sees the encoders in an inertial frame (each plus the hull's turn
      about its hinge since the start), so the angles it remembers still point at the
      LED after the hull has turned;
    - on a moving vehicle (``range_gain``: :class:`~ledsim.agent.range_gain.RangeGain`)
      the filters' model is told the gain at the range the navigation knows
      (:meth:`tell_range`), and the supervisor where the navigation puts the node
      (:meth:`tell_node`; ``home``: the encoder angles that looked at it at the start).
    """

    def __init__(self, *args, axes=None, range_gain=None, level_gain=None, home=None,
                 **kwargs):
        super().__init__(*args, **kwargs)
        self.range_gain, self.level_gain = range_gain, level_gain
        self._tracked = 0  # successive steps the head has held the LED well
        self.home = None if home is None else np.asarray(home, dtype=float).copy()
        limit = getattr(self.actuator, "u_limit", None)
        self.loads = None if axes is None else [
            LoadObserver(m, max_load=None if limit is None else float(lim))
            for m, lim in zip(axes, np.broadcast_to(limit, (len(axes),)), strict=True)]
        self._rates = None if axes is None else [a.rate_coefficients for a in axes]
        self._turned = np.zeros(2)  # the hull's turn about each hinge since the start
        self._motor_enc = np.zeros(2)  # the encoders' u the motors gave last step

    def tell_range(self, r: float, theta: float | None = None) -> None:
        """The vehicle's navigation puts the LED ``r`` [m] away now (and sees it at the
        emission angle ``theta`` [rad], when it knows the LED's axis): the filters'
        gain, and the supervisor's levels, follow."""
        if self.range_gain is not None:
            self.range_gain.tell(r, theta)
        if self.level_gain is not None and hasattr(self.supervisor, "tell_gain"):
            self.supervisor.tell_gain(self.level_gain.factor(r, theta))

    def anchor(self, r: float, theta: float) -> None:
        """The head's model's gain is the link's at range ``r`` [m] and emission angle
        ``theta`` [rad] (the start's, which it was calibrated at): the gains that
        :meth:`tell_node` tells are relative to it."""
        for g in (self.range_gain, self.level_gain):
            if g is not None:
                g.anchor(r, theta)

    def tell_node(self, view) -> None:
        """What the navigation says of the node now (a
        :class:`~ledsim.agent.node_cue.NodeView`): the supervisor's cue, in its inertial
        encoder angles (the start's look plus the LED's turn), and the gains at its
        range and emission angle (relative to :meth:`anchor`'s)."""
        if self.home is not None and hasattr(self.supervisor, "node"):
            self.supervisor.node.tell(self.home + np.asarray(view.change, dtype=float),
                                      view.spread)
        self.tell_range(view.range, view.emission_angle)

    def look(self) -> np.ndarray | None:
        """Where the head holds the LED, turned from its start's look [rad] (bearing,
        elevation), once its supervisor has tracked it :data:`LOOK_TIME` with the data
        detector at :data:`LOOK_LEVEL` times the level it sees the beam at (None: not
        so; a look at a beam's edge is a poor one)."""
        sup = self.supervisor
        ref = self.constants.layout.reference
        steady = getattr(sup, "mode", None) == "tracking" and sup.target is not None \
            and self.y_gated[ref] >= LOOK_LEVEL * sup.seen
        self._tracked = self._tracked + 1 if steady else 0
        if self.home is None or self._tracked * self.constants.Te < LOOK_TIME:
            return None
        return sup.target - self.home

    def _turn_damping(self, qdot_in, q) -> np.ndarray:
        """What the estimator's input must add [rad/s^2] per axis so that its model
        damps the hinges' turn, not the line of sight's.

        The model's rate step, b1 r + b2 u + b3 |r| r, was fitted with the LED still,
        where the line of sight's rate r is the hinges' (s = -their inertial rate in the
        head's frame). When the LED's bearing turns too (a vehicle passing a node, at
        the navigation's turn w of the node), the head follows it and pays the damping
        on that turn, which the model would charge to r = s + w: told nothing, the
        estimates lagged the bearing by 0.03-0.08 rad on a 5 m fly-by, mostly on the
        light tilt, whose damping is 10 /s. Zero at a station (no cue: the LED's
        bearing stands still) and while the node's position is too unsure for its
        turn (:data:`TURN_SPREAD`)."""
        node = getattr(self.supervisor, "node", None)
        turn = None if node is None else node.rate
        if self._rates is None or turn is None or node.spread > TURN_SPREAD:
            return np.zeros(2)
        s = -to_head(np.asarray(qdot_in, dtype=float), q)
        r = s + to_head(np.asarray(turn, dtype=float), q)
        out = np.zeros(2)
        for i, (b1, b2, b3) in enumerate(self._rates):
            ri, si = float(r[i]), float(s[i])
            out[i] = ((1.0 - b1) * (ri - si) + b3 * (abs(si) * si - abs(ri) * ri)) / b2
        return out

    def __call__(self, y, t, q=0.0, qdot=0.0, los=None):
        act = self.actuator
        act.tilt = float(q[1])
        if los is None or self.loads is None:
            return super().__call__(y, t, q, qdot)
        wx, wy, wz = (float(v) for v in los)
        pan = float(q[0])
        # the hull's rate about the pan (its z) and about the tilt (-y turned by the pan)
        base = np.array([wz, wx * math.sin(pan) - wy * math.cos(pan)])
        load = np.array([o.update(float(qdot[i] + base[i]), float(self._motor_enc[i]))
                         for i, o in enumerate(self.loads)])
        self._turned += base * self.constants.Te
        q_in, qdot_in = q + self._turned, qdot + base
        d, command, _ = self._decide(y, t, q_in, qdot_in)
        # the load in the head's frame; none while the slew or the scan has the motors
        # (the model misses fast turns)
        load_head = to_head(load, q) if d.u is None else np.zeros(2)
        motor = act.applied(np.asarray(command, dtype=float) - load_head)
        self._motor_enc = to_encoder(motor, q)
        u = motor + load_head  # what the angles get: the motor's and the load's
        self.supervisor.predict(u + self._turn_damping(qdot_in, q))
        self.decision, self.u = d, u
        return act.torque(motor)
