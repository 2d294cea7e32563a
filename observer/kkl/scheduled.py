"""A KKL observer that tunes its own gain: maps learned over a continuous range of
filter gains, and a schedule that slows the filters as the estimate settles.

A fixed filter bank averages the noise over about its slowest time constant, while a
Kalman filter's gain shrinks as it becomes sure. Here one number ``w`` (the gain) sets
the bank: at gain w each output's filters have rates from ``slowest x w`` to
``fastest`` (:class:`~observer.kkl.scheduled_design.ScheduledDesign`), eigenvalues
``l_i(w) = 1 - Te r_i(w)``. The encoder ``T(x; w)`` and the decoder ``T*(z; w, s)``
are learned for every ``w`` of a range (and every noise level ``s``), in the averaged
coordinates

    z_i' = l_i(w) z_i + (1 - l_i(w)) y_j(i)        (each z_i an average of one power)

so ``z`` keeps the size of ``y`` whatever ``w`` is. The schedule starts fast (the
initial guess is forgotten in a fraction of a second) and slows down as the time since
the last (re)start grows, like a Kalman filter's 1/k gain, to a floor set by the
measured noise level. When ``w`` changes, ``z`` moves with it by the encoder's own
change at the current estimate, ``z += T(x_hat; w') - T(x_hat; w)`` (the input
correction Omega, with ``w`` as the input), so what ``z`` has averaged is kept. Near
the operating point a second decoder, trained on states near it, takes over once the
estimate has settled there. (Buisson-Fenet et al., "Towards gain tuning for numerical
KKL observers", learn T as a function of the gain; ``docs/observer.md``.)
"""

from __future__ import annotations

import math

import numpy as np

from observer import jit
from observer.estimator import Estimator, usable_mask
from observer.kkl.gainmaps import GainTableMap
from observer.kkl.scheduled_compiled import CompiledPath
from observer.kkl.scheduled_design import GainSchedule, ScheduledDesign
from observer.system import DiscreteSystem

compiled_step = jit.lazy("observer.kkl.compiled_step")

__all__ = ["GainSchedule", "ScheduledDesign", "ScheduledKKL"]


class ScheduledKKL(CompiledPath, Estimator):
    """The gain-scheduled KKL observer (numpy inference; its step runs compiled where
    :func:`observer.jit.enabled`, :class:`~observer.kkl.scheduled_compiled.CompiledPath`).

    Args:
        system: what it computes with (f for Omega, h for missing samples, Te).
        design: the family of banks.
        encoder_T: x -> z at gain w (:class:`~observer.kkl.gainmaps.GainTableMap`).
        decoder_T_star: z -> x at gain w and noise s, for a state anywhere in the domain.
        decoder_locked: the same for a state near the operating point (the design's
            ``lock_box``), used while the first one's estimate is well inside that box
            (None: never).
        schedule: the gain schedule.
        u_bar: the constant input the maps were learned for.
        use_omega: apply the Omega(z, u) correction when u != u_bar.
    """

    name = "kkl"

    def __init__(self, system: DiscreteSystem, design: ScheduledDesign, encoder_T: GainTableMap,
                 decoder_T_star: GainTableMap, decoder_locked: GainTableMap | None = None,
                 schedule: GainSchedule | None = None, u_bar: float = 0.0,
                 use_omega: bool = True):
        super().__init__(system)
        design.check_stable(system.Te)
        self.design = design
        self.encoder_T, self.decoder_T_star = encoder_T, decoder_T_star
        self.decoder_locked = decoder_locked
        #: How much of the estimate is the locked decoder's (0: none, 1: all) [-].
        self.locked = 0.0
        self.schedule = schedule or GainSchedule()
        self.u_bar, self.use_omega = float(u_bar), use_omega
        self._channel = design.channel()
        # The box in plain floats: the per-step distances below are of two numbers.
        self._center = system.domain_center.astype(float).tolist()
        self._half = np.asarray(system.domain_halfwidth, dtype=float).tolist()
        self.noise = 1.0  # measurement noise over the nominal, in the model's gain
        self._constants = None  # the compiled path's (_kernel_constants)
        self.reset()

    @property
    def q(self) -> int:
        return self.design.q

    def clip(self, w: float) -> float:
        lo, hi = self.design.w_range
        return min(max(w, lo), hi)

    # -- the maps (batched) ----------------------------------------------------------

    def encode(self, x, w=None) -> np.ndarray:
        """z = T(x; w) (default: the current w)."""
        return self.encoder_T(np.asarray(x, dtype=float), self.w if w is None else w)

    def decode(self, z, w=None, noise=None) -> np.ndarray:
        """x_hat = T*(z; w, s) (default: the current w and noise)."""
        return self.decoder_T_star(np.asarray(z, dtype=float), self.w if w is None else w,
                                   self.noise if noise is None else noise)

    def _enc(self, x: np.ndarray, w: float) -> np.ndarray:
        return self.encoder_T(x, w)

    # -- the gain ----------------------------------------------------------------------

    def adapt_noise(self, noise_ratio: float, y=None):
        """:meth:`set_noise`; the estimate stays (the gain follows at its next step)."""
        self.set_noise(noise_ratio)
        return None

    def set_noise(self, noise: float) -> None:
        """The measurement noise over the nominal [-] the powers now carry (in the
        model's gain): sets the schedule's floor and the decoder's noise input."""
        lo, hi = self.design.noise_range
        self.noise = min(max(float(noise), lo), hi)

    def set_gain(self, w: float, x: np.ndarray | None = None, restart: bool = False) -> None:
        """Run at gain ``w`` from now on; z moves by T(x; w) - T(x; w_old) at the
        estimate ``x`` (default: the latest), so the estimate carries on and z keeps
        what it has averaged. ``restart``: z = T(x; w) instead, forgetting the rest (a
        jump of the gain after a kick: z's memory is of another motion, and carried
        over it sent the estimate off by radians)."""
        w = self.clip(float(w))
        if w == self.w:
            return
        x = self._xhat if x is None else x
        if x is not None:
            z = self._compiled_gain_change(x, w, restart) if jit.enabled() else None
            if z is None:
                z = self._enc(x, w) if restart else \
                    self.z + self._enc(x, w) - self._enc(x, self.w)
            self.z = z
        self._gain(w)

    def _gain(self, w: float) -> None:
        self.w = w
        if jit.enabled():
            d = self.design
            rates = compiled_step.rate_vector(d.slowest, d.fastest, d.n_rates, d.n_output, w)
            self._a, self._slowest = self.system.Te * rates, float(rates[0])
            return
        self._a = self.system.Te * self.design.rate_vector(w)
        self._slowest = self.design.rates(w)[0]

    def _box_distance(self, x: np.ndarray, centre) -> float:
        """max_i |x_i - centre_i| / halfwidth_i [-] (NaN if any is), as numpy's max of
        the array computes it."""
        d = [abs(v - c) / h for v, c, h in zip(x.tolist(), centre, self._half, strict=True)]
        return math.nan if any(v != v for v in d) else max(d)

    def _estimate(self) -> np.ndarray:
        """The wide decoder's estimate, blended into the locked decoder's once it has
        stayed inside half the locked box for ``lock_after`` slowest time constants (z
        then holds no memory of a state outside it), over ``lock_ramp`` [s]; released
        when it leaves three quarters of the box. While the estimate is outside the box
        (converging, a slew, a kick) the gain is at least ``recover``: the filters slow
        down only near the operating point (a slow bank during a slew lost the link in
        every seed). These tests read the estimate's distance from the operating point
        averaged over ``settle_off`` [s], so that a weak link's noise does not trip
        them, or at once for a jump of ``jump`` boxes (a kick)."""
        if jit.enabled():
            x = self._compiled_estimate()
            if x is not None:
                return x
        sys_, box, sch = self.system, self.design.lock_box, self.schedule
        x = self.decoder_T_star(self.z, self.w, self.noise)
        off = self._box_distance(x, self._center)
        self._off += min(sys_.Te / sch.settle_off, 1.0) * (off - self._off)
        jump = off > sch.jump * box
        self._wide = self._off > box or jump  # the clock holds (see predict)
        if self._wide and self.w < sch.recover_gain(self.noise):
            self.set_gain(sch.recover_gain(self.noise), x, restart=True)
            x = self.decoder_T_star(self.z, self.w, self.noise)
        if self._off > 0.75 * box or jump:
            self._inside = 0.0
        elif self._off <= 0.5 * box:
            self._inside += sys_.Te
        memory = sch.lock_after / self._slowest
        self.locked = 0.0 if self.decoder_locked is None else \
            min(max((self._inside - memory) / sch.lock_ramp, 0.0), 1.0)
        if self.locked > 0:
            near = self.decoder_locked(self.z, self.w, self.noise)
            if self._box_distance(near, x.tolist()) > sch.disagree:
                # Powers the model does not explain (a gain or a parallax error of a
                # moving hull) put z off the locked decoder's training states, where
                # it extrapolates: its rate ran the other way from the true one, and
                # the loop followed it off by radians. Back to the wide decoder, and
                # to a fresh stay inside the box.
                self._inside, self.locked = 0.0, 0.0
            else:
                x = x + self.locked * (near - x)
        return x

    # -- Estimator interface ---------------------------------------------------------

    def reset(self, x0=None, covariance=None) -> None:
        """Start again, fast: the schedule's clock restarts (no covariance to set)."""
        self.k, self._inside, self.locked, self._off = 0, 0.0, 0.0, 1.0
        self._drive = 0.0  # mean |u - u_bar| (GainSchedule.driven)
        self._wide = False
        self._gain(self.clip(self.schedule.gain(0.0, self.noise)))
        self._xhat, self._y = None, None
        self.outside_domain = False
        self.z = self._enc(self.initial_guess(x0), self.w)

    def update(self, y) -> np.ndarray:
        y = np.asarray(y, dtype=float)
        self._xhat = self._estimate()
        if jit.enabled() and (k := self._kernel_constants()) is not None:
            inside, usable = compiled_step.checks(self._xhat, k[4], k[5], y, k[6], k[7],
                                                  k[8])
            if usable:
                self.outside_domain, self._y = not inside, y
                return self._xhat
        self.outside_domain = not self.in_domain(self._xhat)
        ok = usable_mask(self.system, y)
        if not ok.all():  # hold the prediction: a missing power is replaced by h(x_hat)
            y = np.where(ok, y, self.system.h(self._xhat))
        self._y = y
        return self._xhat

    def predict(self, u) -> None:
        z = self._compiled_filter(u) if jit.enabled() else None
        if z is None:
            z = self._filter(u)
        self.z = z
        self._schedule(u)

    def _filter(self, u) -> np.ndarray:
        """The filters' step on the held sample, and Omega for the input ``u``: z's next
        value."""
        a = self._a  # 1 - l_i(w)
        z = self.z + a * (self._y[self._channel] - self.z)
        moved = u != self.u_bar if isinstance(u, float | int) else \
            bool(np.any(np.asarray(u, dtype=float) != self.u_bar))
        if self.use_omega and moved:
            f, xh = self.system.f, self._xhat
            driven = f(xh, u)
            self.outside_domain = self.outside_domain or not self.in_domain(driven)
            # Both states through one call, stacked as rows of one: each row's
            # products are the single vector's (a (2, n) matrix's would not be).
            both = self._enc(np.array([driven, f(xh, self.u_bar)])[:, None], self.w)
            z = z + both[0, 0] - both[1, 0]
        return z

    def _schedule(self, u) -> None:
        """The gain's clock and its schedule after a step under input ``u``."""
        self.k += 1
        sch = self.schedule
        if self._wide:  # no slowing down while the estimate is outside the locked box
            t_wide = sch.time_of(sch.recover_gain(self.noise), self.noise)
            self.k = min(self.k, int(round(t_wide / self.system.Te)))
        driven = 0.0
        if sch.driven is not None:  # nor while the motor works against a load
            Te = self.system.Te
            du = abs(u - self.u_bar) if isinstance(u, float | int) else \
                float(np.max(np.abs(np.asarray(u, dtype=float) - self.u_bar)))
            self._drive += min(Te / sch.driven_time, 1.0) * (du - self._drive)
            if self._drive > sch.driven:
                driven = self.clip(sch.driven_gain * sch.recover_gain(self.noise))
                self.k = min(self.k, int(round(sch.time_of(driven, self.noise) / Te)))
        w = max(self.clip(self.schedule.gain(self.k * self.system.Te, self.noise)), driven)
        if max(w / self.w, self.w / w) >= self.schedule.step_ratio or \
                (w != self.w and w == self.clip(self.schedule.floor(self.noise))):
            self.set_gain(w)
