"""The ``ledsim`` command line. User mistakes print one line and exit with code 2.

The parser is built from the registries (scenarios, estimators, presets, disturbances),
so ``ledsim COMMAND --help`` lists every choice with its default.
"""

from __future__ import annotations

import logging
import os
import signal
import sys

from ..outputs import INTERRUPTED
from .parser import CAMERAS, EXIT_USAGE, build_parser  # noqa: F401 (re-exported)


def _gl_from_argv(argv: list[str]) -> None:
    """MuJoCo reads MUJOCO_GL when first imported, and building the parser imports it:
    so ``--gl`` is applied here, before anything else."""
    for i, a in enumerate(argv):
        value = a.split("=", 1)[1] if a.startswith("--gl=") else (
            argv[i + 1] if a == "--gl" and i + 1 < len(argv) else None)
        if value in ("osmesa", "egl"):
            os.environ.setdefault("MUJOCO_GL", value)


def _on_sigint(signum, frame) -> None:
    INTERRUPTED.set()
    raise KeyboardInterrupt


def _pin_threads(argv: list[str]) -> None:
    """One BLAS thread per process for every command but ``train`` (the loop's matrices
    are 2x2, and worker processes forked from this one share the cores), unless the user
    chose; only effective before numpy is first imported (``import ledsim.cli`` does not
    import it)."""
    if "train" not in argv[:1] and "numpy" not in sys.modules:
        from ..montecarlo import pin_blas_threads

        pin_blas_threads()


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    _gl_from_argv(argv)
    _pin_threads([a for a in argv if not a.startswith("-")])
    from observer.errors import ObserverError

    from ..errors import LedsimError
    from . import commands

    parser = build_parser()
    if not argv:  # bare ``ledsim``: say what it takes
        parser.print_usage(sys.stderr)
        print("ledsim: error: choose a command (ledsim --help describes each)",
              file=sys.stderr)
        return EXIT_USAGE
    args = parser.parse_args(argv)
    INTERRUPTED.clear()
    previous = signal.signal(signal.SIGINT, _on_sigint)
    try:
        return _dispatch(commands, args, (LedsimError, ObserverError))
    finally:  # main() may be called in-process (tests, notebooks): leave no trace
        signal.signal(signal.SIGINT, previous)
        INTERRUPTED.clear()


def _dispatch(commands, args, user_errors: tuple) -> int:
    from ..errors import one_line

    # Results go to stdout; progress bars (tqdm) and diagnostics (logging) to stderr.
    logging.basicConfig(format="ledsim: %(message)s",
                        level=logging.WARNING if args.quiet else logging.INFO)
    try:
        code = getattr(commands, args.command)(args)
    except user_errors as exc:
        if not INTERRUPTED.is_set():
            print(f"ledsim: error: {one_line(str(exc))}", file=sys.stderr)
            return EXIT_USAGE
    except KeyboardInterrupt:
        INTERRUPTED.set()
    if INTERRUPTED.is_set():  # also a Ctrl-C that Python swallowed: nothing was committed
        print("ledsim: interrupted", file=sys.stderr)
        return 130
    return code
