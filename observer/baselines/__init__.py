"""Classical estimators run on exactly the same measurements as the KKL observer: the
Bayesian filters (EKF, UKF, particle filter) and the oracle, which is handed the truth."""

from observer.baselines.ekf import ExtendedKalmanFilter
from observer.baselines.pf import ParticleFilter
from observer.baselines.ukf import UnscentedKalmanFilter

__all__ = ["ExtendedKalmanFilter", "UnscentedKalmanFilter", "ParticleFilter"]
