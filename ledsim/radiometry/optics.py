"""LED link optics: paper eqs. (pow-d-theta-phi) and (modified-gaussian2).

    P = a exp(-b d) / d^2 * I~(theta) * g(phi)        (transmitter gain x receiver response)

All angles in rad, distances in m, powers in W. Functions broadcast over arrays.
:func:`received_power` is the one place the product is formed: the ray sensor, the
simulation's noise-free series and every observer model's ``h`` go through it.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from ledsim.constants import LinkConstants, ReceiverResponse
from observer import jit
from observer.rowops import FLOATS

compiled_pair = jit.lazy("observer.supervision.compiled_pair")


def response_terms(phi, r: ReceiverResponse, exp=np.exp):
    """(u1, u2, e1, e2) of the paper's g(phi) = e1 + e2 (eq. modified-gaussian2), with
    u1 = (phi - b1) / c1, u2 = (phi + b2) / c2 and e_i = a_i exp(-u_i^2).

    The one place the formula is written. ``exp`` evaluates it: ``np.exp`` for arrays,
    ``math.exp`` for one angle in plain floats (the per-step paths, several times
    faster), ``torch.exp`` for the exported observer's graph. g is e1 + e2 and its
    derivative dg/dphi = -2 u1 / c1 e1 - 2 u2 / c2 e2 (:func:`response_slope`).
    """
    u1, u2 = (phi - r.b1) / r.c1, (phi + r.b2) / r.c2
    return u1, u2, r.a1 * exp(-(u1 * u1)), r.a2 * exp(-(u2 * u2))


def response_slope(u1, u2, e1, e2, r: ReceiverResponse):
    """dg/dphi [1/rad] from :func:`response_terms`."""
    return -2 * u1 / r.c1 * e1 - 2 * u2 / r.c2 * e2


def receiver_response(phi, r: ReceiverResponse) -> np.ndarray:
    """g(phi): dimensionless photodiode response at incidence angle ``phi`` [rad]."""
    _, _, e1, e2 = response_terms(np.asarray(phi, dtype=float), r)
    return e1 + e2


def receiver_response_at(phi, r: ReceiverResponse, o=FLOATS):
    """g(phi) for one angle [rad] in plain floats (the per-step paths; same formula), or
    with ``o`` :data:`~observer.rowops.ARRAYS` for the angles of many worlds, each with
    libm's ``exp`` as one angle's."""
    _, _, e1, e2 = response_terms(phi, r, o.exp)
    return e1 + e2


def receiver_response_derivative(phi, r: ReceiverResponse) -> np.ndarray:
    """dg/dphi [1/rad]."""
    return response_slope(*response_terms(np.asarray(phi, dtype=float), r), r)


def led_intensity(theta, c: LinkConstants) -> np.ndarray:
    """I~(theta): Lambertian angular intensity of the LED, 1 on axis, 0 behind it."""
    cos_t = np.maximum(np.cos(np.asarray(theta, dtype=float)), 0.0)  # np.clip's bits, cheaper
    return cos_t ** c.lambertian_order


def transmitter_gain(d, theta, c: LinkConstants) -> np.ndarray:
    """The transmitter part a exp(-b d) / d^2 * I~(theta) of eq. (pow-d-theta-phi) [W]."""
    d = np.asarray(d, dtype=float)
    return c.power_scale * np.exp(-c.attenuation * d) / d**2 * led_intensity(theta, c)


def transmitter_gain_at(d, theta, c: LinkConstants, o=FLOATS):
    """:func:`transmitter_gain` for one distance [m] and angle [rad] in plain floats, or
    with ``o`` :data:`~observer.rowops.ARRAYS` for many, each as one's to the last bit."""
    cos_t = o.maximum(o.cos(theta), 0.0)
    return c.power_scale * o.exp(-c.attenuation * d) / o.square(d) * \
        o.pow(cos_t, c.lambertian_order)


def received_power(gain, incidence_angle, r: ReceiverResponse, visible=1.0) -> np.ndarray:
    """P = visible x gain x g(phi) [W].

    Args:
        gain: transmitter gain a exp(-b d) I~(theta) / d^2 [W] (:func:`transmitter_gain`).
        incidence_angle: phi [rad].
        r: the photodiode response g.
        visible: share of the LED aperture the photodiode sees (ray-traced) [-].
    """
    return visible * gain * receiver_response(incidence_angle, r)


def photodiode_power(d, theta, incidence_angle, c: LinkConstants, visible=1.0) -> np.ndarray:
    """Received optical power P_d(d, theta, phi) [W], eq. (pow-d-theta-phi)."""
    return received_power(transmitter_gain(d, theta, c), incidence_angle, c.receiver, visible)


def layout_power(gain, phi, c: LinkConstants) -> np.ndarray:
    """Outputs of the receiver's photodiodes (``c.layout``), eq. (eq-4a) for the paper's
    pair: gain x [g(phi + offset_i)] [W], i over the photodiodes.

    ``phi`` [rad] has any shape; the result has one more axis, one entry a photodiode.
    """
    phi = np.asarray(phi, dtype=float)
    return np.stack([received_power(gain, phi + offset, c.receiver)
                     for offset in c.layout.offsets], axis=-1)


def head_power(gain, azimuth, elevation, c: LinkConstants) -> np.ndarray:
    """Outputs of a receiver head's photodiodes (``c.layout``) when the line of sight
    stands ``azimuth`` and ``elevation`` [rad] from its boresight (left and up
    positive): gain x g(azimuth + offset_i) x g(elevation + tilt_i) [W], a physical
    receiver's cone taken as the same response across the pan plane as in it. The paper's
    bench measured its detectors about the hinge only: there it is gain x g(azimuth +
    offset_i), :func:`layout_power`. The angles have any (common) shape; the result has
    one more axis, one entry a photodiode."""
    az, el = np.broadcast_arrays(np.asarray(azimuth, dtype=float),
                                 np.asarray(elevation, dtype=float))
    cone = c.link is not None
    return np.stack([received_power(gain, az + p.offset, c.receiver)
                     * (receiver_response(el + p.tilt, c.receiver) if cone else 1.0)
                     for p in c.layout.photodiodes], axis=-1)


def layout_power_jacobian(gain, phi, c: LinkConstants) -> np.ndarray:
    """d(layout_power)/d(phi, phidot), shape ``phi.shape + (n_pd, 2)`` [W/rad, W s/rad]."""
    phi = np.asarray(phi, dtype=float)
    offsets = c.layout.offsets
    jac = np.zeros(np.shape(phi) + (len(offsets), 2))
    for i, offset in enumerate(offsets):
        jac[..., i, 0] = gain * response_slope(*response_terms(phi + offset, c.receiver),
                                               c.receiver)
    return jac


#: Their earlier names (the paper's pair, eq. eq-4a), kept as aliases.
pair_power, pair_power_jacobian = layout_power, layout_power_jacobian


def peak_power(c: LinkConstants) -> float:
    """Largest power one photodiode can see at the configured distance and theta [W]."""
    phi = np.linspace(-np.pi / 2, np.pi / 2, 20001)
    return float(np.max(photodiode_power(c.distance, c.theta, phi, c)))


def receiver_saturates(c: LinkConstants, noise_scale: float = 1.0) -> bool:
    """Whether the receiver saturates at the configured distance: the largest power one
    photodiode can see there (:func:`peak_power`) reaches the full scale of its
    digitiser with its detector's gain turned down (``Digitiser.saturation``; False
    without one: the paper's bench), so aligned samples clip."""
    digitiser = c.measurement_noise(noise_scale).digitiser
    return digitiser is not None and peak_power(c) >= digitiser.saturation


def nominal_noise_std(c: LinkConstants) -> float:
    """The pointing samples' noise at the configured distance's peak power [W]: the
    paper's constant noise, or a physical receiver's at that signal."""
    noise = c.measurement_noise()
    if not noise.signal_dependent:
        return c.measurement_noise_std
    return float(noise.std_at(np.array([peak_power(c)]))[0])


#: Measured powers beyond this many noise standard deviations below zero, or above twice
#: the peak, cannot come from the link: estimators treat them as missing.
IMPOSSIBLE_SIGMAS = 20.0


def achievable_power(distance, emission_angle, c: LinkConstants, peak_response: float):
    """Most photodiode 1 can receive at a distance [m] and emission angle [rad]: the
    transmitter gain there times the receiver's peak response ``peak_response`` (g at
    the intensity maximum) [W]; any shapes."""
    return transmitter_gain(distance, emission_angle, c) * peak_response


def plausible_power_range(c: LinkConstants) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) of physically possible measured powers of the photodiodes [W]."""
    sigma, n = c.measurement_noise_std, c.layout.n_photodiodes
    return (np.full(n, -IMPOSSIBLE_SIGMAS * sigma),
            np.full(n, 2.0 * peak_power(c) + IMPOSSIBLE_SIGMAS * sigma))


_SHAPE_PHI = np.linspace(-1.2, 1.2, 4801)


def pair_shape_inverse(powers, c: LinkConstants) -> tuple[float, float, float]:
    """(phi [rad], gain [W], v) that give the pair of powers ``powers`` = gain x
    [g(phi), g(phi + dphi)], from the shape log(P1 / P2), which the gain (distance,
    attenuation, LED angle) does not change. (NaN, NaN, inf) unless both powers are > 0.

    ``v`` [1/W^2]: variance of the relative gain per unit noise variance on each power,
    ``[(J^T J)^-1]_gg / gain^2`` with J the Jacobian of the pair in (phi, gain). Off the
    peak the two photodiodes see nearly the same log-slope, so the gain is poorly
    determined there and v is large.

    The log-ratio is monotonic in phi for the datasheet response (checked in the tests),
    so the inversion is a table lookup.
    """
    p1, p2 = float(powers[0]), float(powers[1])
    if not (p1 > 0 and p2 > 0):
        return math.nan, math.nan, math.inf
    table = _shape_table(c.receiver, c.dphi)
    if jit.enabled():
        r = c.receiver
        return compiled_pair.shape_inverse(p1, p2, table, _SHAPE_PHI, r.a1, r.b1, r.c1,
                                             r.a2, r.b2, r.c2, float(c.dphi))
    phi = float(np.interp(math.log(p1 / p2), table, _SHAPE_PHI))
    g1, dg1 = response_and_slope(phi, c.receiver)
    g2, dg2 = response_and_slope(phi + c.dphi, c.receiver)
    gain = (p1 * g1 + p2 * g2) / (g1 * g1 + g2 * g2)
    d1, d2 = gain * dg1, gain * dg2
    det = d1 * g2 - d2 * g1  # J = [[d1, g1], [d2, g2]]
    if det == 0 or gain <= 0:
        return phi, gain, math.inf
    v = (d1 * d1 + d2 * d2) / det**2 / gain**2
    return phi, gain, v


def pair_phi_variance(phi: float, powers, noise_std: float, c: LinkConstants) -> float:
    """Variance of the phi inverted from one pair of powers ``powers`` [W] with noise
    ``noise_std`` [W] on each, at ``phi`` [rad]: the log-ratio's noise
    sigma^2 (1/P1^2 + 1/P2^2) over its squared slope in phi there [rad^2] (inf where
    the slope vanishes)."""
    if jit.enabled():
        r = c.receiver
        return compiled_pair.phi_variance(float(phi), np.asarray(powers, dtype=float),
                                            float(noise_std), r.a1, r.b1, r.c1, r.a2, r.b2,
                                            r.c2, float(c.dphi))
    g1, dg1 = response_and_slope(phi, c.receiver)
    g2, dg2 = response_and_slope(phi + c.dphi, c.receiver)
    slope = dg1 / g1 - dg2 / g2
    if slope == 0:
        return math.inf
    return noise_std * noise_std * sum(1.0 / (p * p) for p in powers) / (slope * slope)


def pair_shape_numbers(c: LinkConstants) -> tuple:
    """The pair's shape as the compiled kernels take it
    (:mod:`observer.supervision.compiled_pair`): (the table of log(g1 / g2), its phis
    [rad], the response's a1, b1, c1, a2, b2, c2, dphi [rad])."""
    r = c.receiver
    return (_shape_table(r, c.dphi), _SHAPE_PHI, r.a1, r.b1, r.c1, r.a2, r.b2, r.c2,
            float(c.dphi))


def response_and_slope(phi: float, r: ReceiverResponse) -> tuple[float, float]:
    """(g(phi), dg/dphi) for one angle, in plain floats (the per-step paths)."""
    terms = response_terms(phi, r, math.exp)
    return terms[2] + terms[3], response_slope(*terms, r)


@functools.lru_cache(maxsize=8)
def _shape_table(r: ReceiverResponse, dphi: float) -> np.ndarray:
    return np.log(receiver_response(_SHAPE_PHI, r) / receiver_response(_SHAPE_PHI + dphi, r))


def step_form(coef_phi, coef_rate, gain: float, c: LinkConstants, output_low, output_high):
    """The :class:`observer.kkl.export.StepForm` of a system whose h is
    ``gain x [g(phi), g(phi + dphi)]`` [W] (what an exported observer computes)."""
    from observer.kkl.export import StepForm

    r = c.receiver
    return StepForm(tuple(float(v) for v in coef_phi), tuple(float(v) for v in coef_rate),
                    float(gain), (r.a1, r.b1, r.c1, r.a2, r.b2, r.c2), float(c.dphi),
                    tuple(float(v) for v in output_low), tuple(float(v) for v in output_high),
                    tuple(float(o) for o in c.layout.offsets))

