"""One axis of a quad on a pan-tilt head, on its own: the two-state system that a
one-axis observer of that axis estimates (:class:`~observer.kkl.decoupled.PerAxis`)."""

from __future__ import annotations

import bisect
import math

import numpy as np

from ledsim.physics.head_model import HeadModel
from ledsim.radiometry.optics import receiver_response, receiver_response_at
from observer import jit
from observer.noise import MeasurementNoise
from observer.system import DiscreteSystem

compiled_axis = jit.lazy("ledsim.physics.compiled_axis")


class AxisRatioModel(DiscreteSystem):
    """One axis of a quad, seen through its pair of pointing photodiodes over the data
    detector on the boresight: x = (angle, rate) of that axis, u its input, and
    y = (P_plus / P_0, P_minus / P_0), the pair's powers over the boresight's.

    Each ratio is g(angle + d) / g(angle) for the pair turned by d on that axis: the
    other axis's response and the link's gain divide out, so the axis is a two-state
    system of its own (the paper's, with ratios for powers), for a one-axis observer
    trained on a two-dimensional box (:class:`~observer.kkl.decoupled.PerAxis`).

    Args:
        head: the head's model (its dynamics, gain, noise and layout).
        axis: 0 (azimuth: the pair turned in azimuth) or 1 (elevation).
    """

    n_state = 2
    n_output = 2
    n_input = 1

    def __init__(self, head: HeadModel, axis: int):
        c = head.constants
        if axis == 1 and c.link is None:
            raise ValueError("the paper's bench measures no elevation response: its "
                             "photodiodes cannot see the tilt")
        self.head, self.axis, self.constants = head, axis, c
        self.pair, self.turns = pair_of(c.layout, axis)
        self.reference = c.layout.reference
        self.state_names = head.state_names[axis::2]
        self.output_names = tuple(f"{c.layout.photodiodes[i].series} / "
                                  f"{c.layout.photodiodes[self.reference].series}"
                                  for i in self.pair)
        # The ratios' noise at the boresight, from the powers' there [-].
        p0 = head.power_gain
        sigma = float(np.max(head.measurement_noise.std_at(np.full(head.n_output, p0))))
        ratio = self._ratios(np.zeros(1))[0]
        std = sigma / p0 * float(np.sqrt(1.0 + np.max(ratio) ** 2))
        self.set_model(c.Te, [head.domain_high[axis], head.domain_high[2 + axis]],
                       [head.process_noise_std[axis], head.process_noise_std[2 + axis]],
                       MeasurementNoise(std, 2))
        self._coef = (head.coef_angle[axis], head.coef_rate[axis])
        self._coefs = tuple(c.tolist() for c in self._coef)  # f's plain-float path
        #: (b1, b2, b3) of the rate's step, rate' = b1 rate + b2 u + b3 |rate| rate.
        self.rate_coefficients = tuple(self._coefs[1])
        self._gains = head.channel_gains.tolist()
        self._fix_grid = None  # (log ratio difference, angle) for fix(), built once

    def _ratios(self, angle) -> np.ndarray:
        r = self.constants.receiver
        g0 = receiver_response(angle, r)
        return np.stack([receiver_response(angle + d, r) / g0 for d in self.turns], axis=-1)

    def f(self, x, u=0.0):
        if np.ndim(x) == 1 and np.ndim(u) == 0:  # one sample: plain floats, ~10x faster
            angle, rate = np.asarray(x, dtype=float).tolist()  # (angle, rate)
            u, drag = float(u), abs(rate) * rate
            (a1, a2, a3), (b1, b2, b3) = self._coefs
            return np.array([angle + (a1 * rate + a2 * u + a3 * drag),
                             b1 * rate + b2 * u + b3 * drag])
        angle, rate = np.moveaxis(np.asarray(x, dtype=float), -1, 0)
        u = self.input_array(u, angle.shape)[..., 0]
        feats = np.stack([rate, u, np.abs(rate) * rate], axis=-1)
        (a, b) = self._coef
        return np.stack([angle + feats @ a, feats @ b], axis=-1)

    def compiled_f(self) -> tuple:
        """f as the compiled kernels take it (:mod:`observer.kkl.compiled_fixed`): the
        coefficients (a1, a2, a3) of the angle's step and (b1, b2, b3) of the rate's."""
        return tuple(np.array(c, dtype=float) for c in self._coef)

    def h(self, x):
        angle, _ = np.moveaxis(np.asarray(x, dtype=float), -1, 0)
        return self._ratios(angle)

    def metadata(self) -> dict:
        """The system's dimensions and box, and what its ratios are of: the axis, the
        pair's turns [rad] and the receiver's response (a checkpoint is checked
        against them)."""
        meta = super().metadata()
        meta.update(axis=self.axis, turns=[float(d) for d in self.turns],
                    receiver=dict(vars(self.constants.receiver)))
        return meta

    def fix(self, y, tolerance: float = 0.1) -> float | None:
        """The axis's angle [rad] straight from the head's powers ``y`` [W]: the pair's
        log ratio difference, log(P_plus / P_minus), is monotonic in the angle over the
        field of view (for the physical receiver's Gaussian, -4 d angle / c1^2), so it is
        inverted on a grid. None: a power is missing or not positive, the value is off
        the grid's range, or the powers disagree with one direction (the pair's log
        product off the receiver's by more than ``tolerance``: a shaded photodiode)."""
        if self._fix_grid is None:
            angle = np.linspace(-0.8, 0.8, 1601)
            r = self._ratios(angle)
            v = np.log(r[:, 0]) - np.log(r[:, 1])
            order = np.argsort(v)
            self._fix_grid = (v[order].tolist(), angle[order].tolist())
        if jit.enabled():
            out = compiled_axis.fix(np.asarray(y, dtype=float), *self._fix_numbers(),
                                    float(tolerance))
            return None if out != out else out
        # Plain floats: two ratios a step, where numpy's per-call cost was most of it.
        y = np.asarray(y, dtype=float).tolist()
        gains = self._gains
        (i, j), ref = self.pair, self.reference
        p0, pi, pj = y[ref] / gains[ref], y[i] / gains[i], y[j] / gains[j]
        if not (p0 > 0 and pi > 0 and pj > 0 and math.isfinite(p0) and math.isfinite(pi)
                and math.isfinite(pj)):
            return None
        log_plus, log_minus = math.log(pi / p0), math.log(pj / p0)
        v, angle = self._fix_grid
        value = log_plus - log_minus
        if not v[0] <= value <= v[-1]:
            return None
        k = min(max(bisect.bisect_right(v, value), 1), len(v) - 1)
        fix = angle[k - 1] + (angle[k] - angle[k - 1]) * (value - v[k - 1]) / (v[k] - v[k - 1])
        # The pair's product over the detector's square is the receiver's own at the fix
        # (for a Gaussian a constant, exp(-2 d^2 / c1^2)): a photodiode that an edge
        # shades, or that the light outside the beam fills, breaks it.
        r = self.constants.receiver
        g0 = receiver_response_at(fix, r)
        expected = sum(math.log(receiver_response_at(fix + d, r) / g0) for d in self.turns)
        if abs(log_plus + log_minus - expected) > tolerance:
            return None
        return fix

    def _fix_numbers(self) -> tuple:
        """:func:`~ledsim.physics.compiled_axis.fix`'s constants, built once."""
        if getattr(self, "_fix_kernel", None) is None:
            r = self.constants.receiver
            (i, j), grid = self.pair, self._fix_grid
            self._fix_kernel = (np.array(self._gains), i, j, self.reference,
                                *(np.array(g) for g in grid),
                                np.array(self.turns, dtype=float),
                                np.array([r.a1, r.b1, r.c1, r.a2, r.b2, r.c2], dtype=float))
        return self._fix_kernel

    def step_form(self):
        """f and h for an exported observer (:class:`observer.kkl.export.StepForm`): h
        the pair's responses over the data detector's."""
        from dataclasses import replace

        from ledsim.radiometry.optics import step_form

        form = step_form(*self._coef, 1.0, self.constants, (0.0, 0.0), (1e300, 1e300))
        return replace(form, offsets=tuple(float(d) for d in self.turns), ratio_to=0.0)

    def split(self, y) -> np.ndarray:
        """This axis's outputs from the head's powers ``y`` [W], each channel first
        divided by its calibrated gain (the head model's ``channel_gains``)."""
        y = np.asarray(y, dtype=float)
        g = self.head.channel_gains
        if y.ndim == 1:  # one sample (the step's): the same divisions in plain floats
            v, g = y.tolist(), g.tolist()
            (i, j), ref = self.pair, self.reference
            p0 = v[ref] / g[ref] if g[ref] else 0.0
            if p0 and g[i] and g[j]:  # no zero to divide by (numpy's inf or NaN there)
                return np.array([v[i] / g[i] / p0, v[j] / g[j] / p0])
            g = self.head.channel_gains
        y = y / g
        return y[..., list(self.pair)] / y[..., self.reference, None]


def pair_of(layout, axis: int) -> tuple[tuple[int, int], tuple[float, float]]:
    """The photodiodes turned on ``axis`` alone (0: azimuth, by their offsets; 1:
    elevation, by their tilts) and how far: ((i, j), (d_i, d_j)) [rad]."""
    found = [(i, p.offset if axis == 0 else p.tilt)
             for i, p in enumerate(layout.photodiodes)
             if (p.offset if axis == 0 else p.tilt) != 0.0
             and (p.tilt if axis == 0 else p.offset) == 0.0]
    if len(found) != 2:
        raise ValueError(f"the layout has {len(found)} photodiodes turned on axis {axis} "
                         "alone: a pair is needed")
    return (found[0][0], found[1][0]), (found[0][1], found[1][1])
