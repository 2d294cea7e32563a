"""Gymnasium environments of the LED link. ``import ledsim.envs`` registers:

==========================  =================================================
id                          what it is
==========================  =================================================
``ledsim/LinkAlign-v0``     keep the receiver gimbal aligned on the LED beam: the
                            paper's 8.5 cm bench (``link="paper"``)
``ledsim/LinkAlign-v1``     the same on a physical link: ``link="luma"`` at its
                            30 m in clear ocean, ``ledsim run``'s default
                            (docs/link.md); any constructor argument still
                            overrides it
``ledsim/LinkAlign-v2``     a pan-tilt head with its quad on that link: a (2,)
                            action, five powers over the link's peak and both
                            encoders (:mod:`ledsim.envs.head_align`)
==========================  =================================================

``gym.make_vec(id, num_envs=N)`` builds the native vector env of either id
(:class:`~ledsim.envs.vector.LinkAlignVectorEnv`: N worlds stepped in one call, next-step
autoreset); ``vectorization_mode="sync"`` or ``"async"`` still gives Gymnasium's own.

A new version for the new default, as Gymnasium's convention asks when results change:
``LinkAlign-v0`` keeps its behaviour. The three are different tasks (another link,
another receiver and action space), not one task's releases, so Gymnasium's warning that
v0 and v1 are "out of date" on every ``gym.make`` is silenced here (that message only).
"""

import warnings

from gymnasium.envs.registration import register, registry

from ledsim.envs.link_align import LinkAlignEnv
from ledsim.envs.policy import EstimatorObservation, ShippedAlignmentPolicy

ENV_ID = "ledsim/LinkAlign-v0"
#: The env on a physical link (``ledsim run``'s default link).
ENV_ID_PHYSICAL = "ledsim/LinkAlign-v1"
if ENV_ID not in registry:
    register(id=ENV_ID, entry_point="ledsim.envs.link_align:LinkAlignEnv",
             vector_entry_point="ledsim.envs.vector:LinkAlignVectorEnv",
             max_episode_steps=1000)
if ENV_ID_PHYSICAL not in registry:
    register(id=ENV_ID_PHYSICAL, entry_point="ledsim.envs.link_align:LinkAlignEnv",
             vector_entry_point="ledsim.envs.vector:LinkAlignVectorEnv",
             max_episode_steps=1000, kwargs={"link": "luma"})

#: The pan-tilt head's env.
ENV_ID_HEAD = "ledsim/LinkAlign-v2"
if ENV_ID_HEAD not in registry:
    register(id=ENV_ID_HEAD, entry_point="ledsim.envs.head_align:HeadAlignEnv",
             max_episode_steps=1000)

warnings.filterwarnings("ignore", message=r".*ledsim/LinkAlign-v[01] is out of date",
                        category=DeprecationWarning)

__all__ = ["ENV_ID", "ENV_ID_HEAD", "ENV_ID_PHYSICAL", "LinkAlignEnv", "EstimatorObservation",
           "ShippedAlignmentPolicy"]
