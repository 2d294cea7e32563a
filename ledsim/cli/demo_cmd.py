"""``ledsim demo``: the main job. The default link's alignment with every estimator,
a fly-by past a seabed node, one table, and a video of the link as it is."""

from __future__ import annotations

import logging
import time
from pathlib import Path

from ledsim.cli.checks import _check_vehicle
from ledsim.cli.spec_flags import VEHICLE, spec_values
from ledsim.files.outputs import check_out_dir, output_folder

log = logging.getLogger("ledsim")


def demo(args) -> int:
    """Align the receiver from 0.3 rad off with each estimator; print one table."""
    from ledsim.files.outputs import atomic_write_text
    from ledsim.files.results import write_json
    from ledsim.loop.build.estimation import check_checkpoint
    from ledsim.loop.registry import COMPARED_ESTIMATORS, TWO_AXIS_ESTIMATORS
    from ledsim.loop.report import run_many, write_run
    from ledsim.loop.run_config import RunConfig
    from ledsim.loop.table import TABLE_HEADER, format_summary
    from ledsim.loop.video import VideoSpec, check_video

    out = check_out_dir(args.out)
    t0 = time.perf_counter()
    rows, summaries = [], []
    # Every estimator's run and the video are checked before the first one starts.
    values = spec_values(args)
    # a pan-tilt head runs the estimators it takes (the KKL, EKF, UKF, PF and oracle)
    estimators = TWO_AXIS_ESTIMATORS if RunConfig(**values).world.two_axes else \
        COMPARED_ESTIMATORS
    cfgs = [RunConfig(scenario="align", estimator=est, **values) for est in estimators]
    labels = list(estimators)
    if cfgs[0].world.two_axes:  # and a fly-by past a seabed node, on the default KKL
        cfgs.append(RunConfig(**{**values, "mission": None, "node_error": 0.0},
                              scenario="flyby", estimator="kkl"))
        labels.append("flyby-kkl")
    for cfg in cfgs:
        cfg.validate()
        check_checkpoint(cfg)
    _check_vehicle(cfgs[0])
    # the video shows the run's link as it is (both vehicles in the sea, the beam, the
    # fog: the overview camera), or the paper's bench with --bench-video (side camera)
    link = None if args.bench_video or cfgs[0].link == "paper" else \
        {k: values[k] for k in SCENE_KEYS if values.get(k) is not None}
    video = VideoSpec(camera="side" if link is None else "overview")
    if not args.no_video:
        check_video(_demo_video_config(args.scene, spec_values(args, VEHICLE), link), video)
    with output_folder(out) as tmp:
        for label, cfg in zip(labels, cfgs, strict=True):
            summary, trace = run_many(cfg, progress=not args.quiet)
            write_run(summary, trace, tmp / label)
            summaries.append(summary)
            rows.append(format_summary(summary))
            print(rows[-1] if len(rows) > 1 else f"{TABLE_HEADER}\n{rows[-1]}", flush=True)
        passes = [_delivered(s) for label, s in zip(labels, summaries, strict=True)
                  if label == "flyby-kkl"]
        for line in passes:
            print(line)
        atomic_write_text(tmp / "table.md", TABLE_HEADER + "\n" + "\n".join(rows) + "\n"
                          + "".join(f"\n{line}\n" for line in passes))
        write_json(tmp / "results.json", summaries)
        if not args.no_video:
            # The video stays on the bench: the scene's cameras frame 8.5 cm, not metres.
            _demo_video(tmp, args.scene, not args.quiet, spec_values(args, VEHICLE), link,
                        spec=video)
    log.info(f"wrote {out}/table.md, results.json, <estimator>/run.png"
             f"{'' if args.no_video else ', alignment.mp4, alignment.png'} in "
          f"{time.perf_counter() - t0:.0f} s")
    return 0


def _delivered(s) -> str:
    """One line of the data a pass delivered (a mission's summary)."""
    got, ideal = s.goodput_bits.mean, s.ideal_bits.mean
    return (f"{s.scenario} with {s.estimator}: {got / 1e6:.2f} Mbit delivered of the "
            f"{ideal / 1e6:.2f} Mbit the pass allows pointed perfectly ({got / ideal:.4f}), "
            f"range {s.range_m[0]:.1f}-{s.range_m[1]:.1f} m, {s.outages.mean:.1f} outages")


#: The run's flags its demo video keeps on a physical link: the link, its water and
#: depths, and the head.
SCENE_KEYS = ("link", "water", "attenuation", "bit_rate", "distance", "depth",
              "transmitter_depth", "sea_depth", "gimbal", "receiver", "lens_field_deg")


def _demo_video_config(scene: str | None, vehicle: dict, link: dict | None = None,
                       estimator: str = "kkl"):
    """The run of the demo's video: 5 s of the ``estimator``-driven alignment with an
    occlusion (on ``link``: default the paper's bench, whose 8.5 cm the cameras frame)."""
    from ledsim.loop.run_config import RunConfig

    return RunConfig(scenario="align", estimator=estimator, seconds=5.0, scene=scene,
                     disturbances=("occlusion:start=3,duration=0.5",), **vehicle,
                     **(link or {"link": "paper"}))


def _demo_video(out: Path, scene: str | None, progress: bool, vehicle: dict,
                link: dict | None = None, estimator: str = "kkl", spec=None) -> None:
    """A short video of the ``estimator``-driven alignment with an occlusion, and a still
    frame (:func:`_demo_video_config`; ``spec``: its :class:`VideoSpec`)."""
    from ledsim.loop.video import VideoSpec, check_video, render_video

    spec = spec or VideoSpec()
    cfg = _demo_video_config(scene, vehicle, link, estimator)
    check_video(cfg, spec)
    frames = render_video(cfg, 0, out / "alignment.mp4", spec,
                          still=out / "alignment.png", progress=progress)
    log.info(f"rendered {frames} frames of alignment.mp4")
