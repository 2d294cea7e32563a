import math

import numpy as np
import pytest

from ledsim.constants import ConfigError, LinkConstants
from ledsim.paper.model import LEDLinkModel
from ledsim.radiometry.optics import (
    photodiode_power,
    receiver_response,
    receiver_response_derivative,
)


def test_power_matches_paper_formula_evaluated_by_hand():
    c = LinkConstants()
    r = c.receiver
    d, theta, phi = 0.1, 0.2, 0.13
    m = -math.log(2) / math.log(math.cos(c.led_half_angle))
    g = (r.a1 * math.exp(-(((phi - r.b1) / r.c1) ** 2))
         + r.a2 * math.exp(-(((phi + r.b2) / r.c2) ** 2)))
    expected = c.power_scale * math.exp(-c.attenuation * d) / d**2 * math.cos(theta) ** m * g
    assert photodiode_power(d, theta, phi, c) == pytest.approx(expected, rel=1e-12)


def test_g_derivative_matches_finite_difference():
    r = LinkConstants().receiver
    phi = np.linspace(-0.6, 0.6, 25)
    fd = (receiver_response(phi + 1e-6, r) - receiver_response(phi - 1e-6, r)) / 2e-6
    np.testing.assert_allclose(receiver_response_derivative(phi, r), fd, rtol=1e-6, atol=1e-8)


def test_g_is_non_monotonic_on_the_domain():
    g = receiver_response(np.linspace(-0.5, 0.5, 101), LinkConstants().receiver)
    peak = int(np.argmax(g))
    assert 0 < peak < 100


def test_second_photodiode_is_first_shifted_by_dphi(system):
    phi = np.linspace(-0.4, 0.4, 9)
    y = system.h(np.stack([phi, 0 * phi], -1))
    y_shift = system.h(np.stack([phi + system.constants.dphi, 0 * phi], -1))
    np.testing.assert_allclose(y[:, 1], y_shift[:, 0], rtol=1e-12)


def test_f_inverse_undoes_f(system, rng):
    x = system.sample_domain(rng, 50)
    u = rng.normal(size=50)
    np.testing.assert_allclose(system.f_inverse(system.f(x, u), u), x, atol=1e-14)


def test_input_is_an_angular_acceleration(system):
    x = np.array([0.1, 0.2])
    np.testing.assert_allclose(system.f(x, 3.0), [0.1 + 0.01 * 0.2, 0.2 + 0.01 * 3.0])


def test_analytic_jacobian_matches_generic_one(system, rng):
    from observer.system import DiscreteSystem

    x = system.sample_domain(rng, 5)
    np.testing.assert_allclose(system.h_jacobian(x), DiscreteSystem.h_jacobian(system, x),
                               rtol=1e-6, atol=1e-7)


def test_power_falls_with_distance():
    near = LEDLinkModel(LinkConstants(distance=0.085)).h(np.zeros(2))
    far = LEDLinkModel(LinkConstants(distance=0.2)).h(np.zeros(2))
    c = LinkConstants()
    ratio = (0.085 / 0.2) ** 2 * math.exp(-c.attenuation * (0.2 - 0.085))
    np.testing.assert_allclose(far / near, ratio, rtol=1e-12)


@pytest.mark.parametrize("field,value", [("distance", 0.0), ("distance", -1.0), ("dphi", 0.0),
                                         ("Te", 0.0), ("led_half_angle", 2.0)])
def test_bad_constants_are_rejected_by_name(field, value):
    with pytest.raises(ConfigError, match=field):
        LinkConstants(**{field: value})


def test_constants_round_trip_through_dict():
    c = LinkConstants(distance=0.2)
    assert LinkConstants.from_dict(c.to_dict()) == c


def test_table2_rows_at_d0_are_the_papers_table2_not_table1():
    from ledsim.paper.evaluate import paper_reference

    t2 = paper_reference("if2", 0.085, table=2)
    assert (t2["x1"], t2["x2"], t2["y1"], t2["y2"]) == (6.64e-3, 40.1e-3, 13.0e-3, 15.6e-3)
    assert paper_reference("if2", 0.085, table=1)["x1"] == 5.7e-3
    assert paper_reference("open-loop", 0.2, table=2) is None
