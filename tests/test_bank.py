"""A bank of observers for several noise levels (the closed loop's KKL at any distance)."""

import numpy as np
import pytest

from ledsim.constants import LinkConstants
from ledsim.paper.model import LEDLinkModel
from observer.estimator import Estimator
from observer.exceptions import ObserverError
from observer.kkl.bank import ObserverBank


class Recorder(Estimator):
    """Returns its last reset state plus the number of updates since."""

    def __init__(self, system):
        super().__init__(system)
        self.reset()

    def reset(self, x0=None):
        self.x = self.initial_guess(x0)
        self.n = 0

    def update(self, y):
        self.n += 1
        return self.x + self.n

    def predict(self, u):
        pass


@pytest.fixture
def bank():
    s = LEDLinkModel(LinkConstants())
    return ObserverBank([Recorder(s), Recorder(s), Recorder(s)], [1.0, 6.0, 13.0])


def test_nearest_member_is_chosen_in_log_ratio(bank):
    assert [bank.nearest(r) for r in (0.5, 2.0, 2.6, 5.0, 8.5, 9.0, 40.0)] == \
        [0, 0, 1, 1, 1, 2, 2]


def test_switch_needs_the_hysteresis_margin(bank):
    bank.update(np.zeros(2))
    mid = np.sqrt(6.0)  # log midpoint of members 0 and 1
    assert not bank.select(mid * 1.05)  # nearer member 1, inside the margin
    assert bank.active == 0
    assert bank.select(mid * 1.5)
    assert bank.active == 1
    assert not bank.select(mid * 0.95)  # and back only past the margin the other way
    assert bank.active == 1


def test_switch_carries_the_estimate_over(bank):
    for _ in range(3):
        x = bank.update(np.zeros(2))
    assert bank.select(13.0, y=np.zeros(2))
    # The new member started from the old estimate and took the measurement once.
    np.testing.assert_allclose(bank.xhat, x + 1)
    np.testing.assert_allclose(bank.update(np.zeros(2)), x + 2)


def test_bad_ratios_are_refused():
    s = LEDLinkModel(LinkConstants())
    with pytest.raises(ObserverError, match="increasing"):
        ObserverBank([Recorder(s), Recorder(s)], [6.0, 1.0])
    with pytest.raises(ObserverError, match="one positive"):
        ObserverBank([Recorder(s)], [1.0, 2.0])


def test_a_switch_waits_for_the_dwell():
    s = LEDLinkModel(LinkConstants())
    bank = ObserverBank([Recorder(s), Recorder(s)], [1.0, 6.0], dwell=3)
    bank.update(np.zeros(2))
    assert [bank.select(6.0) for _ in range(3)] == [False] * 3
    assert bank.select(1.0) is False  # asked for the active one: the count starts again
    assert [bank.select(6.0) for _ in range(4)] == [False, False, False, True]
    assert bank.active == 1
