"""The MuJoCo world: scene, ray-based sensor, disturbances, simulation loop, the system
the observer sees, and rendering.

MuJoCo picks its OpenGL backend when it is first imported, so the headless default
(``MUJOCO_GL=osmesa``) is set here, before anything imports mujoco; a value already in
the environment (``egl``, say) is kept.
"""

import os

os.environ.setdefault("MUJOCO_GL", "osmesa")
