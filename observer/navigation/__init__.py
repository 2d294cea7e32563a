"""The vehicle's navigation: the aided INS (:mod:`~observer.navigation.ins`), dead
reckoning, the line of sight to the LED, the water's loads on the hull, and rotations."""

from observer.moved import lent_names

# alias: this package took the path of the old module observer/navigation.py
__getattr__ = lent_names("observer.navigation.dead_reckoning")
