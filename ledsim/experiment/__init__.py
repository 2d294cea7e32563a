"""What every experiment shares: the estimator registry and the observer presets, the
scenario type, the Monte-Carlo runner and its workers, and its figures."""
