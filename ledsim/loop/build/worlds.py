"""Building a run's worlds: the first piece of the one builder (issue 47).

:func:`build_worlds` gives the N worlds a closed loop steps, one per seed, from one
:class:`~ledsim.physics.scene.WorldConfig`: the scene is compiled once and the other
worlds share its model (each its own ``MjData``), unless the run changes the model as it
goes (a water current sets MuJoCo's medium velocity), when each compiles its own. The
receiver's layout travels in the world's constants, so a layout with two axes and four
photodiodes is built by the same call (``tests/test_two_axes.py``).
"""

from __future__ import annotations

from ledsim.physics.scene import WorldConfig
from ledsim.physics.world import LinkWorld


def build_worlds(config: WorldConfig, n: int, first: LinkWorld | None = None,
                 share: bool = True) -> list[LinkWorld]:
    """``n`` worlds of ``config``: ``first`` (None: a new one) and ``n - 1`` more,
    sharing its compiled model when ``share``."""
    if n < 1:
        raise ValueError(f"n={n!r} worlds: need at least 1")
    first = LinkWorld(config) if first is None else first
    return [first] + [LinkWorld(config, share_model_of=first if share else None)
                      for _ in range(n - 1)]
