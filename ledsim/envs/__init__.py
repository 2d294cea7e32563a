"""Gymnasium environments of the LED link. ``import ledsim.envs`` registers:

==========================  =================================================
id                          what it is
==========================  =================================================
``ledsim/LinkAlign-v0``     keep the receiver gimbal aligned on the LED beam
==========================  =================================================
"""

from gymnasium.envs.registration import register, registry

from .link_align import LinkAlignEnv
from .policy import EstimatorObservation, ShippedAlignmentPolicy

ENV_ID = "ledsim/LinkAlign-v0"
if ENV_ID not in registry:
    register(id=ENV_ID, entry_point="ledsim.envs.link_align:LinkAlignEnv",
             max_episode_steps=1000)

__all__ = ["ENV_ID", "LinkAlignEnv", "EstimatorObservation", "ShippedAlignmentPolicy"]
