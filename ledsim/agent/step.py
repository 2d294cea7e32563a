"""One control step, written once: sense, gate, supervise, control law, actuator.

Every loop of the project goes through :class:`ControlStep`: ``ledsim run`` (one run or
many stepped together), the shipped policy of the Gymnasium environment, and the
paper's closed-form experiments. At step t:

1. **gate**: occluded samples become missing (:class:`~ledsim.agent.gate.DropoutGate`;
   the identity for the paper's experiments, whose dropouts are given);
2. **supervise**: the supervisor runs the estimator's ``update`` and decides whether the
   estimate is trusted, or whether its acquisition scan has the motor
   (:class:`~ledsim.agent.supervisor.LinkSupervisor`; :class:`Unsupervised` trusts the
   estimator as it is);
3. **control law**: the input u [rad/s^2] from the estimate; during the warm-up the
   motor holds its encoder angle instead, and while scanning the scan drives it;
4. **actuator**: the supervisor runs the estimator's ``predict`` with the u the motor
   gives, and u becomes a motor command (:class:`GimbalMotor` in MuJoCo,
   :class:`DirectInput` for the closed-form model). The step keeps one unit, u = phi''
   [rad/s^2], from the acquisition, the warm-up hold and the law to the motor's limit;
   only its last line turns u into a torque.

With the vehicle's measurement of the line of sight (``los``, a
:class:`~ledsim.agent.autopilot.LineOfSight`: the IMU, the DVL and the encoder), the
step also stabilises the line of sight: the motor command carries the torque that
turns the gimbal with the LED's bearing (feed-forward of its measured acceleration),
the estimator's ``predict`` is told the input phi'' really gets (the hull's part plus
the motor's, after the torque limit: a known input), and the supervisor, the scan and
the warm-up hold see the encoder in the line of sight's frame (the encoder angle less
the bearing the hull's motion turned), so the angle they remember still points at the
LED after the hull has moved.

The sensor reading (step 0) and the physics tick (after the step) belong to the world
that runs the loop (:class:`~ledsim.physics.world_rows.WorldRows` in MuJoCo).

Axes: the encoder angle and rate, u and the torque are values over the gimbal's axes
(:mod:`ledsim.agent.axes`): floats for the paper's one axis, arrays of shape (n_axes,)
for more, with the estimate (angles, rates). The step, the laws, the motor and the
minimum-time slew are written once for both. The link supervisor, its scan and its fix
read a pair of photodiodes on one axis; a head of more axes runs :class:`Unsupervised`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ledsim.agent.axes import angles_rates, clip, magnitude
from ledsim.agent.laws import ControlLaw
from ledsim.constants import LinkConstants
from observer.supervision.gimbal_load import LoadObserver

__all__ = ["ControlStep", "Decision", "DirectInput", "GimbalMotor", "LoadObserver",
           "Unsupervised", "identity_gate"]


@dataclass
class Decision:
    """What the supervisor decided at one step.

    Attributes:
        xhat: the estimate (phi [rad], phidot [rad/s]; over n axes the n angles, then
            the n rates).
        lost: the estimate is not trusted (inconsistent with the data, or scanning).
        acquiring: the acquisition scan has the motor.
        u: the acquisition's input, phi'' [rad/s^2], per axis (None: the control law
            decides).
        reseeded: the acquisition handed over this step (the estimator restarted from
            it, or kept as it is: the oracle, a weak-light hand-over); the control law
            starts afresh.
        reason: why the link is lost ("" when it is not).
        held: while the link is lost, the estimate the run reports instead of the
            estimator's own ``xhat``: the last trusted one carried on the encoder (None:
            the estimator's own stands, or nothing was trusted yet).
        held_std: the standard deviation of ``held`` per state (that of the last
            trusted estimate: the encoder carries it without adding to it; None: the
            estimator has no covariance, or nothing is held).
    """

    xhat: np.ndarray
    lost: bool
    acquiring: bool = False
    u: float | np.ndarray | None = None
    reseeded: bool = False
    reason: str = ""
    held: np.ndarray | None = None
    held_std: np.ndarray | None = None

    @property
    def reported(self) -> np.ndarray:
        """The estimate the run reports: ``held`` while there is one, else ``xhat``."""
        return self.xhat if self.held is None else self.held


class Unsupervised:
    """The supervisor of a run without supervision: the estimator alone, always trusted.

    With ``slew`` (a :class:`~ledsim.agent.slew.TimeOptimalSlew`), the run starts by
    slewing the encoder to where the estimate puts the alignment target ``phi_ref``
    [rad] (the oracle's minimum-time acquisition: its estimate is the truth), hands
    over to the control law on arrival (within ``arrive_tol`` [rad], under
    ``arrive_rate`` [rad/s]), and slews again whenever the estimate is more than
    ``reslew`` [rad] off the target (a kick, a hull strike). Over several axes the
    slew moves them all, and the tolerances hold on each.
    """

    def __init__(self, estimator, slew=None, phi_ref: float = 0.0,
                 arrive_tol: float = 0.005, arrive_rate: float = 0.3,
                 reslew: float = 0.1):
        self.estimator = estimator
        self.slew = slew
        self.phi_ref = phi_ref
        self.arrive_tol, self.arrive_rate = arrive_tol, arrive_rate
        self.reslew = reslew
        self.slewing = slew is not None

    #: The powers reach the estimator as they are (a link supervisor rescales them).
    gain_ratio = 1.0

    @property
    def outside_domain(self) -> bool:
        """The estimator's :attr:`~observer.estimator.Estimator.outside_domain`."""
        return self.estimator.outside_domain

    def step(self, t: float, y: np.ndarray, q: float, qdot: float) -> Decision:
        xhat = self.estimator.update(y)
        if self.slew is None:
            return Decision(xhat, False)
        phi, phidot = angles_rates(xhat)
        if not isinstance(phi, np.ndarray):
            phi = float(phi)
        error = phi - self.phi_ref  # phi = phi_home - q: the encoder's way to go
        if not self.slewing:
            if magnitude(error) <= self.reslew:
                return Decision(xhat, False)
            self.slewing = True
        if magnitude(error) < self.arrive_tol and magnitude(phidot) < self.arrive_rate:
            self.slewing = False
            return Decision(xhat, False, reseeded=True, reason="acquired")
        return Decision(xhat, False, True, self.slew.command(q, qdot, q + error),
                        reason="acquiring")

    def predict(self, u) -> None:
        self.estimator.predict(u)


class GimbalMotor:
    """The gimbal's motor seen from the paper's input u [rad/s^2].

    The control step works in u throughout; the motor turns it into a torque once, at
    the end: phi = phi_home - q, so a torque tau gives phi'' = -tau / I, and
    ``torque(u) = -I u``. The torque limit is ``u_limit = limit / I`` in u. Over several
    axes each has its motor: ``inertia`` (and ``q_hold``) one per axis, and u, the
    torque and the encoder arrays of that many (:mod:`ledsim.agent.axes`).

    Args:
        inertia: the gimbal's inertia about the hinge [kg m^2] (an array: one per axis).
        q_hold: encoder angle [rad] the motor holds during the warm-up.
        hold_gains: PD gains of that hold (1/s^2, 1/s): 10 rad/s of bandwidth.
        limit: the motor's torque limit [N m].
    """

    def __init__(self, inertia: float, q_hold: float = 0.0,
                 hold_gains: tuple[float, float] = (400.0, 40.0), limit: float = math.inf):
        if np.ndim(inertia):
            inertia = np.asarray(inertia, dtype=float)
        self.inertia = inertia
        self.n_axes = int(np.size(inertia))
        self.q_hold = q_hold
        self.hold_gains = hold_gains
        self.limit = limit
        self.u_limit = limit / inertia  # [rad/s^2]

    def applied(self, u: float) -> float:
        """The u [rad/s^2] the motor gives for a commanded ``u`` (clipped at its limit)."""
        return clip(u, -self.u_limit, self.u_limit)

    def torque(self, u: float) -> float:
        """Motor torque [N m] that commands angular acceleration ``u`` [rad/s^2] of phi,
        within the limit, as the motor takes it: a duty in [-1, 1] times the limit (the
        Gymnasium env's action), so an agent that sends that duty applies the same
        torque to the last bit."""
        tau = -self.inertia * u
        if not math.isfinite(self.limit):
            return tau
        return self.limit * clip(tau / self.limit, -1.0, 1.0)

    def acceleration(self, torque: float) -> float:
        """The u [rad/s^2] a motor torque [N m] commands (an agent's torque, say)."""
        return -torque / self.inertia

    def hold(self, q: float, qdot: float) -> float:
        """Warm-up input u [rad/s^2]: PD on the encoder angle ``q`` [rad] and rate
        ``qdot`` [rad/s] (q'' = -u)."""
        kp, kd = self.hold_gains
        return kp * (q - self.q_hold) + kd * qdot


class DirectInput:
    """The closed-form model's actuator: the command is u itself; no warm-up hold."""

    def torque(self, u: float) -> float:
        return u

    def applied(self, u: float) -> float:
        return u

    def hold(self, q: float, qdot: float) -> float:
        return 0.0


def identity_gate(y: np.ndarray) -> np.ndarray:
    """No gate: every sample passes as it is."""
    return y


class ControlStep:
    """sense -> gate -> supervise -> control law -> actuator, for one run.

    Args:
        gate: ``gate(y) -> y`` with occluded samples NaN.
        supervisor: ``step(t, y, q, qdot) -> Decision`` (runs the estimator's update)
            and ``predict(u)``.
        law: the control law template (a fresh copy starts now and after a re-seed).
        constants: the link (binds the law).
        actuator: its limit in u, the warm-up hold, and the torque of a u.
        warmup: no control-law input before this time [s].
        model: the one-step model of the gimbal (``f``) for the load observer of runs
            with the vehicle's sensors (None: no load observer).

    After a call, :attr:`decision` and :attr:`u` hold what the step decided.
    """

    def __init__(self, gate: Callable[[np.ndarray], np.ndarray], supervisor,
                 law: ControlLaw, constants: LinkConstants, actuator, warmup: float = 0.0,
                 model=None):
        self.gate = gate
        self.supervisor = supervisor
        self.law_template = law
        self.constants = constants
        self.law = law.start(constants)
        self.actuator = actuator
        self.warmup = warmup
        self.decision: Decision | None = None
        self.u = 0.0
        self.y_gated: np.ndarray | None = None  # what the gate passed on this step
        self._holding, self._last_command = False, 0.0
        # The load it believes is at most what the motor can cancel.
        limit = getattr(actuator, "u_limit", math.inf)
        self.load = None if model is None else LoadObserver(
            model, max_load=limit if math.isfinite(limit) else None)
        self._motor_u = 0.0  # the phi'' the motor gave last step [rad/s^2]

    @property
    def estimator(self):
        return self.supervisor.estimator

    def _decide(self, y: np.ndarray, t: float, q, qdot) -> tuple[Decision, object, object]:
        """Gate, supervise and choose: (the decision, the command u [rad/s^2] before
        the motor, and the u the estimator is told of it) at encoder ``q``, ``qdot``."""
        self.y_gated = self.gate(y)
        d = self.supervisor.step(t, self.y_gated, q, qdot)
        if d.reseeded:
            self.law = self.law_template.start(self.constants)
        if d.u is not None:  # the acquisition has the motor
            u = command = d.u
        elif t < self.warmup:  # the estimator is still forgetting its initial guess
            command, u = self.actuator.hold(q, qdot), 0.0
        else:
            if self._holding and hasattr(self.law, "take_over"):
                self.law.take_over(self._last_command)
            u = command = self.law(d.xhat, t)
        self._holding = d.u is None and t < self.warmup
        self._last_command = command
        return d, command, u

    def __call__(self, y: np.ndarray, t: float, q: float = 0.0, qdot: float = 0.0,
                 los=None) -> float:
        """The motor torque [N m] (u itself for :class:`DirectInput`) of step ``t`` [s]
        from the measured powers ``y`` [W], the encoder angle ``q`` [rad] and rate
        ``qdot`` [rad/s], and (None: no vehicle sensors) the vehicle's measured line of
        sight ``los``. ``q``, ``qdot`` and the torque are floats for one axis, arrays
        of shape (n_axes,) for more."""
        if los is not None:  # the encoder in the line of sight's frame
            if isinstance(q, np.ndarray):
                raise ValueError("the vehicle's line of sight turns one axis (the pan): "
                                 "a step of several axes takes los=None")
            load = 0.0 if self.load is None else \
                self.load.update(qdot + los.hull_rate, self._motor_u)
            q, qdot = q - los.bearing, qdot - los.incidence_rate
        d, command, u = self._decide(y, t, q, qdot)
        act = self.actuator
        if los is not None:  # turn with the bearing, cancel the load; phi'' gets the rest
            command = command - los.acceleration - load
            self._motor_u = act.applied(command)
            u = self._motor_u + load + los.acceleration
        self.supervisor.predict(u)
        self.decision, self.u = d, u
        return act.torque(command)
