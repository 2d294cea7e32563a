"""The ``ledsim`` command line. User mistakes print one line and exit with code 2; Ctrl-C
prints ``ledsim: interrupted`` and exits with code 130 within 2 s, at any moment,
leaving no output and no temporary behind.

The parser is built from the registries (scenarios, estimators, presets, disturbances),
so ``ledsim COMMAND --help`` lists every choice with its default. This module imports
only modules that Python has loaded already: the ``ledsim`` command (:func:`console`)
handles Ctrl-C before the heavy imports start. Before that Python itself is starting
(``site``, ``runpy``: 3-25 ms on an idle machine, the Makefile's install keeping ``site``
short, and seen up to 0.4 s on a loaded one): a Ctrl-C then gets Python's default
handling (a KeyboardInterrupt traceback), out of ledsim's reach.
"""

from __future__ import annotations

import _signal as signal  # the C module: ``signal`` first builds its enums (about 1 ms)
import atexit
import os
import sys

EXIT_INTERRUPTED = 130
#: Seconds from Ctrl-C after which ``ledsim`` stops without waiting for its cleanup any
#: longer (it removes its temporaries first): the last resort of the 2 s promise.
FORCE_EXIT_AFTER = 1.5

_PARSER_NAMES = ("CAMERAS", "EXIT_USAGE", "build_parser")


def __getattr__(name: str):
    """The parser's names, re-exported; imported on first use (it loads the registries)."""
    if name in _PARSER_NAMES:
        from ledsim.cli import parser

        return getattr(parser, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _gl_from_argv(argv: list[str]) -> None:
    """MuJoCo reads MUJOCO_GL when first imported, and building the parser imports it:
    so ``--gl`` is applied here, before anything else."""
    for i, a in enumerate(argv):
        value = a.split("=", 1)[1] if a.startswith("--gl=") else (
            argv[i + 1] if a == "--gl" and i + 1 < len(argv) else None)
        if value in ("osmesa", "egl"):
            os.environ.setdefault("MUJOCO_GL", value)


class _State:
    """Where the command is, for the SIGINT handler: ``console`` (the ``ledsim`` command,
    not :func:`main` called in a Python process), ``phase`` (``setup``: imports and
    parsing, nothing written yet; ``work``: the command runs; ``done``: it ended with
    ``code``)."""

    console = False
    phase = "setup"
    code = 0
    unraisablehook = None  # the hook :func:`main` replaced, while it runs


def _on_sigint(signum, frame) -> None:
    """Ctrl-C. In a Python process calling :func:`main`: flag it and raise
    KeyboardInterrupt. In the ``ledsim`` command, by phase: during setup, exit at once
    (there is nothing to clean up, and a KeyboardInterrupt in an import may be swallowed or
    print a traceback); during the work, flag it, raise KeyboardInterrupt once (the
    command removes its temporaries and stops its workers), and force the exit if that
    takes over :data:`FORCE_EXIT_AFTER` s; once the command ended, exit with its code."""
    if _State.console and _State.phase == "setup":
        _say_interrupted()
        os._exit(EXIT_INTERRUPTED)
    if _State.console and _State.phase == "done":
        _flush()
        os._exit(_State.code)
    from ledsim.files.outputs import INTERRUPTED

    first = not INTERRUPTED.is_set()
    INTERRUPTED.set()
    if _State.console:
        if not first:  # a second Ctrl-C: the cleanup runs, and the watchdog bounds it
            return
        import threading

        threading.Thread(target=_force_exit, name="ledsim-interrupted", daemon=True).start()
    raise KeyboardInterrupt


def _force_exit() -> None:
    import time

    from ledsim.files.outputs import discard_temporaries

    time.sleep(FORCE_EXIT_AFTER)
    discard_temporaries()  # waits for a rename into place under way, and allows no other
    _say_interrupted(f" (forced: cleanup took over {FORCE_EXIT_AFTER:g} s)")
    os._exit(EXIT_INTERRUPTED)


def _say_interrupted(why: str = "") -> None:
    """``ledsim: interrupted`` on stderr, unbuffered: safe in a signal handler, where
    ``print`` may find ``sys.stderr`` in the middle of a write and raise."""
    try:
        os.write(2, f"ledsim: interrupted{why}\n".encode())
    except OSError:
        pass


def _flush() -> None:
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError, RuntimeError, AttributeError):  # closed, reentrant
            pass


def _quiet_unraisable(unraisable) -> None:
    """Python reports a KeyboardInterrupt it could not raise (in a weakref callback, a
    ``__del__``) with a traceback; Ctrl-C was flagged already, so say nothing."""
    if not issubclass(unraisable.exc_type, KeyboardInterrupt):
        _State.unraisablehook(unraisable)


def _pin_threads(argv: list[str]) -> None:
    """One BLAS thread per process for every command but ``train`` (the loop's matrices
    are 2x2, and worker processes forked from this one share the cores), unless the user
    chose; only effective before numpy is first imported (``import ledsim.cli`` does not
    import it)."""
    if "train" not in argv[:1] and "numpy" not in sys.modules:
        from ledsim.experiment.montecarlo import pin_blas_threads

        pin_blas_threads()


def console() -> None:
    """The ``ledsim`` command (also ``python -m ledsim`` and ``python -m ledsim.cli``):
    :func:`main` on the command line's arguments, then exit with its code."""
    _State.console, _State.phase = True, "setup"
    signal.signal(signal.SIGINT, _on_sigint)  # first of all: Ctrl-C during the imports
    # Python puts SIGINT back to its default as it finalizes, after the atexit callbacks:
    # a Ctrl-C then would kill a finished command by signal (no message, status -2).
    # Ignored from the last callback on (they run last registered, first).
    atexit.register(signal.signal, signal.SIGINT, signal.SIG_IGN)
    code = main()
    _flush()
    if code == EXIT_INTERRUPTED:  # cleaned up: the interpreter's own exit can only delay
        os._exit(code)
    sys.exit(code)


def main(argv: list[str] | None = None) -> int:
    """Run one ``ledsim`` command (``argv``: its arguments, default ``sys.argv[1:]``).

    Returns:
        the exit code: 0, 2 for a user mistake (one line on stderr), 130 when
        interrupted (Ctrl-C: nothing was written).
    """
    argv = sys.argv[1:] if argv is None else list(argv)
    from ledsim.files.outputs import INTERRUPTED

    INTERRUPTED.clear()
    previous = signal.getsignal(signal.SIGINT)
    _State.unraisablehook = sys.unraisablehook
    try:
        sys.unraisablehook = _quiet_unraisable
        if not _State.console:  # in-process: Ctrl-C from here on ends the command with 130
            signal.signal(signal.SIGINT, _on_sigint)
        try:
            code = _main(argv)
            if INTERRUPTED.is_set():  # a Ctrl-C that Python swallowed: nothing committed
                raise KeyboardInterrupt
            _State.code, _State.phase = code, "done"
        except KeyboardInterrupt:
            _interrupted()
        except Exception:
            # An error the Ctrl-C caused: a KeyboardInterrupt raised while a C extension
            # initialises comes out as "ImportError: initialization failed" (matplotlib's
            # _image, as the plots were drawn). The work unwound as for the interrupt.
            if not INTERRUPTED.is_set():
                raise
            _interrupted()
        return _State.code
    finally:  # main() may be called in-process (tests, notebooks): leave no trace
        if not _State.console:
            signal.signal(signal.SIGINT, previous)
            _State.phase = "setup"
        sys.unraisablehook = _State.unraisablehook
        INTERRUPTED.clear()


def _interrupted() -> None:
    """Ctrl-C ended the command (its temporaries removed as it unwound): say so, exit 130."""
    from ledsim.files.outputs import INTERRUPTED

    INTERRUPTED.set()
    print("ledsim: interrupted", file=sys.stderr)
    _State.code, _State.phase = EXIT_INTERRUPTED, "done"


def _main(argv: list[str]) -> int:
    _gl_from_argv(argv)
    _pin_threads([a for a in argv if not a.startswith("-")])
    from ledsim.cli import commands
    from ledsim.cli.parser import EXIT_USAGE, build_parser
    from ledsim.errors import LedsimError
    from observer.exceptions import ObserverError

    parser = build_parser()
    if not argv:  # bare ``ledsim``: say what it takes
        parser.print_usage(sys.stderr)
        print("ledsim: error: choose a command (ledsim --help describes each)",
              file=sys.stderr)
        return EXIT_USAGE
    args = parser.parse_args(argv)
    return _dispatch(commands, args, (LedsimError, ObserverError))


def _dispatch(commands, args, user_errors: tuple) -> int:
    import logging

    from ledsim.cli.parser import EXIT_USAGE
    from ledsim.errors import one_line
    from ledsim.files.outputs import INTERRUPTED

    # Results go to stdout; progress bars (tqdm) and diagnostics (logging) to stderr.
    logging.basicConfig(format="ledsim: %(message)s",
                        level=logging.WARNING if args.quiet else logging.INFO)
    _State.phase = "work"  # from here, Ctrl-C unwinds: temporaries to remove, workers
    try:
        return getattr(commands, args.command)(args)
    except user_errors as exc:
        if INTERRUPTED.is_set():  # the error came from the interrupt
            raise KeyboardInterrupt from None
        print(f"ledsim: error: {one_line(str(exc))}", file=sys.stderr)
        return EXIT_USAGE
