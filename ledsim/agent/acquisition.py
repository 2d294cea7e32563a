"""Finding the beam again: an acquisition scan of the gimbal, as in pointing-acquisition-
tracking (PAT) terminals, and a re-seed of the observer from what the scan saw.

The scan first brings the gimbal's encoder angle back to the last angle where the link
was trusted and waits there for ``dwell`` s (an occluded beam comes back where it was; a
kicked gimbal meets the beam on the way back), then sweeps back and forth around it at
a constant speed, widening by ``widen`` rad every half sweep, up to a full turn.

Re-seeding uses a physical invariant of the two-photodiode head: both photodiodes see
the same transmitter gain (attenuation, spreading, LED pattern), so the pair of powers
fixes phi whatever the distance. :func:`fit_incidence_angle` fits the last samples of
the scan, moved to the present through the encoder, by least squares over phi with the
gain free.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from ledsim.agent.axes import clip
from ledsim.constants import LinkConstants
from ledsim.radiometry.optics import receiver_response


@dataclass
class ScanFit:
    """Result of :func:`fit_incidence_angle`.

    Attributes:
        phi: incidence angle of photodiode 1 now [rad].
        gain: transmitter gain seen by the head [W] (a exp(-b d) I(theta) / d^2).
        chi2: residual sum of squares over the noise variance, per sample [-].
    """

    phi: float
    gain: float
    chi2: float


#: Candidate incidence angles of the fit [rad]: the receiver's main lobe and beyond.
_PHI_GRID = np.linspace(-0.9, 0.9, 721)


def fit_incidence_angle(powers: np.ndarray, shift: np.ndarray, c: LinkConstants,
                        noise_std: float) -> ScanFit:
    """Least-squares phi now from samples ``powers`` (n, 2) [W] taken when phi was
    ``phi + shift`` (``shift`` (n,) [rad], from the encoder), with the gain free."""
    phi = _PHI_GRID[:, None] + shift[None, :]  # (grid, n)
    g = np.stack([receiver_response(phi, c.receiver),
                  receiver_response(phi + c.dphi, c.receiver)], axis=-1)  # (grid, n, 2)
    gy = np.einsum("gnk,nk->g", g, powers)
    gg = np.einsum("gnk,gnk->g", g, g)
    gain = np.maximum(gy / np.maximum(gg, 1e-12), 0.0)
    sse = np.einsum("gnk,gnk->g", powers[None] - gain[:, None, None] * g,
                    powers[None] - gain[:, None, None] * g)
    best = int(np.argmin(sse))
    return ScanFit(float(_PHI_GRID[best]), float(gain[best]),
                   float(sse[best] / (noise_std**2 * powers.size)))


def follow(q, qdot, q_ref, feed, gains: tuple[float, float], cap: float):
    """The input u = phi'' [rad/s^2] (q'' = -u) that brings encoder angles ``q`` [rad],
    at rates ``qdot`` [rad/s], onto a scan's reference ``q_ref`` moving at ``feed``
    [rad/s]: a cascade, the position error to a rate target capped at ``cap`` (so a
    kicked gimbal comes back no faster than the scan), the rate error to the input; per
    axis (:mod:`ledsim.agent.axes`), with the gains (kp [1/s^2], kd [1/s])."""
    kp, kd = gains
    rate_ref = clip(feed + kp / kd * (q_ref - q), -cap, cap)
    return kd * (qdot - rate_ref)


class AcquisitionScan:
    """Back-and-forth scan of the gimbal encoder, and beam detection during it.

    Args:
        constants: the link (Te, the receiver response, dphi).
        gains: encoder gains (kp [1/s^2], kd [1/s]): a rate loop
            of bandwidth kd under a position loop of bandwidth kp / kd.
        speed: scan speed of the encoder angle [rad/s].
        widen: growth of the scan's half-width every half sweep [rad].
        window: samples the re-seed fits [s].
        detect_sigmas: mean power of the window, over its standard error, that counts
            as the beam seen [-].
        centre_margin: largest |phi| [rad] re-seeded from (the estimators' domain).
        dwell: time spent going back to, and waiting at, the centre before sweeping [s].
        max_hold: longest stop on light that does not yet give a re-seed [s].
    """

    def __init__(self, constants: LinkConstants,
                 gains: tuple[float, float] = (100.0, 20.0), speed: float = 0.4,
                 widen: float = 0.15, window: float = 0.2, detect_sigmas: float = 8.0,
                 centre_margin: float = 0.45, dwell: float = 1.0, max_hold: float = 0.5):
        self.c = constants
        self.gains = gains
        self.speed = speed
        self.widen = widen
        self.n_window = max(3, int(round(window / constants.Te)))
        self.detect_sigmas = detect_sigmas
        self.centre_margin = centre_margin
        self.dwell = dwell
        self.max_hold = max_hold
        self.active = False
        self.samples: deque = deque(maxlen=self.n_window)  # (powers [W], encoder [rad])

    def start(self, q_centre: float, q_now: float, dwell: float | None = None) -> None:
        """Begin scanning around encoder angle ``q_centre`` [rad] from ``q_now``, first
        going back and waiting there for ``dwell`` s (None: the scan's own)."""
        self.active = True
        self.centre = q_centre
        self.q_ref = q_now
        self.half_width = self.widen
        self.elapsed = 0.0 if dwell is None else self.dwell - dwell
        self.held = 0.0
        self.direction = 1.0 if q_now <= q_centre else -1.0

    def stop(self) -> None:
        self.active = False

    def command(self, q: float, qdot: float, noise_std: float) -> float:
        """The input u = phi'' [rad/s^2] (q'' = -u) that follows the scan; advances the
        reference by Te.

        Where the last few samples show light (``noise_std`` [W] sets the bar), the scan
        holds still for up to ``max_hold`` s, so the re-seed's window fills on the beam.
        """
        self.elapsed += self.c.Te
        if self._light_seen(noise_std) and self.held < self.max_hold:
            self.held += self.c.Te
            self.q_ref = q
            return self._follow(q, qdot, 0.0)
        step = self.speed * self.c.Te
        if self.elapsed < self.dwell:
            # First back to the centre, and wait there: an occluded beam comes back
            # where it was, and a kicked gimbal finds it on the way.
            gap = self.centre - self.q_ref
            self.q_ref = self.centre if abs(gap) <= step else self.q_ref + math.copysign(
                step, gap)
            feed = 0.0 if self.q_ref == self.centre else math.copysign(self.speed, gap)
            return self._follow(q, qdot, feed)
        edge = self.centre + self.direction * self.half_width
        if abs(edge - self.q_ref) <= step:
            self.q_ref = edge
            self.direction = -self.direction
            self.half_width = min(self.half_width + self.widen, math.pi)
        else:
            self.q_ref += math.copysign(step, edge - self.q_ref)
        return self._follow(q, qdot, self.direction * self.speed)

    def _light_seen(self, noise_std: float, n: int = 3) -> bool:
        if len(self.samples) < n:
            return False
        total = sum(float(np.sum(self.samples[-k][0])) for k in range(1, n + 1)) / n
        return total > self.detect_sigmas * noise_std * math.sqrt(2.0 / n)

    def _follow(self, q: float, qdot: float, feed: float) -> float:
        return follow(q, qdot, self.q_ref, feed, self.gains, 1.25 * self.speed)

    def record(self, y: np.ndarray, q: float) -> None:
        """Keep the gated powers ``y`` [W] seen at encoder angle ``q`` [rad] (every step,
        scanning or not: a loss with the beam in view is re-seeded without a scan)."""
        y = np.asarray(y, dtype=float)
        if np.all(np.isfinite(y)):
            self.samples.append((y, q))
        else:
            self.samples.clear()

    def fit(self, noise_std: float) -> ScanFit | None:
        """phi now, fitted to the recorded window, once the beam is seen well enough to
        re-seed from (else None). ``noise_std``: measurement noise [W]."""
        if len(self.samples) < self.n_window:
            return None
        q = self.samples[-1][1]
        powers = np.array([s[0] for s in self.samples])
        stderr = noise_std * math.sqrt(2.0 / len(powers))
        if powers.sum(axis=1).mean() < self.detect_sigmas * stderr:
            return None
        # phi = phi_home - q (hull still over the window): phi_k = phi_now + (q_now - q_k).
        shift = q - np.array([s[1] for s in self.samples])
        fit = fit_incidence_angle(powers, shift, self.c, noise_std)
        if abs(fit.phi) > self.centre_margin or fit.chi2 > 4.0:
            return None
        return fit
