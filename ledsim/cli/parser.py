"""The ``ledsim`` argument parser, built from the registries (scenarios, estimators,
presets, disturbances), so ``ledsim COMMAND --help`` lists every choice with its default."""

from __future__ import annotations

import argparse
import math

from ledsim.cli.groups import (
    add_head_args,
    add_link_args,
    add_loop_args,
    add_run_knobs,
    add_scene_args,
    add_start_arg,
    add_vehicle_args,
    add_world_args,
    choices,
)
from ledsim.cli.options import (
    DISTANCE,
    DPHI_DEG,
    NOISE_SCALE,
    SEED,
    WORKERS,
    number,
)
from ledsim.cli.spec_flags import add_spec_flags
from ledsim.constants import PAPER_DISTANCE

EXIT_USAGE = 2
CAMERAS = ("side", "overview", "chase")  # the shipped scene's cameras


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, no usage dump
        from ledsim.errors import one_line

        self.exit(EXIT_USAGE, f"{self.prog}: error: {one_line(message)}\n")

    def _get_values(self, action, arg_strings):
        # ``--flag=--``: Python 3.11's argparse drops the "--" as the end of the options
        # and gives the flag an empty list, which no check expects; it is the value "--"
        # (as Python 3.13 reads it), refused by the flag's type or choices.
        if action.option_strings and action.nargs is None and arg_strings == ["--"]:
            value = self._get_value(action, "--")
            self._check_value(action, value)
            return value
        return super()._get_values(action, arg_strings)


class _Help(argparse.ArgumentDefaultsHelpFormatter):
    """Shows defaults, except where there is none to show."""

    def _get_help_string(self, action):
        text = action.help or ""
        if action.default in (None, False, argparse.SUPPRESS) or action.required:
            return text
        return f"{text} (default: %(default)s)".strip()


def build_parser() -> argparse.ArgumentParser:
    from ledsim import __version__
    from ledsim.experiment.observer_presets import PRESETS
    from ledsim.paper.evaluate import CLOSED_FORM_ESTIMATORS
    from ledsim.paper.scenarios import PAPER_SCENARIOS
    from ledsim.physics.simulation import TORQUE_PROFILES

    p = _Parser(prog="ledsim", description="An underwater LED optical link in MuJoCo, kept "
                "aligned by a learned KKL observer. User mistakes exit with code 2.")
    from ledsim.loop.run_config import ExecutionPart as X

    p.add_argument("--version", action="version", version=f"ledsim {__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("-q", "--quiet", action="store_true",
                        help="no progress bars or diagnostics; results and errors only")

    def command(name, help):
        return sub.add_parser(name, help=help, description=help, formatter_class=_Help,
                              parents=[common])

    ev = command("evaluate", "paper Table 1/2 experiment: KKL vs EKF/UKF/PF")
    ev.add_argument("--scenario", required=True, **choices(PAPER_SCENARIOS))
    ev.add_argument("--distance", type=DISTANCE, default=PAPER_DISTANCE,
                    help="link distance d [m]")
    ev.add_argument("--dphi-deg", "--dphi", dest="dphi", type=DPHI_DEG, default=6.0,
                    help="angle between the photodiode normals [deg]")
    ev.add_argument("--seeds", type=number(0, 10_000, integer=True), default=10,
                    help="noise seeds (>= 1)")
    ev.add_argument("--starts", type=number(0, 10_000, integer=True), default=100,
                    help="random initial guesses for the convergence share (0 to skip)")
    ev.add_argument("--particles", type=number(0, 1_000_000, integer=True), default=5000,
                    help="particle-filter size")
    ev.add_argument("--checkpoint", help="KKL checkpoint (default: the shipped one for d)")
    ev.add_argument("--estimator", dest="estimators", action="append",
                    **choices(CLOSED_FORM_ESTIMATORS),
                    help="run only this estimator (repeat for several; default: kkl, "
                         "kkl-paper, kkl-handover, kkl-scheduled where shipped, ekf, ukf, "
                         "pf)")
    ev.add_argument("--workers", type=WORKERS, default=X.workers, help="processes")
    ev.add_argument("--out", required=True, help="output folder")

    tr = command("train", "learn a KKL observer (Algorithm 1) and save it")
    tr.add_argument("--world", default="closed-form", **choices(("closed-form", "mujoco")),
                    help="whose transitions: the paper's model, or the MuJoCo world itself")
    tr.add_argument("--design", default=None, **choices(PRESETS),
                    help="observer preset (default: default; in MuJoCo the bank's preset "
                         "for --noise-scale)")
    tr.add_argument("--distance", type=DISTANCE, default=PAPER_DISTANCE,
                    help="link distance d [m]")
    tr.add_argument("--noise-scale", type=NOISE_SCALE, default=1.0,
                    help="measurement noise over the nominal (MuJoCo world)")
    tr.add_argument("--threads", type=WORKERS, default=1,
                    help="threads stepping the MuJoCo transitions' physics")
    tr.add_argument("--samples", type=number(1000, 1_000_000, integer=True), default=200_000,
                    help="training transitions")
    tr.add_argument("--seed", type=SEED, default=0, help="seed of data and features")
    tr.add_argument("--gimbal", default="yaw", **choices(("yaw", "pan-tilt")),
                    help="pan-tilt: the pan-tilt head's pair, one KKL per axis (with "
                         "--world mujoco), written to NAME_azimuth and NAME_elevation of "
                         "--out NAME; ledsim run --gimbal pan-tilt --checkpoint NAME runs it")
    tr.add_argument("--lens-field-deg", type=number(1.0, 29.9, "deg"), default=None,
                    metavar="F", help="with --gimbal pan-tilt: behind a lens of this "
                                      "half-power field")
    tr.add_argument("--out", required=True, help="checkpoint path (.safetensors; a .pt "
                    "name writes its .safetensors sibling)")

    ex = command("export", "one step of a KKL observer as an ONNX graph (for the vehicle)")
    ex.add_argument("--checkpoint", help="KKL checkpoint (default: the shipped MuJoCo "
                    "observer of d = 0.085 m)")
    ex.add_argument("--format", default="onnx", **choices(("onnx",)), help="file format")
    ex.add_argument("--gimbal", default="yaw", **choices(("yaw", "pan-tilt")),
                    help="pan-tilt: the pan-tilt head's pair (shipped, or --checkpoint "
                         "NAME's), each axis to NAME_azimuth.onnx and NAME_elevation.onnx "
                         "of --out NAME.onnx")
    ex.add_argument("--lens-field-deg", type=number(1.0, 29.9, "deg"), default=None,
                    metavar="F", help="with --gimbal pan-tilt: the shipped pair of this lens")
    ex.add_argument("--out", required=True, help="output file (.onnx)")

    rp = command("replay", "feed a saved trace's estimator inputs to a fresh estimator "
                 "(or an ONNX export) and compare the estimates")
    rp.add_argument("trace", help="trace_seed<K>.npz from ledsim run --save-trace")
    rp.add_argument("--onnx", help="an ONNX export of the run's fixed-gain KKL (ledsim "
                    "export) to replay instead of the numpy estimator")
    rp.add_argument("--json", action="store_true",
                    help="print the result as JSON (max_abs_difference, ...)")

    bg = command("budget", "the link budget against distance: SNR, BER, throughput, FEC "
                  "share and the range at the FEC limit, for a --link preset")
    add_link_args(bg, sea=False)
    bg.add_argument("--distance", action="append", type=DISTANCE, default=[],
                    help="a distance [m] (repeatable; default: 12 from a tenth of the FEC "
                    "range to twice it)")
    bg.add_argument("--pointing-error", type=number(0.0, 1.0, "rad"), default=0.0,
                    metavar="RAD", help="the receiver's Gaussian pointing error [rad]: the "
                    "FEC share is the share of it the link survives")
    bg.add_argument("--json", action="store_true",
                    help="print the report as JSON (range_at_fec_limit_m, rows, ...)")
    bg.add_argument("--plot", default=None, metavar="FILE",
                    help="also write SNR and BER against distance to FILE (.png)")

    sim = command("simulate", "run the MuJoCo world headless; save series + plot")
    add_spec_flags(sim, "seconds", seconds={"default": 5.0, "help": "duration [s]"})
    sim.add_argument("--torque-profile", default="zero", **choices(TORQUE_PROFILES),
                     help="gimbal torque")
    sim.add_argument("--torque-amplitude", type=number(-10.0, 10.0, "N m"), default=0.002,
                     help="[N m]")
    sim.add_argument("--torque-frequency", type=number(0.0, 50.0, "Hz", lo_open=True),
                     default=0.5, help="[Hz]")
    add_spec_flags(sim, "disturbances")
    add_world_args(sim)
    sim.add_argument("--dphi-deg", "--dphi", dest="dphi", type=DPHI_DEG, default=6.0,
                     help="angle between the photodiode normals [deg]")
    sim.add_argument("--led-yaw-deg", "--led-yaw", dest="led_yaw",
                     type=number(-180.0, 180.0, "deg"), default=0.0,
                     help="LED axis turned away from the receiver [deg]")
    sim.add_argument("--led-offset", type=number(-1.0, 1.0, "m"), default=0.0,
                     help="LED moved across the link [m]")
    add_spec_flags(sim, "torque_limit")
    sim.add_argument("--gimbal-angle", type=number(-math.pi, math.pi, "rad"), default=0.0,
                     help="initial angle [rad]")
    sim.add_argument("--seed", type=SEED, default=0, help="measurement-noise seed")
    sim.add_argument("--out", required=True, help="output folder")

    rn = command("run", "closed loop in MuJoCo: estimator + controller + gimbal")
    add_loop_args(rn)
    add_run_knobs(rn)
    add_start_arg(rn)
    add_spec_flags(rn, "noise_scale", "seeds", "checkpoint", "omega_model", "workers")
    rn.add_argument("--no-plot", action="store_true", help="skip run.png")
    rn.add_argument("--save-trace", action="store_true",
                    help="also write trace_seed<K>.npz per seed: t, phi, phidot, phi_hat, "
                         "phidot_hat, p1, p2, torque, lost (SI units, one row per step) "
                         "and what the estimator was given, for ledsim replay")
    add_spec_flags(rn, "window")
    rn.add_argument("--out", required=True, help="output folder")

    rd = command("render", "render a closed-loop run to an H.264 mp4 (headless)")
    add_loop_args(rd)
    add_start_arg(rd)
    add_spec_flags(rd, "seconds", seconds={"type": number(0.0, 600.0, "s", lo_open=True),
                                           "default": 6.0, "help": "[s]"})
    rd.add_argument("--width", type=number(-10_000, 10_000, integer=True), default=640,
                    help="[px]")
    rd.add_argument("--height", type=number(-10_000, 10_000, integer=True), default=480,
                    help="[px]")
    rd.add_argument("--fps", type=number(-1e6, 240.0), default=30.0,
                    help="frames per second, at most 240")
    rd.add_argument("--camera", default="side",
                    help="a camera of the scene; the shipped one has " + ", ".join(CAMERAS))
    rd.add_argument("--gl", default=None, choices=["osmesa", "egl"],
                    help="OpenGL backend (default: MUJOCO_GL, else osmesa)")
    rd.add_argument("--seed", type=SEED, default=0, help="noise and disturbance seed")
    rd.add_argument("--out", required=True, help="video file (.mp4)")

    sw = command("sweep", "a grid of closed-loop runs (estimators x disturbances x "
                 "distances x noise scales x seeds), locally or on a Ray cluster")
    from ledsim.loop.registry import LOOP_ESTIMATORS
    from ledsim.loop.sweep import BACKENDS
    sw.add_argument("--estimator", action="append", choices=list(LOOP_ESTIMATORS),
                    metavar="{" + ",".join(LOOP_ESTIMATORS) + "}",
                    help="estimator (repeatable; default: kkl)")
    sw.add_argument("--disturbance", action="append", metavar="SPEC",
                    help="disturbance of one cell: none, name[:key=value,...], or several "
                    "joined by + (repeatable; default: none)")
    sw.add_argument("--distance", action="append", type=DISTANCE,
                    help="link distance d [m] (repeatable; default: 0.085)")
    sw.add_argument("--noise-scale", action="append", type=NOISE_SCALE,
                    help="multiplies the measurement-noise std (repeatable; default: 1)")
    add_spec_flags(sw, "seeds", "scenario", seeds={"default": 2,
                                                  "help": "runs per combination"})
    add_run_knobs(sw)
    add_start_arg(sw)
    add_spec_flags(sw, "supervision", supervision={
        "help": "no loss detection or reacquisition (see ledsim run)"})
    add_vehicle_args(sw)
    add_link_args(sw)
    add_head_args(sw)
    add_scene_args(sw)
    sw.add_argument("--backend", default="local", **choices(BACKENDS),
                    help="local processes, or Ray (pip install 'ledsim[ray]')")
    sw.add_argument("--address", default=None,
                    help="Ray cluster to join (e.g. auto, or ray://HEAD:10001); default: "
                    "start a local Ray instance of --workers CPUs")
    add_spec_flags(sw, "workers", workers={
        "help": "processes (local) or CPUs of a local Ray instance"})
    sw.add_argument("--no-plot", action="store_true", help="skip summary.png")
    sw.add_argument("--out", required=True, help="output folder; rerun to resume")

    dm = command("demo", "main job: closed-loop alignment with every estimator")
    add_spec_flags(dm, "seeds", seeds={"type": number(1, 1000, integer=True), "default": 2,
                                       "help": "Monte-Carlo runs per estimator"})
    dm.add_argument("--out", default="out/demo", help="output folder")
    add_spec_flags(dm, "scene")
    dm.add_argument("--no-video", action="store_true", help="skip the rendered video")
    dm.add_argument("--bench-video", action="store_true",
                    help="render the video on the paper's 8.5 cm bench (side camera) "
                    "instead of the run's link (overview camera)")
    add_spec_flags(dm, "distance", distance={
        "help": "link distance d [m] (default: the --link preset's)"})
    add_link_args(dm)
    add_head_args(dm)
    add_vehicle_args(dm)
    return p
