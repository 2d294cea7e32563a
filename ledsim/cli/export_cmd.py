"""``ledsim export``: one step of a fixed-gain KKL checkpoint as an ONNX graph."""

from __future__ import annotations

import logging
from pathlib import Path

from ledsim.constants import PAPER_DISTANCE
from ledsim.errors import LedsimError
from ledsim.files.outputs import check_out_file

log = logging.getLogger("ledsim")


def export(args) -> int:
    """One step of a KKL checkpoint (update with its missing-sample hold, predict with
    Omega, and the decoder) as an ONNX graph."""
    from ledsim.experiment.estimators import build_estimator
    from ledsim.files.outputs import atomic_write_bytes
    from ledsim.files.resources import require_shipped_checkpoint
    from ledsim.radiometry.link import constants_from_dict
    from observer.kkl import checkpoint
    from observer.kkl.export import kkl_step_graph

    out = check_out_file(args.out, ".onnx")
    path = args.checkpoint or require_shipped_checkpoint(PAPER_DISTANCE, "mujoco")
    saved = checkpoint.metadata(path)["system"]
    constants = constants_from_dict(saved["constants"])
    if saved.get("class") == "LEDLinkModel":
        from ledsim.paper.model import LEDLinkModel

        system = model = LEDLinkModel(constants)
    elif saved.get("class") == "GimbalSystem":
        from ledsim.loop.build.estimation import identified_model
        from ledsim.physics.gimbal_system import GimbalSystem
        from ledsim.physics.scene import WorldConfig

        world = saved.get("world", {})
        system = GimbalSystem(WorldConfig(constants=constants, **{
            k: world[k] for k in ("timestep", "water_density", "water_viscosity",
                                  "gimbal_damping") if k in world}))
        model = identified_model(system)  # Omega's f and the h of missing samples
    else:
        raise LedsimError(f"checkpoint {str(path)!r} is for a {saved.get('class')!r} system: "
                          "ledsim exports observers of LEDLinkModel or GimbalSystem")
    obs = build_estimator("kkl", system, model=model, checkpoint=path)
    if not hasattr(obs, "eigenvalues"):
        raise LedsimError(f"checkpoint {str(path)!r} is a gain-scheduled KKL: ledsim exports "
                          "fixed-gain observers (its gain schedule is not one ONNX step)")
    graph = kkl_step_graph(obs, model.step_form())
    atomic_write_bytes(out, lambda tmp: Path(tmp).write_bytes(graph.SerializeToString()))
    log.info(f"wrote {out}: one step of {path} ({saved.get('class')}, q = {obs.q}); inputs "
             "z, y [W], u [rad/s^2]; outputs x_hat, z_next")
    return 0
