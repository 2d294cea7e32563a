"""Classical estimators run on exactly the same measurements as the KKL observer."""

from .ekf import ExtendedKalmanFilter
from .pf import ParticleFilter
from .ukf import UnscentedKalmanFilter

__all__ = ["ExtendedKalmanFilter", "UnscentedKalmanFilter", "ParticleFilter"]
