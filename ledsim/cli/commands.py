"""What each ``ledsim`` command does, one function per command (named after it).

Arguments were parsed by :func:`ledsim.cli.build_parser`; errors are raised as
:class:`~ledsim.errors.LedsimError` and printed as one line by :func:`ledsim.cli.main`.
"""

from __future__ import annotations

import logging
import math
import os
import time
from pathlib import Path

from ledsim.cli.budget_cmd import budget  # noqa: F401 (the budget command)
from ledsim.cli.checks import _check_vehicle, _say_head, _warn_unserved
from ledsim.cli.demo_cmd import _demo_video, demo  # noqa: F401 (the demo command)
from ledsim.cli.export_cmd import export  # noqa: F401 (the export command)
from ledsim.cli.groups import resolved_distance
from ledsim.cli.replay_cmd import replay  # noqa: F401 (the replay command)
from ledsim.cli.spec_flags import spec_values
from ledsim.errors import LedsimError
from ledsim.files.outputs import check_out_dir, check_out_file, output_folder, save_checkpoint

log = logging.getLogger("ledsim")


def _loop_config(args, **given):
    """The run of a command line: the spec's names from the flags it has
    (:func:`~ledsim.cli.spec_flags.spec_values`; a part's own default for the flags a
    command does not take) and ``given``, validated."""
    from ledsim.loop.run_config import RunSpec

    cfg = RunSpec(**{**spec_values(args), **given})
    cfg.validate()
    _say_head(cfg, args)
    return cfg


def simulate(args) -> int:
    from ledsim.constants import LinkConstants
    from ledsim.experiment.plotting import plot_series
    from ledsim.loop.world_part import aimed_pitch
    from ledsim.physics.disturbances import check_sea, check_timing, parse_disturbance
    from ledsim.physics.scene import WorldConfig
    from ledsim.physics.sensor import IrradianceSensor
    from ledsim.physics.simulation import simulate, torque_profile
    from ledsim.physics.world import LinkWorld

    if not args.seconds > 0:
        raise LedsimError(f"--seconds {args.seconds!r} is not allowed: must be > 0")
    check_out_dir(args.out)
    profile = torque_profile(args.torque_profile, args.torque_amplitude,
                             args.torque_frequency)
    disturbances = [parse_disturbance(d) for d in args.disturbance]
    check_timing(disturbances, args.seconds)
    check_sea(disturbances, args.depth, args.transmitter_depth, args.sea_depth)
    from ledsim.radiometry.link_presets import link_constants

    args.distance = resolved_distance(args)
    constants = link_constants(args.link, args.distance, args.water, args.attenuation,
                               LinkConstants(dphi=math.radians(args.dphi)))
    extra = {} if args.scene is None else {"xml": Path(args.scene)}
    world = LinkWorld(WorldConfig(constants=constants, torque_limit=args.torque_limit,
                                  integrator=args.integrator,
                                  led_yaw=math.radians(args.led_yaw),
                                  led_lateral_offset=args.led_offset, depth=args.depth,
                                  transmitter_depth=args.transmitter_depth,
                                  led_pitch=aimed_pitch(args.depth, args.transmitter_depth,
                                                        args.distance)
                                  if args.transmitter_aimed else 0.0,
                                  receiver_dome=args.receiver_dome,
                                  sea_depth=args.sea_depth, **extra))
    world.reset(gimbal_angle=args.gimbal_angle)
    sensor = IrradianceSensor(world, seed=args.seed)
    t0 = time.perf_counter()
    res = simulate(world, sensor, args.seconds, profile, disturbances,
                   progress=not args.quiet)
    wall = time.perf_counter() - t0
    out = Path(args.out)
    title = f"d = {args.distance:g} m, torque {args.torque_profile}" + (
        f", {', '.join(args.disturbance)}" if args.disturbance else "")
    with output_folder(out) as tmp:
        res.save_npz(tmp / "series.npz")
        res.save_csv(tmp / "series.csv")
        plot_series(res, tmp / "series.png", title)
    log.info(f"simulated {args.seconds:g} s ({len(res.t)} steps) in {wall:.2f} s "
          f"({args.seconds / wall:.0f}x real time); wrote {out}/series.npz, series.csv, "
          "series.png")
    return 0


def run(args) -> int:
    from ledsim.loop.report import run_seeds, write_run, write_traces
    from ledsim.loop.table import TABLE_HEADER, format_summary

    cfg = _loop_config(args)
    out = check_out_dir(args.out)
    _check_vehicle(cfg)
    _warn_unserved(cfg)
    if cfg.steady_from < cfg.scenario_spec.steady_from:
        log.info(f"a {cfg.run_seconds:g} s run is shorter than the steady-state window "
                 f"(from {cfg.scenario_spec.steady_from:g} s): RMSE over its second half, "
                 f"from {cfg.steady_from:g} s")
    summary, outs = run_seeds(cfg, progress=not args.quiet, all_traces=args.save_trace)
    with output_folder(out) as tmp:
        written = write_run(summary, outs[0].trace, tmp, plot=not args.no_plot)
        if args.save_trace:
            written += write_traces(outs, tmp)
        paths = [out / p.name for p in written]
    print(TABLE_HEADER)
    print(format_summary(summary))
    log.info(f"wrote {', '.join(str(p) for p in paths)}")
    return 0


def render(args) -> int:
    if args.gl and os.environ.get("MUJOCO_GL", args.gl) != args.gl:
        raise LedsimError(f"--gl {args.gl} conflicts with MUJOCO_GL={os.environ['MUJOCO_GL']}")
    for flag, value in (("--fps", args.fps), ("--seconds", args.seconds)):
        if not value > 0:
            raise LedsimError(f"{flag} {value!r} is not allowed: must be > 0")
    out = check_out_file(args.out, ".mp4")
    from ledsim.loop.video import VideoSpec, check_video, render_video

    cfg = _loop_config(args, seconds=args.seconds)
    _check_vehicle(cfg)
    spec = VideoSpec(args.width, args.height, args.fps, args.camera)
    check_video(cfg, spec)
    t0 = time.perf_counter()
    frames = render_video(cfg, args.seed, out, spec, progress=not args.quiet)
    wall = time.perf_counter() - t0
    log.info(f"rendered {frames} frames ({args.width}x{args.height}) in {wall:.1f} s "
          f"({frames / wall:.1f} frames/s incl. physics and observer); wrote {out}")
    return 0


def evaluate(args) -> int:
    from ledsim.paper.evaluate import EvaluationConfig, evaluate, markdown_table, write_outputs

    cfg = EvaluationConfig(scenario=args.scenario, distance=args.distance,
                           dphi=math.radians(args.dphi), seeds=args.seeds,
                           starts=args.starts, particles=args.particles,
                           checkpoint=args.checkpoint, workers=args.workers,
                           **({"estimators": tuple(dict.fromkeys(args.estimators))}
                              if args.estimators else {}))
    out = check_out_dir(args.out)
    t0 = time.perf_counter()
    result = evaluate(cfg, progress=not args.quiet)
    with output_folder(out) as tmp:
        paths = [out / p.name for p in write_outputs(result, tmp)]
    print(markdown_table(result))
    log.info(f"wrote {', '.join(str(p) for p in paths)} in {time.perf_counter() - t0:.0f} s")
    return 0


def train(args) -> int:
    # A .pt name (ledsim 0.2 wrote torch files) writes its .safetensors sibling, which
    # the same name then loads (observer.kkl.checkpoint.resolve).
    out = check_out_file(args.out, (".safetensors", ".pt"))
    if out.with_suffix(".safetensors").is_dir():
        raise LedsimError(f"--out {str(args.out)!r}: {str(out.with_suffix('.safetensors'))!r} "
                          "is a folder")
    if args.gimbal == "pan-tilt":
        return _train_pair(args)
    if args.world == "mujoco":
        from ledsim.loop.world_training import train_mujoco_observer

        obs, report, extra = train_mujoco_observer(args.distance, args.noise_scale,
                                                   args.design, args.samples, args.seed,
                                                   args.threads, progress=not args.quiet)
    else:
        from ledsim.constants import LinkConstants
        from ledsim.experiment.observer_presets import train_preset
        from ledsim.paper.model import LEDLinkModel

        system = LEDLinkModel(LinkConstants(distance=args.distance))
        obs, report = train_preset(system, args.design or "default", args.samples,
                                   args.seed, progress=not args.quiet)
        extra = {}
    path = save_checkpoint(obs, args.out, extra=extra)
    log.info(f"trained {args.design or 'default'} observer ({args.world}) in "
             f"{report.seconds:.1f} s: "
             f"L_dyn={report.loss_dyn:.2e}, L_recon={report.loss_recon:.2e}; wrote {path}")
    return 0


def _train_pair(args) -> int:
    """``ledsim train --gimbal pan-tilt``: the pan-tilt's pair, one KKL per axis on the
    head's dynamics fitted to MuJoCo (``--world mujoco``), to NAME_azimuth and
    NAME_elevation."""
    from ledsim.loop.build.head_kkl import pair_paths, train_pair

    if args.world != "mujoco" or args.design not in (None, "default"):
        raise LedsimError("--gimbal pan-tilt trains in the MuJoCo world's head, the default "
                          "design: use --world mujoco (and no --design)")
    paths = pair_paths(args.out)
    for name, obs, report in train_pair(args.lens_field_deg, args.samples, seed=args.seed,
                                        progress=not args.quiet):
        path = save_checkpoint(obs, paths[name], extra={
            "pan_tilt_axis": name, "samples": args.samples,
            "lens_field_deg": args.lens_field_deg})
        log.info(f"trained the pan-tilt's {name} in {report.seconds:.1f} s: "
                 f"L_dyn={report.loss_dyn:.2e}, L_recon={report.loss_recon:.2e}; wrote {path}")
    return 0


def sweep(args) -> int:
    from ledsim.cli.checks import _warn_mixed_heads
    from ledsim.loop.run_config import RunConfig
    from ledsim.loop.sweep import SweepGrid, run_sweep
    from ledsim.radiometry.link_presets import default_distance

    if args.address is not None and args.backend != "ray":
        raise LedsimError("--address needs --backend ray")
    base = RunConfig(**spec_values(args, exclude=(  # the grid's flags and the sweep's apart
        "estimator", "disturbances", "distance", "noise_scale", "seeds", "workers")))
    base.validate()
    _check_vehicle(base)
    grid = SweepGrid(estimators=args.estimator or ["kkl"],
                     disturbances=args.disturbance or ["none"],
                     distances=args.distance or [default_distance(args.link)],
                     noise_scales=args.noise_scale or [1.0], seeds=args.seeds, base=base)
    out = check_out_dir(args.out)
    _warn_mixed_heads(grid)
    t0 = time.perf_counter()
    rows, paths = run_sweep(grid, out, args.backend, args.workers, args.address,
                            progress=not args.quiet, plot=not args.no_plot)
    log.info(f"{len(rows)} runs in {time.perf_counter() - t0:.0f} s; wrote "
             f"{', '.join(str(p) for p in paths)}")
    print((out / "summary.csv").read_text(), end="")
    return 0
