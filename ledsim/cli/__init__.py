"""The ``ledsim`` command line. User mistakes print one line and exit with code 2.

The parser is built from the registries (scenarios, estimators, presets, disturbances),
so ``ledsim COMMAND --help`` lists every choice with its default.
"""

from __future__ import annotations

import argparse
import math
import os
import sys

EXIT_USAGE = 2
CAMERAS = ("side", "overview", "chase")  # the shipped scene's cameras


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, no usage dump
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message}\n")


class _Help(argparse.ArgumentDefaultsHelpFormatter):
    """Shows defaults, except where there is none to show."""

    def _get_help_string(self, action):
        text = action.help or ""
        if action.default in (None, False, argparse.SUPPRESS) or action.required:
            return text
        return f"{text} (default: %(default)s)".strip()


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
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not allowed: must be finite")
    return value


def _choices(registry) -> dict:
    return dict(choices=list(registry), metavar="{" + ",".join(registry) + "}")


def _add_world_args(p, distance_help="link distance d [m]") -> None:
    p.add_argument("--distance", type=_float, default=0.085, help=distance_help)
    p.add_argument("--scene", help="MJCF scene file (default: the shipped led_link.xml)")


def _add_loop_args(p) -> None:
    from ..loop.config import LOOP_ESTIMATORS, PHYSICS_SCENARIOS
    from ..physics.disturbances import DISTURBANCES

    p.add_argument("--scenario", default="align", **_choices(PHYSICS_SCENARIOS),
                   help="closed-loop scenario")
    p.add_argument("--estimator", default="kkl", **_choices(LOOP_ESTIMATORS),
                   help="estimator in the loop (oracle: handed the true state)")
    p.add_argument("--disturbance", action="append", default=[], metavar="SPEC",
                   help="name[:key=value,...] with name in " + ", ".join(DISTURBANCES)
                   + " (repeatable)")
    _add_world_args(p)


def build_parser() -> argparse.ArgumentParser:
    from .. import __version__
    from ..paper.scenarios import PAPER_SCENARIOS
    from ..physics.simulation import TORQUE_PROFILES
    from ..presets import PRESETS

    p = _Parser(prog="ledsim", description="An underwater LED optical link in MuJoCo, kept "
                "aligned by a learned KKL observer. User mistakes exit with code 2.")
    p.add_argument("--version", action="version", version=f"ledsim {__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    def command(name, help):
        return sub.add_parser(name, help=help, description=help, formatter_class=_Help)

    ev = command("evaluate", "paper Table 1/2 experiment: KKL vs EKF/UKF/PF")
    ev.add_argument("--scenario", required=True, **_choices(PAPER_SCENARIOS))
    ev.add_argument("--distance", type=_float, default=0.085, help="link distance d [m]")
    ev.add_argument("--dphi-deg", "--dphi", dest="dphi", type=_float, default=6.0,
                    help="angle between the photodiode normals [deg]")
    ev.add_argument("--seeds", type=int, default=10, help="noise seeds (>= 1)")
    ev.add_argument("--starts", type=int, default=100,
                    help="random initial guesses for the convergence share (0 to skip)")
    ev.add_argument("--particles", type=int, default=5000, help="particle-filter size")
    ev.add_argument("--checkpoint", help="KKL checkpoint (default: the shipped one for d)")
    ev.add_argument("--workers", type=_positive_int, default=2, help="processes")
    ev.add_argument("--out", required=True, help="output folder")

    tr = command("train", "learn a KKL observer (Algorithm 1) and save it")
    tr.add_argument("--design", default="default", **_choices(PRESETS),
                    help="observer preset")
    tr.add_argument("--distance", type=_float, default=0.085, help="link distance d [m]")
    tr.add_argument("--samples", type=_positive_int, default=200_000,
                    help="training transitions")
    tr.add_argument("--seed", type=int, default=0, help="seed of data and features")
    tr.add_argument("--out", required=True, help="checkpoint path (.pt)")

    sim = command("simulate", "run the MuJoCo world headless; save series + plot")
    sim.add_argument("--seconds", type=_float, default=5.0, help="duration [s]")
    sim.add_argument("--torque-profile", default="zero", **_choices(TORQUE_PROFILES),
                     help="gimbal torque")
    sim.add_argument("--torque-amplitude", type=_float, default=0.002, help="[N m]")
    sim.add_argument("--torque-frequency", type=_float, default=0.5, help="[Hz]")
    from ..physics.disturbances import DISTURBANCES

    sim.add_argument("--disturbance", action="append", default=[], metavar="SPEC",
                     help="name[:key=value,...] with name in " + ", ".join(DISTURBANCES)
                     + " (repeatable)")
    _add_world_args(sim)
    sim.add_argument("--dphi-deg", "--dphi", dest="dphi", type=_float, default=6.0,
                     help="angle between the photodiode normals [deg]")
    sim.add_argument("--led-yaw-deg", "--led-yaw", dest="led_yaw", type=_float, default=0.0,
                     help="LED axis turned away from the receiver [deg]")
    sim.add_argument("--led-offset", type=_float, default=0.0,
                     help="LED moved across the link [m]")
    sim.add_argument("--torque-limit", type=_float, default=0.05, help="[N m]")
    sim.add_argument("--gimbal-angle", type=_float, default=0.0, help="initial angle [rad]")
    sim.add_argument("--seed", type=int, default=0, help="measurement-noise seed")
    sim.add_argument("--out", required=True, help="output folder")

    rn = command("run", "closed loop in MuJoCo: estimator + controller + gimbal")
    _add_loop_args(rn)
    rn.add_argument("--torque-limit", type=_float, default=0.05, help="[N m]")
    rn.add_argument("--noise-scale", type=_float, default=1.0,
                    help="multiplies the measurement-noise std")
    rn.add_argument("--seconds", type=_float, default=None,
                    help="length of each run [s] (default: the scenario's, 10 s)")
    rn.add_argument("--seeds", type=int, default=4, help="Monte-Carlo runs (seeds 0..N-1)")
    rn.add_argument("--particles", type=int, default=2000, help="particle-filter size")
    rn.add_argument("--checkpoint", help="KKL checkpoint trained on the MuJoCo world")
    rn.add_argument("--omega-model", default="identified",
                    **_choices(("identified", "simulator", "none")),
                    help="f used by the KKL's Omega correction")
    rn.add_argument("--workers", type=_positive_int, default=2, help="processes")
    rn.add_argument("--no-plot", action="store_true", help="skip run.png")
    rn.add_argument("--out", required=True, help="output folder")

    rd = command("render", "render a closed-loop run to an H.264 mp4 (headless)")
    _add_loop_args(rd)
    rd.add_argument("--seconds", type=_float, default=6.0, help="[s]")
    rd.add_argument("--width", type=int, default=640, help="[px]")
    rd.add_argument("--height", type=int, default=480, help="[px]")
    rd.add_argument("--fps", type=_float, default=30.0, help="frames per second")
    rd.add_argument("--camera", default="side",
                    help="a camera of the scene; the shipped one has " + ", ".join(CAMERAS))
    rd.add_argument("--gl", default=None, choices=["osmesa", "egl"],
                    help="OpenGL backend (default: MUJOCO_GL, else osmesa)")
    rd.add_argument("--seed", type=int, default=0, help="noise and disturbance seed")
    rd.add_argument("--out", required=True, help="video file (.mp4)")

    dm = command("demo", "main job: closed-loop alignment with every estimator")
    dm.add_argument("--seeds", type=_positive_int, default=2,
                    help="Monte-Carlo runs per estimator")
    dm.add_argument("--out", default="out/demo", help="output folder")
    dm.add_argument("--scene", help="MJCF scene file (default: the shipped led_link.xml)")
    dm.add_argument("--no-video", action="store_true", help="skip the rendered video")
    return p


def _gl_from_argv(argv: list[str]) -> None:
    """MuJoCo reads MUJOCO_GL when first imported, and building the parser imports it:
    so ``--gl`` is applied here, before anything else."""
    for i, a in enumerate(argv):
        value = a.split("=", 1)[1] if a.startswith("--gl=") else (
            argv[i + 1] if a == "--gl" and i + 1 < len(argv) else None)
        if value in ("osmesa", "egl"):
            os.environ.setdefault("MUJOCO_GL", value)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    _gl_from_argv(argv)
    from observer.errors import ObserverError

    from ..errors import LedsimError
    from . import commands

    args = build_parser().parse_args(argv)
    try:
        return getattr(commands, args.command)(args)
    except (LedsimError, ObserverError) as exc:
        print(f"ledsim: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("ledsim: interrupted", file=sys.stderr)
        return 130
