"""The gain-scheduled KKL's compiled path: what :class:`~observer.kkl.scheduled.ScheduledKKL`
hands to the kernels of :mod:`observer.kkl.compiled_step`, and when it cannot (a map that is
not a :class:`~observer.kkl.gainmaps.GainTableMap`, several inputs, a one-step model other
than the identified one): then each method returns None and the reference runs."""

from __future__ import annotations

import numpy as np

from observer import jit
from observer.kkl.gainmaps import GainTableMap

compiled_step = jit.lazy("observer.kkl.compiled_step")


class CompiledPath:
    """The compiled half of :class:`~observer.kkl.scheduled.ScheduledKKL` (a mixin: it
    reads the observer's state and sets it as the reference does)."""

    _constants = None  # what the kernels take, made once (_kernel_constants)

    def _kernel_constants(self) -> tuple | None:
        """What the kernels take of the model and the maps, made once (again when a map
        is replaced; None: a map is not a :class:`GainTableMap`, for the reference)."""
        k = self._constants
        if k is not None:  # the maps it was made of are still the observer's
            enc, dec, loc = k[-1]
            if enc is self.encoder_T and dec is self.decoder_T_star and \
                    loc is self.decoder_locked:
                return k
        maps = (self.encoder_T, self.decoder_T_star, self.decoder_locked)
        if not all(isinstance(m, GainTableMap) for m in maps if m is not None):
            return None
        sys_ = self.system
        loc = self.decoder_locked or self.decoder_T_star  # a stand-in when none
        out_lo = sys_.output_low
        bounded = out_lo is not None
        y_lo = np.asarray(out_lo if bounded else [0.0], dtype=float)
        y_hi = np.asarray(sys_.output_high if bounded else [0.0], dtype=float)
        coefs = getattr(sys_, "coef_phi", None), getattr(sys_, "coef_rate", None)
        # Omega compiled: the identified one-step model on one axis, a shared encoder
        identified = coefs[0] is not None and sys_.n_state == 2 and \
            self.encoder_T.shared
        self._constants = (
            self.decoder_T_star.kernel_arrays(), loc.kernel_arrays(),
            np.asarray(self._center), np.asarray(self._half),
            np.asarray(sys_.domain_low, dtype=float),
            np.asarray(sys_.domain_high, dtype=float), y_lo, y_hi, bounded,
            tuple(np.asarray(c, dtype=float) for c in coefs) if identified else None,
            maps)
        return self._constants

    def _compiled_estimate(self) -> np.ndarray | None:
        """:meth:`_estimate` in one compiled call (None: the gain must restart first,
        which the reference does)."""
        k = self._kernel_constants()
        if k is None:
            return None
        dec, loc, centre, half = k[:4]
        sch = self.schedule
        x, off, inside, locked, wide, restart = compiled_step.estimate(
            self.z, self.w, self.noise, *dec, self.decoder_locked is not None, *loc,
            centre, half, self._off, self._inside, self.system.Te, sch.settle_off,
            sch.jump, self.design.lock_box, sch.recover_gain(self.noise), self._slowest,
            sch.lock_after, sch.lock_ramp, sch.disagree)
        if restart:
            return None
        self._off, self._inside, self.locked, self._wide = off, inside, locked, wide
        return x

    def _compiled_filter(self, u) -> np.ndarray | None:
        """The filters and Omega of :meth:`predict` in one compiled call (None: not on
        the compiled path: several inputs, or another one-step model)."""
        if not isinstance(u, float | int):
            return None
        k = self._kernel_constants()
        if k is None or k[9] is None:
            return None
        W1T, b1 = self.encoder_T.kernel_arrays()[:2]
        omega = self.use_omega and u != self.u_bar
        z, outside = compiled_step.filter_step(
            self.z, self._a, self._y, self._channel, omega, self._xhat, float(u),
            self.u_bar, *k[9], k[4], k[5], W1T, b1,
            self.encoder_T.shared_weights(self.w) if omega else k[0][2][:1, :1])
        self.outside_domain = self.outside_domain or outside
        return z

    def _compiled_gain_change(self, x: np.ndarray, w: float, restart: bool
                              ) -> np.ndarray | None:
        """:meth:`set_gain`'s new z at the estimate ``x`` in one compiled call, the
        encoder's hidden layer of x shared by the two gains (None: not compiled)."""
        if self._kernel_constants() is None or not self.encoder_T.shared:
            return None
        W1T, b1, coef, log_w, _ = self.encoder_T.kernel_arrays()
        return compiled_step.gain_change(self.z, np.asarray(x, dtype=float), w, self.w,
                                         W1T, b1, coef, log_w, restart)
