"""The link supervisor of a pan-tilt head: acquisition, loss detection, occlusion carry
and reacquisition on both axes (what :class:`~ledsim.agent.supervisor.LinkSupervisor`
is for the paper's pair on one axis).

The quad fixes the beam in one sample: each axis's pair over the data detector gives
that axis's angle (:meth:`~ledsim.physics.axis_model.AxisRatioModel.fix`), whatever the
gain. So every acquisition is a fix, a minimum-time slew to it on both hinges, and the
estimator restarted there. The encoder angles at which the head last saw the LED
(:attr:`HeadSupervisor.target`: an angle is the encoder's way to go, x = home - q) carry
the estimate while the link is lost.

==============  =============================================================
mode            what the head does
==============  =============================================================
``acquiring``   slews to the fix (renewed each step the beam is seen), then
                restarts the estimator there and tracks
``tracking``    the estimator drives the law; a data detector dark for
                ``loss_time`` declares the link lost (the dropout gate's missing
                samples count as dark)
``lost``        carries the estimate on the encoder, slews back to where the LED was
                (a kick, a hull strike) and waits there ``patience`` (an occluder);
                then spirals around it (:class:`~ledsim.agent.spiral.SpiralScan`);
                the beam seen again is a fix and an acquisition
==============  =============================================================

On the move the navigation tells where the node is each step (:attr:`HeadSupervisor.cue`,
in the same encoder angles; None: a station; :mod:`ledsim.agent.node_aim`). While
acquiring, the fixes' target moves as the cue has; otherwise the head looks at the cue,
and stares there while the LED is out of sight (the light will come from there). A fix
or an estimate far from the cue is not the LED.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from ledsim.agent.axes import angles_rates, magnitude
from ledsim.agent.node_aim import NodeAim
from ledsim.agent.pan_tilt import to_encoder, to_head
from ledsim.agent.spiral import SpiralScan
from ledsim.agent.step import Decision

#: The least the data detector must read, in the noise's standard deviations, for the
#: beam to count as seen, and under which it counts as gone: a node far out of its
#: beam, whose model's peak is under the noise, is not fixed on the noise.
SEEN_SIGMAS, DARK_SIGMAS = 6.0, 3.0


class HeadSupervisor:
    """The :mod:`supervisor <ledsim.agent.head_supervisor>` of a pan-tilt head.

    Args:
        estimator: the estimator in four states (angles, then rates).
        axes: each axis's :class:`~ledsim.physics.axis_model.AxisRatioModel` (the fix).
        slew: the minimum-time slew of both hinges
            (:class:`~ledsim.agent.slew.TimeOptimalSlew`).
        peak: the data detector's power on the boresight [W] (the model's).
        reference: the data detector's index among the powers.
        Te: the control period [s].
        seen_level, dark_level: the data detector's share of ``peak`` at which the beam
            counts as seen (a fix is taken) and as gone [-], but never under
            :data:`SEEN_SIGMAS` and :data:`DARK_SIGMAS` times ``floor``.
        floor: the noise's standard deviation without a signal [W] (0: none).
        loss_time: how long the data detector stays dark before the link is lost [s].
        patience: how long a lost head waits where the LED was before it scans [s].
        arrive_tol, arrive_rate: an acquisition arrives within this angle [rad] of the
            fix on each axis, turning slower than this [rad/s].
        reslew: a tracked estimate this far off the boresight [rad], or this far from
            the fix, is slewed to ...
        reslew_time: ... when it stays so for this long [s], each step counted by how
            many ``reslew`` it is off (a fix's noise and fading in scintillation at half
            the FEC range: 0.03 rad rms, 0.1 at worst; a kick's is more at once).
        fit_fixes: how many of the last fixes the LED's direction and turn are fitted to
            while acquiring (a least-squares line in time).
        corrects: the quad's fix corrects a tracked estimate (False: the scanning
            baselines track on the data detector alone).
    """

    def __init__(self, estimator, axes, slew, peak: float, reference: int, Te: float,
                 seen_level: float = 0.05, dark_level: float = 0.02,
                 loss_time: float = 0.05, patience: float = 0.5,
                 arrive_tol: float = 0.005, arrive_rate: float = 0.3, reslew: float = 0.1,
                 reslew_time: float = 0.05, fit_fixes: int = 8, floor: float = 0.0,
                 corrects: bool = True):
        self.estimator, self.axes, self.slew = estimator, list(axes), slew
        self.peak, self.reference, self.Te = float(peak), int(reference), Te
        self._levels = (seen_level * self.peak, dark_level * self.peak)
        self._floors, self.node = (SEEN_SIGMAS * floor, DARK_SIGMAS * floor), NodeAim(Te)
        self.tell_gain(1.0)
        self.loss_steps = max(1, int(round(loss_time / Te)))
        self.patience_steps = int(round(patience / Te))
        self.arrive_tol, self.arrive_rate, self.reslew = arrive_tol, arrive_rate, reslew
        self.corrects, self.spiral, self.mode = corrects, SpiralScan(Te), "acquiring"
        self.reslew_steps = max(1, int(round(reslew_time / Te)))
        self._off_steps = 0.0  # successive tracked steps off, each in reslew's
        self.target: np.ndarray | None = None  # encoder angles where the LED was seen
        self._dark_steps = 0
        self._blind_steps = 0  # successive acquiring steps without a fix
        self._waited = 0
        self._std: np.ndarray | None = None
        self._updated = False  # the estimator was updated this step
        self._q = np.zeros(2)  # the step's encoder angles
        self._k = 0  # the step's count
        self._seen: deque = deque(maxlen=fit_fixes)  # (step, target) of the last fixes
        self._turn: np.ndarray | None = None  # d(target)/dt from the fixes [rad/s]

    gain_ratio = 1.0  # the powers reach the estimator as they are (ratios need no gain)
    def tell_gain(self, gain: float) -> None:
        """The link's gain is ``gain`` times the model's now [-] (a vehicle on the move:
        ``agent/range_gain.py``): the levels at which the beam is seen and gone follow,
        above the noise's."""
        self.seen, self.dark = (max(level * gain, floor) for level, floor in
                                zip(self._levels, self._floors, strict=True))

    outside_domain = property(lambda self: self.estimator.outside_domain)

    # -- what the powers say ---------------------------------------------------------

    def _fix(self, y: np.ndarray) -> np.ndarray | None:
        """Both angles [rad] from the powers, when the data detector sees the beam."""
        p0 = y[self.reference]
        if not (math.isfinite(p0) and p0 >= self.seen):
            return None
        angles = [a.fix(y) for a in self.axes]
        if any(v is None for v in angles):
            return None
        angles = np.array(angles)
        if self.node.off(self._q + to_encoder(angles, self._q)):
            return None  # far from where the navigation puts the node: a shaded quad
        return angles

    def _is_dark(self, y: np.ndarray) -> bool:
        p0 = y[self.reference]
        return not math.isfinite(p0) or p0 < self.dark

    @property
    def cue(self) -> np.ndarray | None:
        """Where the navigation puts the LED now, in encoder angles [rad] (told each
        step on the move; None: a station)."""
        return self.node.cue

    @cue.setter
    def cue(self, value) -> None:
        self.node.cue = value

    def _aim(self) -> np.ndarray | None:
        return self.node.aim(self.target, self.mode == "acquiring")

    def _set_target(self, target: np.ndarray) -> None:
        self.target = target
        self.node.target_set()

    def _carried(self, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """The estimate carried on the encoder: the LED where it was last seen (moved
        with the cue)."""
        return np.r_[to_head(self._aim() - q, q), -to_head(qdot, q)]

    # The slew's and the scan's inputs per hinge, in the head's frame (the motor turns
    # them back: agent/pan_tilt.py).
    def _slew(self, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        return to_head(self.slew.command(q, qdot, self._aim(), target_rate=self.node.rate),
                       q)

    def _scan(self, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        return to_head(self.spiral.command(q, qdot), q)

    # -- the step ----------------------------------------------------------------------

    def step(self, t: float, y: np.ndarray, q, qdot) -> Decision:
        self._updated, self._k = False, self._k + 1
        self.node.observe()
        y = np.asarray(y, dtype=float)
        q, qdot = np.asarray(q, dtype=float), np.asarray(qdot, dtype=float)
        self._q = q
        if self.mode == "tracking":
            return self._track(y, q, qdot)
        fix = self._fix(y)
        if fix is not None:
            self._blind_steps = 0
            # The LED's direction in the encoder's terms, and its turn, fitted to the
            # last fixes (one fix carries the noise and the fading: docs/two_axes.md)
            self._seen.append((self._k, q + to_encoder(fix, q)))
            target, self._turn = self._fitted()
            self._set_target(target)
            fix = to_head(self.target - q, q)
            self.spiral.stop()
            if self.mode == "lost" and magnitude(fix) <= self.reslew:
                return self._restart(fix, y, qdot, "reacquired")
            self.mode = "acquiring"
            if magnitude(fix) < self.arrive_tol and self.node.settled(qdot, self.arrive_rate):
                return self._restart(fix, y, qdot, "acquired")
            # The beam is in view: the fix is the estimate, and the link stands.
            return Decision(np.r_[fix, -to_head(qdot, q)], False, True, self._slew(q, qdot),
                            reason="acquiring")
        if self.mode == "acquiring" and self.target is not None and \
                self._blind_steps + 1 < self.loss_steps:
            # A sample without a fix (a fade, the noise breaking the pair's agreement)
            # while the slew runs: the slew goes on to the last fix; no fix for
            # loss_time, and the link is lost.
            self._blind_steps += 1
            return Decision(self._carried(q, qdot), False, True, self._slew(q, qdot),
                            reason="acquiring")
        self._blind_steps = 0
        xhat = self._update(y)
        if self.target is None and self.cue is not None:  # look where the node is
            self.mode = "lost"
            return Decision(xhat, True, True, self._slew(q, qdot), reason="cued",
                            held=self._carried(q, qdot))
        if self.target is None:  # nothing seen yet: scan around where the head looks
            if not self.spiral.active:
                self.spiral.start(q)
            self.mode = "lost"
            return Decision(xhat, True, True, self._scan(q, qdot), reason="searching")
        if self.mode != "lost":  # an acquisition lost: its fixes are of before the gap
            self._seen.clear()
        self.mode = "lost"
        held = self._carried(q, qdot)
        if self.spiral.active:
            return Decision(xhat, True, True, self._scan(q, qdot), reason="scanning",
                            held=held, held_std=self._std)
        if magnitude(self._aim() - q) > self.arrive_tol or \
                not self.node.settled(qdot, self.arrive_rate):
            self._waited = 0  # back to where the LED was first
        else:
            self._waited += 1
            if self._waited > self.patience_steps and self.cue is None:
                self.spiral.start(self.target)
        return Decision(xhat, True, True, self._slew(q, qdot), reason="waiting", held=held,
                        held_std=self._std)

    def _update(self, y: np.ndarray) -> np.ndarray:
        self._updated = True
        return self.estimator.update(y)

    def _track(self, y: np.ndarray, q: np.ndarray, qdot: np.ndarray) -> Decision:
        xhat = self._update(y)
        angles, _ = angles_rates(xhat)
        if self.node.off(q + to_encoder(angles, q)):
            # on the move, an estimate far from where the navigation puts the node (a
            # beam's edge at a few noise deviations): lost, back to the cue
            self.mode, self._waited = "lost", 0
            self._seen.clear()
            return Decision(xhat, True, True, self._slew(q, qdot), reason="off cue",
                            held=self._carried(q, qdot), held_std=self._std)
        if not self._is_dark(y):
            self._dark_steps = 0
            self._set_target(q + to_encoder(angles, q))
            self._std = getattr(self.estimator, "std", None)
            fix = self._fix(y)
            # Far off the boresight (a kick), or far from what the powers say (an
            # estimate left behind): the fix takes over, and the slew.
            # Each step off adds how far off it is, in reslew's: five steps just off
            # (a noisy fix) or one far off (a kick: 0.5 rad within 30 ms) trip it.
            off = 0.0 if fix is None or not self.corrects else \
                max(magnitude(angles), magnitude(fix - angles))
            self._off_steps = self._off_steps + off / self.reslew if off > self.reslew \
                else 0.0
            if self._off_steps >= self.reslew_steps:
                self.mode, self._off_steps = "acquiring", 0.0
                return self.step(0.0, y, q, qdot)
            return Decision(xhat, False)
        self._dark_steps += 1
        if self._dark_steps < self.loss_steps:
            return Decision(xhat, False)
        self.mode, self._waited = "lost", 0
        self._seen.clear()  # the fixes before a loss say nothing of the LED's turn after
        return Decision(xhat, True, True, self._slew(q, qdot), reason="dark",
                        held=self._carried(q, qdot), held_std=self._std)

    def _fitted(self) -> tuple[np.ndarray, np.ndarray | None]:
        """The LED's encoder angles now and their rate [rad/s] (None from one fix): the
        least-squares line through the last fixes' targets."""
        if len(self._seen) == 1:
            return self._seen[0][1], None
        k = np.array([s[0] for s in self._seen], dtype=float)
        targets = np.array([s[1] for s in self._seen])
        k -= k.mean()
        mean = targets.mean(axis=0)
        slope = (k @ (targets - mean)) / (k @ k)
        return mean + slope * k[-1], slope / self.Te

    def _restart(self, fix: np.ndarray, y: np.ndarray, qdot: np.ndarray,
                 reason: str) -> Decision:
        """Restart the estimator at the fix, its rates the line of sight's turn (seen
        over the last fixes) less the encoder's, and track."""
        turn = 0.0 if self._turn is None else self._turn
        self.estimator.reset(np.r_[fix, to_head(turn - qdot, self._q)])
        self.mode, self._dark_steps, self._turn = "tracking", 0, None
        self._seen.clear()
        self._off_steps = 0.0
        return Decision(self._update(y), False, reseeded=True, reason=reason)

    def predict(self, u) -> None:
        """The estimator's predict, after a step that updated it (while the slew or
        the scan has the motor from a fix, the estimator waits)."""
        if self._updated:
            self.estimator.predict(u)
