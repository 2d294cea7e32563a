"""The ``ledsim`` command line. User mistakes print one line and exit with code 2."""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

EXIT_USAGE = 2


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, no usage dump
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message}\n")


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value} is not allowed: must be >= 1")
    return value


def _float(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None


def build_parser() -> argparse.ArgumentParser:
    from .scenarios import SCENARIOS

    p = _Parser(prog="ledsim", description=__doc__)
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    ev = sub.add_parser("evaluate", help="paper Table 1/2 experiment: KKL vs EKF/UKF/PF")
    ev.add_argument("--scenario", required=True, choices=list(SCENARIOS), metavar="SCENARIO",
                    help="one of: " + ", ".join(SCENARIOS))
    ev.add_argument("--distance", type=_float, default=0.085, help="link distance d [m]")
    ev.add_argument("--dphi", type=_float, default=6.0,
                    help="angle between the photodiode normals [deg]")
    ev.add_argument("--seeds", type=int, default=10, help="noise seeds (>= 1)")
    ev.add_argument("--starts", type=int, default=100,
                    help="random initial guesses for the convergence share (0 to skip)")
    ev.add_argument("--particles", type=int, default=5000, help="particle-filter size")
    ev.add_argument("--checkpoint", help="KKL checkpoint (default: the shipped one for d)")
    ev.add_argument("--workers", type=_positive_int, default=2, help="processes")
    ev.add_argument("--out", required=True, help="output folder")

    tr = sub.add_parser("train", help="learn a KKL observer (Algorithm 1) and save it")
    tr.add_argument("--design", choices=["default", "low-light", "paper"], default="default")
    tr.add_argument("--distance", type=_float, default=0.085, help="link distance d [m]")
    tr.add_argument("--samples", type=_positive_int, default=200_000)
    tr.add_argument("--seed", type=int, default=0)
    tr.add_argument("--out", required=True, help="checkpoint path (.pt)")

    sim = sub.add_parser("simulate", help="run the MuJoCo world headless; save series + plot")
    sim.add_argument("--seconds", type=_float, default=5.0, help="duration [s]")
    sim.add_argument("--torque-profile", default="zero",
                     help="zero, sine, step or chirp (gimbal torque)")
    sim.add_argument("--torque-amplitude", type=_float, default=0.002, help="[N m]")
    sim.add_argument("--torque-frequency", type=_float, default=0.5, help="[Hz]")
    sim.add_argument("--disturbance", action="append", default=[],
                     help="name[:key=value,...] with name in vibration, current, "
                          "transmitter, occlusion (repeatable)")
    sim.add_argument("--distance", type=_float, default=0.085, help="link distance d [m]")
    sim.add_argument("--dphi", type=_float, default=6.0,
                     help="angle between the photodiode normals [deg]")
    sim.add_argument("--led-yaw", type=_float, default=0.0,
                     help="LED axis turned away from the receiver [deg]")
    sim.add_argument("--led-offset", type=_float, default=0.0,
                     help="LED moved across the link [m]")
    sim.add_argument("--torque-limit", type=_float, default=0.05, help="[N m]")
    sim.add_argument("--gimbal-angle", type=_float, default=0.0, help="initial angle [rad]")
    sim.add_argument("--scene", help="MJCF scene file (default: assets/led_link.xml)")
    sim.add_argument("--seed", type=int, default=0, help="measurement-noise seed")
    sim.add_argument("--out", required=True, help="output folder")

    rn = sub.add_parser("run", help="closed loop in MuJoCo: estimator + controller + gimbal")
    rn.add_argument("--scenario", default="align",
                    help="align, open-loop, if1, if2 or paper-closed-loop")
    rn.add_argument("--estimator", default="kkl", help="kkl, ekf, ukf, pf or oracle")
    rn.add_argument("--disturbance", action="append", default=[],
                    help="name[:key=value,...]: vibration, current, transmitter, occlusion")
    rn.add_argument("--distance", type=_float, default=0.085, help="link distance d [m]")
    rn.add_argument("--torque-limit", type=_float, default=0.05, help="[N m]")
    rn.add_argument("--noise-scale", type=_float, default=1.0,
                    help="multiplies the measurement-noise std")
    rn.add_argument("--seeds", type=int, default=4)
    rn.add_argument("--particles", type=int, default=2000)
    rn.add_argument("--checkpoint", help="KKL checkpoint trained on the MuJoCo world")
    rn.add_argument("--omega-model", default="identified",
                    help="f used by the KKL's Omega: identified, simulator or none")
    rn.add_argument("--workers", type=_positive_int, default=2)
    rn.add_argument("--out", required=True, help="output folder")

    rd = sub.add_parser("render", help="render a closed-loop run to an H.264 mp4 (headless)")
    rd.add_argument("--scenario", default="align")
    rd.add_argument("--estimator", default="kkl")
    rd.add_argument("--disturbance", action="append", default=[])
    rd.add_argument("--distance", type=_float, default=0.085)
    rd.add_argument("--seconds", type=_float, default=6.0)
    rd.add_argument("--width", type=int, default=640)
    rd.add_argument("--height", type=int, default=480)
    rd.add_argument("--fps", type=_float, default=30.0)
    rd.add_argument("--camera", default="side", help="side, overview or chase")
    rd.add_argument("--gl", default=None, help="osmesa (default) or egl")
    rd.add_argument("--seed", type=int, default=0)
    rd.add_argument("--out", required=True, help="video file (.mp4)")

    dm = sub.add_parser("demo", help="main job: closed-loop alignment with every estimator")
    dm.add_argument("--seeds", type=_positive_int, default=2)
    dm.add_argument("--out", default="out/demo", help="output folder")
    dm.add_argument("--no-video", action="store_true", help="skip the rendered video")
    return p


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    from .config import ConfigError
    from .errors import UserError

    try:
        if args.command == "evaluate":
            return _evaluate(args)
        if args.command == "train":
            return _train(args)
        if args.command == "simulate":
            return _simulate(args)
        if args.command == "run":
            return _run(args)
        if args.command == "demo":
            return _demo(args)
        if args.command == "render":
            return _render(args)
    except (UserError, ConfigError) as exc:
        print(f"ledsim: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("ledsim: interrupted", file=sys.stderr)
        return 130
    return 0


def _check_out_dir(path: str) -> Path:
    """Refuse an --out that exists as a file, before any work is done."""
    from .errors import UserError

    out = Path(path)
    if out.exists() and not out.is_dir():
        raise UserError(f"--out {path!r} exists and is not a folder")
    return out


def _writable_dir(path: str) -> Path:
    """The --out folder, created if needed and checked writable."""
    from .errors import UserError

    out = _check_out_dir(path)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UserError(f"--out {path!r} cannot be created: {exc.strerror}") from None
    if not os.access(out, os.W_OK):
        raise UserError(f"--out {path!r} is not writable")
    return out


def _simulate(args) -> int:
    from .config import LinkConstants
    from .disturbances import DisturbanceError, parse_disturbance
    from .errors import UserError
    from .sensor import IrradianceSensor
    from .simulation import ProfileError, plot_result, simulate, torque_profile
    from .world import SCENE, LinkWorld, WorldConfig, WorldError

    if not args.seconds > 0:
        raise UserError(f"--seconds {args.seconds!r} is not allowed: must be > 0")
    try:
        profile = torque_profile(args.torque_profile, args.torque_amplitude,
                                 args.torque_frequency)
        disturbances = [parse_disturbance(d) for d in args.disturbance]
        constants = LinkConstants(distance=args.distance, dphi=math.radians(args.dphi))
        config = WorldConfig(constants=constants, torque_limit=args.torque_limit,
                             led_yaw=math.radians(args.led_yaw),
                             led_lateral_offset=args.led_offset,
                             xml=Path(args.scene) if args.scene else SCENE)
        world = LinkWorld(config)
        world.reset(gimbal_angle=args.gimbal_angle)
        sensor = IrradianceSensor(world, seed=args.seed)
    except (WorldError, DisturbanceError, ProfileError) as exc:
        raise UserError(str(exc)) from None
    t0 = time.perf_counter()
    res = simulate(world, sensor, args.seconds, profile, disturbances, progress=True)
    wall = time.perf_counter() - t0
    out = _writable_dir(args.out)
    res.save_npz(out / "series.npz")
    res.save_csv(out / "series.csv")
    title = f"d = {args.distance:g} m, torque {args.torque_profile}" + (
        f", {', '.join(args.disturbance)}" if args.disturbance else "")
    plot_result(res, out / "series.png", title)
    print(f"simulated {args.seconds:g} s ({len(res.t)} steps) in {wall:.2f} s "
          f"({args.seconds / wall:.0f}x real time); wrote {out}/series.npz, series.csv, "
          "series.png")
    return 0


def _run(args) -> int:
    from .closed_loop import TABLE_HEADER, RunConfig, format_summary, run_many, write_run
    from .config import ConfigError
    from .errors import UserError
    from .world import WorldError

    cfg = RunConfig(scenario=args.scenario, estimator=args.estimator,
                    disturbances=tuple(args.disturbance), distance=args.distance,
                    torque_limit=args.torque_limit, noise_scale=args.noise_scale,
                    seeds=args.seeds, particles=args.particles, checkpoint=args.checkpoint,
                    omega_model=args.omega_model, workers=args.workers)
    _check_out_dir(args.out)
    try:
        summary, trace = run_many(cfg)
    except (WorldError, ConfigError) as exc:
        raise UserError(str(exc)) from None
    paths = write_run(summary, trace, _writable_dir(args.out))
    print(TABLE_HEADER)
    print(format_summary(summary))
    print(f"wrote {', '.join(str(p) for p in paths)}")
    return 0


def _demo(args) -> int:
    """Align the receiver from 0.3 rad off with each estimator; print one table."""
    import json

    from observer.checkpoint import atomic_write_text

    from .closed_loop import (
        ESTIMATORS,
        TABLE_HEADER,
        RunConfig,
        format_summary,
        run_many,
        write_run,
    )

    out = _writable_dir(args.out)
    t0 = time.perf_counter()
    rows, summaries = [], []
    for est in ESTIMATORS:
        summary, trace = run_many(RunConfig(scenario="align", estimator=est,
                                            seeds=args.seeds))
        write_run(summary, trace, out / est)
        summaries.append(summary)
        rows.append(format_summary(summary))
        print(rows[-1] if len(rows) > 1 else f"{TABLE_HEADER}\n{rows[-1]}", flush=True)
    table = TABLE_HEADER + "\n" + "\n".join(rows) + "\n"
    atomic_write_text(out / "table.md", table)
    atomic_write_text(out / "results.json", json.dumps(summaries, indent=2) + "\n")
    if not args.no_video:
        _demo_video(out)
    print(f"wrote {out}/table.md, results.json, <estimator>/run.png in "
          f"{time.perf_counter() - t0:.0f} s")
    return 0


def _demo_video(out: Path) -> None:
    """A short video of the KKL-driven alignment with an occlusion, and a still frame."""
    args = argparse.Namespace(
        scenario="align", estimator="kkl", disturbance=["occlusion:start=3,duration=0.5"],
        distance=0.085, seconds=5.0, width=640, height=480, fps=30.0, camera="side",
        gl=None, seed=0, out=str(out / "alignment.mp4"))
    _render(args, still=out / "alignment.png")


def _render(args, still: Path | None = None) -> int:
    import os

    from .errors import UserError

    os.environ.setdefault("MUJOCO_GL", args.gl or "osmesa")
    if args.gl and os.environ["MUJOCO_GL"] != args.gl:
        raise UserError(f"--gl {args.gl} conflicts with MUJOCO_GL={os.environ['MUJOCO_GL']}")
    if not args.fps > 0:
        raise UserError(f"--fps {args.fps!r} is not allowed: must be > 0")
    if not args.seconds > 0:
        raise UserError(f"--seconds {args.seconds!r} is not allowed: must be > 0")
    out = Path(args.out)
    if out.suffix.lower() != ".mp4":
        raise UserError(f"--out {args.out!r}: the video must be an .mp4 file")
    if not out.parent.exists() or not os.access(out.parent, os.W_OK):
        raise UserError(f"--out {args.out!r}: folder {str(out.parent)!r} does not exist or "
                        "is not writable")
    from .closed_loop import RunConfig, run_once
    from .render import FrameRecorder, VideoWriter
    from .world import LinkWorld

    cfg = RunConfig(scenario=args.scenario, estimator=args.estimator,
                    disturbances=tuple(args.disturbance), distance=args.distance,
                    extra={"seconds": args.seconds})
    cfg.validate()
    # Size, camera and GL backend are checked before any physics runs.
    FrameRecorder(LinkWorld(cfg.world_config()), args.width, args.height, args.fps,
                  args.camera).close()
    writer = VideoWriter(out, args.fps)
    state = {}

    def on_step(t, w, reading, xhat):
        if "rec" not in state:
            state["rec"] = FrameRecorder(
                w, args.width, args.height, args.fps, args.camera, writer,
                label=f"{args.scenario} | {args.estimator} | "
                      f"{', '.join(args.disturbance) or 'no disturbance'}")
        state["rec"](t, w, reading, xhat)

    t0 = time.perf_counter()
    ok = False
    try:
        run_once(cfg, args.seed, on_step=on_step, progress=True)
        ok = True
    finally:
        rec = state.get("rec")
        if rec is not None:
            if still is not None and ok:
                from PIL import Image

                Image.fromarray(rec.last_frame).save(still)
            rec.close()
        writer.close(keep=ok)
    wall = time.perf_counter() - t0
    print(f"rendered {writer.frames} frames ({args.width}x{args.height}) in {wall:.1f} s "
          f"({writer.frames / wall:.1f} frames/s incl. physics and observer); wrote {out}")
    return 0


def _evaluate(args) -> int:
    from .evaluate import EvaluationConfig, evaluate, markdown_table, write_outputs

    cfg = EvaluationConfig(scenario=args.scenario, distance=args.distance,
                           dphi=math.radians(args.dphi), seeds=args.seeds,
                           starts=args.starts, particles=args.particles,
                           checkpoint=args.checkpoint, workers=args.workers)
    _check_out_dir(args.out)
    t0 = time.perf_counter()
    results, traces = evaluate(cfg)
    paths = write_outputs(results, traces, _writable_dir(args.out), results["Te"])
    print(markdown_table(results))
    print(f"wrote {', '.join(str(p) for p in paths)} in {time.perf_counter() - t0:.0f} s")
    return 0


def _train(args) -> int:
    from observer import checkpoint
    from observer.training import train_kkl

    from .config import LinkConstants
    from .errors import UserError
    from .paper_model import LEDLinkModel
    from .presets import observer_preset

    try:
        system = LEDLinkModel(LinkConstants(distance=args.distance))
    except ValueError as exc:
        raise UserError(str(exc)) from None
    name = args.design
    design, config = observer_preset(name, system.Te)
    config.n_samples = args.samples
    config.seed = args.seed
    obs, report = train_kkl(system, design, config)
    path = checkpoint.save(obs, args.out)
    print(f"trained {name} observer in {report.seconds:.1f} s: L_dyn={report.loss_dyn:.2e}"
          f", L_recon={report.loss_recon:.2e}; wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
