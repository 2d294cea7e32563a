"""``ledsim export``: one step of a fixed-gain KKL checkpoint as an ONNX graph, the maps
of a gain-scheduled one, or the pan-tilt's pair (one step per axis)."""

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
    if getattr(args, "gimbal", "yaw") == "pan-tilt":
        return _export_pair(args, out)
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
    if not hasattr(obs, "eigenvalues"):  # gain-scheduled: its maps, in one graph
        from observer.kkl.export_maps import scheduled_maps_graph

        graph = scheduled_maps_graph(obs)
        atomic_write_bytes(out, lambda tmp: Path(tmp).write_bytes(graph.SerializeToString()))
        log.info(f"wrote {out}: the maps of the gain-scheduled KKL {path} (q = {obs.q}); "
                 "inputs x, z, w, s; outputs T(x; w), T_star(z; w, s)"
                 f"{', T_star_locked' if obs.decoder_locked is not None else ''} "
                 "(observer/kkl/export_maps.py; its schedule runs beside them)")
        return 0
    graph = kkl_step_graph(obs, model.step_form())
    atomic_write_bytes(out, lambda tmp: Path(tmp).write_bytes(graph.SerializeToString()))
    log.info(f"wrote {out}: one step of {path} ({saved.get('class')}, q = {obs.q}); inputs "
             "z, y [W], u [rad/s^2]; outputs x_hat, z_next")
    return 0


def _export_pair(args, out: Path) -> int:
    """``ledsim export --gimbal pan-tilt``: each axis's KKL of the pan-tilt's pair (the
    shipped one, or ``--checkpoint NAME``'s) as its own ONNX step, on that axis's ratios
    (its pair's powers over the data detector's), to NAME_azimuth.onnx and
    NAME_elevation.onnx of ``--out NAME.onnx``."""
    from ledsim.files.outputs import atomic_write_bytes
    from ledsim.loop.build.head_kkl import AXES, pair_paths, reference_axes, shipped_axis
    from observer.kkl import checkpoint
    from observer.kkl.export import kkl_step_graph

    lens = getattr(args, "lens_field_deg", None)
    written = []
    for name, system in zip(AXES, reference_axes(lens), strict=True):
        path = shipped_axis(name, lens) if args.checkpoint is None else \
            pair_paths(args.checkpoint)[name]
        if not path.is_file():
            raise LedsimError(f"no KKL for the pan-tilt's {name} at {str(path)!r} (ledsim "
                              "train --gimbal pan-tilt --out NAME writes a pair)")
        obs = checkpoint.load(path, system)
        graph = kkl_step_graph(obs, system.step_form(), name=f"kkl_pan_tilt_{name}")
        target = out.with_name(f"{out.stem}_{name}.onnx")
        atomic_write_bytes(target, lambda tmp, g=graph: Path(tmp).write_bytes(
            g.SerializeToString()))
        written.append(str(target))
    log.info(f"wrote {', '.join(written)}: one step of each axis's KKL; inputs z, y (that "
             "axis's pair over the data detector's power), u [rad/s^2]; outputs x_hat "
             "(angle [rad], rate [rad/s]), z_next")
    return 0
