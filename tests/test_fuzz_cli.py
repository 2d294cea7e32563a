"""A property-based fuzz (hypothesis) of every ``ledsim`` command's flags: any argument
list drawn from a command's own parser, with values from both the valid and the invalid
spaces, either runs (exit 0) or is refused (exit 2) in one line; never a traceback, and
a refused command leaves nothing behind.

The commands and their flags are read from :func:`ledsim.cli.build_parser` (a flag's
range from its ``number`` type, its choices from the parser), the disturbances and their
keys from :data:`ledsim.physics.disturbances.DISTURBANCES` and
:data:`~ledsim.physics.disturbances.RANGES`, the sensors' noise figures and the station
keeping's gains from their dataclasses: a new flag or key is fuzzed with no change here.

``ledsim.cli.main`` runs in-process, through the checks a real run makes. Where the work
would begin (the Monte-Carlo runner, the physics, the training, the video) a stub stops
it by raising :class:`Started`, which counts as exit 0: an example costs what its checks
cost. ``budget``, ``export`` and ``replay`` run for real. Files: ``--checkpoint``,
``--onnx`` and the trace are either missing or valid (a shipped checkpoint, a trace and
an export made once per module); ``--scene`` and ``--out`` also take broken ones.

Environment: ``LEDSIM_SOAK=N`` multiplies the examples (as in ``test_properties.py``:
``LEDSIM_SOAK=40`` tries about 21,000); ``LEDSIM_FUZZ_REAL=1`` lets ``run``,
``simulate`` and ``sweep`` really run, with ``--seconds 3.5 --seeds 1 --workers 1``
forced (past the ``kick``'s and the ``occlusion``'s default starts);
``LEDSIM_FUZZ_SHOW=1`` prints each example and its last line of stderr. ``pytest -s``
shows how the examples ended, per command.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import inspect
import io
import logging
import os
import re
import shutil
import sys
import tempfile
from collections import Counter
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import ledsim.cli.demo_cmd
import ledsim.experiment.montecarlo
import ledsim.files.results
import ledsim.loop.report
import ledsim.loop.table
import ledsim.loop.video
import ledsim.paper.evaluate
import ledsim.physics.simulation
import observer.kkl.training
from ledsim.agent.autopilot import StationKeeping
from ledsim.cli import CAMERAS, build_parser, main
from ledsim.constants import PAPER_DISTANCE, NavigationNoise
from ledsim.files.resources import scene_path, shipped_checkpoint
from ledsim.physics.disturbances import DISTURBANCES, RANGES

SOAK = int(os.environ.get("LEDSIM_SOAK", "1"))
REAL = os.environ.get("LEDSIM_FUZZ_REAL", "") not in ("", "0")
SHOW = os.environ.get("LEDSIM_FUZZ_SHOW", "") not in ("", "0")  # each example, on stderr
#: Examples per command at LEDSIM_SOAK=1 (the whole file in about a minute on 2 cores).
EXAMPLES = {"evaluate": 50, "train": 40, "export": 15, "replay": 20, "budget": 30,
            "simulate": 80, "run": 150, "render": 30, "sweep": 100, "demo": 25}
#: How the examples ended, per command: (command, how) -> examples.
TRIED: Counter = Counter()

PARSER = build_parser()
COMMANDS = next(a for a in PARSER._actions
                if isinstance(a, argparse._SubParsersAction)).choices
#: With LEDSIM_FUZZ_REAL, appended to the commands that then really run: a short run.
FORCED = {"run": ["--seconds", "3.5", "--seeds", "1", "--workers", "1"],
          "simulate": ["--seconds", "3.5"],
          "sweep": ["--seconds", "3.5", "--seeds", "1", "--workers", "1"]}
ERROR_LINE = re.compile(r"^ledsim( [a-z]+)?: error: \S")


class Started(BaseException):
    """The command got past its checks: its work would start here (BaseException, so
    that no ``except Exception`` on the way takes it for a failure)."""


# ---------------------------------------------------------------------------- values
NUMBER_WORDS = ["nan", "NaN", "inf", "-inf", "+inf", "1e308", "-1e308", "1e-320", "-0",
                "0", "-1", "1e999", "0x10", "1_000", " 1", "1,5", "abc", "", " ", "=", "-",
                "--", "é"]
#: Any text a shell can pass (no NUL, no lone surrogate).
TEXT = st.text(st.characters(min_codepoint=1, blacklist_categories=("Cs",)), max_size=12)
ANY_NUMBER = st.one_of(st.floats().map(repr), st.integers(-10**30, 10**30).map(str),
                       st.sampled_from(NUMBER_WORDS))


def number_bounds(kind) -> tuple[float, float, bool, bool] | None:
    """(lo, hi, integer, lo_open) of an argparse type made by
    ``ledsim.cli.options.number``."""
    try:
        names = inspect.getclosurevars(kind).nonlocals
    except TypeError:
        return None
    if "lo" in names and "hi" in names:
        return (names["lo"], names["hi"], bool(names.get("integer")),
                bool(names.get("lo_open")))
    return None


def _text(v, integer: bool) -> str:
    return str(int(v)) if integer and float(v).is_integer() else repr(v)


def in_range(lo: float, hi: float, integer: bool = False,
             lo_open: bool = False) -> st.SearchStrategy[str]:
    """Numbers of [lo, hi] (``lo_open``: (lo, hi]) as text, its ends included."""
    ends = st.sampled_from([hi] if lo_open else [lo, hi]).map(lambda v: _text(v, integer))
    if integer:
        first = int(lo) + lo_open
        small = st.integers(first, int(min(hi, first + 5))).map(str)
        return st.one_of(st.integers(first, int(hi)).map(str), small, small, ends)
    inside = st.floats(lo, hi, exclude_min=lo_open, allow_nan=False).map(repr)
    return st.one_of(inside, inside.map(lambda v: f"{float(v):.6g}"), ends)


def out_of_range(lo: float, hi: float, integer: bool = False,
                 lo_open: bool = False) -> st.SearchStrategy[str]:
    """Just beyond [lo, hi] (and lo itself when open), far beyond it, and what is no
    number at all."""
    step = 1 if integer else 1e-9
    near = [lo - step * max(1.0, abs(lo)), hi + step * max(1.0, abs(hi))]
    near += [lo] if lo_open else []
    return st.one_of(st.sampled_from(near).map(lambda v: _text(v, integer)), ANY_NUMBER)


def either(good, bad, hostile: bool):
    """``good`` values, or with ``hostile`` mostly good and now and then ``bad``."""
    return st.one_of(good, good, bad) if hostile else good


def disturbance_value(key: str, hostile: bool) -> st.SearchStrategy[str]:
    lo, hi, _, lo_open = RANGES.get(key, (-1e3, 1e3, "", False))
    integer = key in ("seed", "strips")
    return either(in_range(lo, hi, integer, lo_open), out_of_range(lo, hi, integer, lo_open),
                  hostile)


def key_values(keys: list[str], value, hostile: bool) -> st.SearchStrategy[str]:
    """``k=v,...`` items over ``keys``; with ``hostile`` also bad values, unknown keys, a
    missing ``=``, empty items, a key twice."""
    known = st.sampled_from(keys).flatmap(
        lambda k: value(k, hostile).map(lambda v: f"{k}={v}"))
    odd = st.one_of(st.sampled_from(["", "=", "bogus=1", "==1", "height", "seed=1.5",
                                     "period=6=7", " period=6", "PERIOD=6"]),
                    st.sampled_from(keys), TEXT)
    items = st.one_of(known, known, known, odd) if hostile else known
    return st.lists(items, max_size=4, unique_by=None if hostile else
                    (lambda kv: kv.partition("=")[0])).map(",".join)


@st.composite
def disturbance_spec(draw, hostile: bool) -> str:
    names = st.sampled_from(sorted(DISTURBANCES))
    name = draw(either(names, st.one_of(
        st.sampled_from(["", "bogus", "Waves", "waves ", "none"]), TEXT), hostile))
    cls = DISTURBANCES.get(name)
    keys = [f.name for f in dataclasses.fields(cls)] if cls else sorted(RANGES)
    args = draw(key_values(keys, disturbance_value, hostile))
    forms = [f"{name}:{args}", f"{name}:{args}", f"{name}:{args}", name]
    return draw(st.sampled_from(forms + ([f"{name}{args}", f"{name}:", f"{name}::{args}"]
                                         if hostile else [])))


def sweep_cell(hostile: bool) -> st.SearchStrategy[str]:
    """One sweep cell: ``none``, a spec, or specs joined by ``+``."""
    spec = disturbance_spec(hostile)
    return st.one_of(st.just("none"), spec, st.lists(spec, min_size=2, max_size=3)
                     .map("+".join))


def settings_for(kind):
    """``key=value`` items over a dataclass's fields (the vehicle's noise and gains):
    good values are its defaults scaled by 0.1 to 10."""
    defaults = {f.name: f.default for f in dataclasses.fields(kind)}

    def value(key, hostile):
        d = defaults[key]
        good = st.floats(0.1, 10.0).map(lambda x: repr(type(d)(d * x)) if isinstance(
            d, float) else str(max(1, int(d * x))))
        return either(good, ANY_NUMBER, hostile)

    return lambda hostile: key_values(sorted(defaults), value, hostile)


#: Files, as tokens the test body turns into paths of its own folder (@TMP@) or the
#: module's valid ones: (good, bad).
OUT_PATHS = (st.sampled_from(["@TMP@/out", "@TMP@/out.mp4", "@TMP@/out.pt", "@TMP@/out.onnx",
                              "@TMP@/out.png", "@TMP@/new/deeper/out", "@TMP@/new/out.mp4",
                              "@TMP@/dir", "out.mp4", "rel/out"]),
             st.sampled_from(["", ".", "@TMP@", "@TMP@/afile", "@TMP@/afile/out",
                              "@TMP@/out.txt", "/proc/ledsim-fuzz", "/proc/ledsim-fuzz.mp4",
                              "/dev/null", "@TMP@/out.MP4", "@TMP@/.mp4", "/"]))
SPECIAL = {
    "out": OUT_PATHS,
    "plot": OUT_PATHS,
    # the loading of damaged checkpoints, traces and exports is another test's: only
    # missing or valid files here
    "checkpoint": (st.sampled_from(["@CKPT_MUJOCO@", "@CKPT_CLOSED_FORM@"]),
                   st.sampled_from(["@TMP@/missing.pt", "@TMP@/missing"])),
    "onnx": (st.just("@ONNX@"), st.just("@TMP@/missing.onnx")),
    "trace": (st.just("@TRACE@"), st.just("@TMP@/missing.npz")),
    "scene": (st.just("@SCENE@"),
              st.sampled_from(["@TMP@/missing.xml", "/dev/null", "@TMP@", "@TMP@/afile",
                               "@TMP@/bare.xml", "@TMP@/empty.xml", ""])),
    "camera": (st.sampled_from(CAMERAS), st.one_of(st.sampled_from(["bogus", ""]), TEXT)),
    "address": (st.just("auto"), st.sampled_from(["", "ray://127.0.0.1:1"])),
}
KEY_VALUES = {"imu_noise": settings_for(NavigationNoise),
              "station_keeping_gain": settings_for(StationKeeping)}


def value_strategy(command: str, action: argparse.Action,
                   hostile: bool) -> st.SearchStrategy[str]:
    """Values of one flag: its choices or its range, and, with ``hostile``, now and then
    what lies outside them."""
    if action.dest == "disturbance":
        return sweep_cell(hostile) if command == "sweep" else disturbance_spec(hostile)
    if action.dest in KEY_VALUES:
        return KEY_VALUES[action.dest](hostile)
    if action.dest in SPECIAL:
        good, bad = SPECIAL[action.dest]
        suffix = re.search(r"\((\.\w+)\)", action.help or "")
        if suffix:  # a file of this kind (e.g. "video file (.mp4)")
            good = st.sampled_from([f"{p}{suffix.group(1)}" for p in (
                "@TMP@/out", "@TMP@/dir/out", "out")])
            bad = st.one_of(bad, st.sampled_from([f"{p}{suffix.group(1)}" for p in (
                "@TMP@/new/out", "@TMP@/afile/out", "/proc/out")]))
        return either(good, bad, hostile)
    if action.choices is not None:
        return either(st.sampled_from(list(action.choices)),
                      st.one_of(st.sampled_from(["", "bogus", "NONE"]), TEXT), hostile)
    bounds = number_bounds(action.type) if action.type is not None else None
    if bounds is not None:
        return either(in_range(*bounds), out_of_range(*bounds), hostile)
    return either(TEXT, ANY_NUMBER, hostile)


@st.composite
def argv_of(draw, command: str) -> list[str]:
    """An argument list for ``command``: its required arguments and a few of its flags in
    either form, with values from their valid spaces; or, hostile, with now and then a
    bad value, a required argument left out or a stray token."""
    parser = COMMANDS[command]
    hostile = draw(st.booleans())
    actions = [a for a in parser._actions if not isinstance(a, argparse._HelpAction)]
    required = [a for a in actions if a.required or not a.option_strings]
    optional = [a for a in actions if a not in required]
    chosen = [a for a in required if not hostile or draw(st.integers(0, 9))]
    chosen += draw(st.lists(st.sampled_from(optional), max_size=7))
    argv = [command]
    for a in draw(st.permutations(chosen)):
        if not a.option_strings:
            argv.append(draw(value_strategy(command, a, hostile)))
            continue
        flag = draw(st.sampled_from(a.option_strings))
        if a.nargs == 0:
            argv.append(flag)
            continue
        value = draw(value_strategy(command, a, hostile))
        argv += [f"{flag}={value}"] if draw(st.booleans()) else [flag, value]
    stray = draw(st.sampled_from([None] * 8 + ["drop-last", "--bogus", "-x", "extra", "--",
                                               "-h", "--out"])) if hostile else None
    if stray == "drop-last" and len(argv) > 1:
        argv.pop()
    elif stray is not None:
        argv.insert(draw(st.integers(1, len(argv))), stray)
    return argv + FORCED.get(command, []) if REAL else argv


# ----------------------------------------------------------------- the work, stubbed
def _started(*args, **kwargs):
    raise Started


def _started_closing(system, *args, **kwargs):
    if hasattr(system, "close"):  # train_mujoco_observer's physics threads, as it would
        system.close()
    raise Started


_real_run_many = ledsim.loop.report.run_many


def _run_many_checked(cfg, progress=True):
    """``run_many`` through its own checks up to the runner (stubbed), then a stand-in
    result, so that ``demo`` goes on to check its other estimators and its video."""
    try:
        _real_run_many(cfg, progress)
    except Started:
        return object(), None
    raise AssertionError("run_many ran past its stubbed runner")


def stubs(command: str) -> list[tuple[object, str, object]]:
    """(module, name, stand-in) for the work of ``command``."""
    report, video = ledsim.loop.report, ledsim.loop.video
    real = REAL and command in FORCED
    return {
        "evaluate": [(ledsim.paper.evaluate, "run_jobs", _started)],
        "train": [(observer.kkl.training, "generate_transitions", _started_closing),
                  (observer.kkl.training, "train_kkl", _started)],
        "simulate": [] if real else [(ledsim.physics.simulation, "simulate", _started)],
        "run": [] if real else [(report, "run_jobs", _started)],
        "render": [(video, "render_video", _started)],
        "sweep": [(ledsim.experiment.montecarlo, "run_jobs_ray", _started)] + (
            [] if real else [(ledsim.experiment.montecarlo, "run_jobs", _started)]),
        "demo": [(report, "run_jobs", _started), (report, "run_many", _run_many_checked),
                 (report, "write_run", lambda *a, **k: []),
                 (ledsim.loop.table, "format_summary", lambda *a, **k: "| row |"),
                 (ledsim.files.results, "write_json", lambda *a, **k: None),
                 (video, "render_video", _started),
                 (ledsim.cli.demo_cmd, "_delivered", lambda s: "a pass")],
    }.get(command, [])


# -------------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """The valid files the fuzz may hand a command: a scene, shipped checkpoints, a
    trace of ``ledsim run --save-trace`` and an ONNX export of the shipped KKL."""
    folder = tmp_path_factory.mktemp("fuzz_files")
    made = {"@SCENE@": str(scene_path()),
            "@CKPT_MUJOCO@": str(shipped_checkpoint(PAPER_DISTANCE, "mujoco")),
            "@CKPT_CLOSED_FORM@": str(shipped_checkpoint(PAPER_DISTANCE))}
    for argv, path in (
            (["run", "--estimator", "kkl", "--seconds", "0.3", "--seeds", "1", "--workers",
              "1", "--save-trace", "--no-plot", "-q", "--out", str(folder / "run")],
             folder / "run" / "trace_seed0.npz"),
            (["export", "-q", "--out", str(folder / "kkl.onnx")], folder / "kkl.onnx")):
        with contextlib.redirect_stdout(io.StringIO()):
            assert main(argv) == 0, argv
        assert path.is_file()
    made["@TRACE@"] = str(folder / "run" / "trace_seed0.npz")
    made["@ONNX@"] = str(folder / "kkl.onnx")
    return made


@pytest.fixture(scope="module", autouse=True)
def tally():
    """How the examples ended, per command (shown with ``pytest -s``)."""
    yield
    for (command, how), n in sorted(TRIED.items()):
        print(f"fuzz: {command:9s} {how:22s} {n}")


def _tree(folder: Path) -> set[str]:
    return {str(p.relative_to(folder)) for p in folder.rglob("*")}


def call(argv: list[str], command: str) -> tuple[int, str, str]:
    """``main(argv)`` with the work of ``command`` stubbed: (exit code, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    for h in list(logging.root.handlers):  # main's logging.basicConfig binds sys.stderr
        logging.root.removeHandler(h)
    with pytest.MonkeyPatch.context() as mp:
        for module, name, stand_in in stubs(command):
            mp.setattr(module, name, stand_in)
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main(argv)
                how = "ran" if code == 0 else "refused"
            except SystemExit as exc:  # argparse: a usage error, or --help
                code, how = exc.code, "refused by argparse" if exc.code else "help"
            except Started:
                code, how = 0, "checked and started"
            finally:
                for h in list(logging.root.handlers):
                    logging.root.removeHandler(h)
    TRIED[(command, how)] += 1
    if SHOW:
        last = (err.getvalue().strip().splitlines() or [""])[-1]
        print(f"fuzz: {how:22s} {argv}\n      {last[:300]}", file=sys.__stderr__)
    return code, out.getvalue(), err.getvalue()


def check(argv: list[str], command: str, files: dict) -> None:
    """The property: exit 0, or 2 with one ``ledsim: error:`` line (after the warnings
    the command gave before it) and nothing left behind."""
    folder = Path(tempfile.mkdtemp(prefix="ledsim-fuzz-"))
    try:
        (folder / "afile").write_text("not a scene, not a folder\n")
        (folder / "bare.xml").write_text("<mujoco/>\n")
        (folder / "empty.xml").write_text("")
        (folder / "dir").mkdir()
        tokens = {**files, "@TMP@": str(folder)}
        real_argv = [re.sub("|".join(map(re.escape, tokens)), lambda m: tokens[m.group(0)],
                            a) for a in argv]
        before = _tree(folder)
        cwd = os.getcwd()
        os.chdir(folder)  # relative outputs (demo's out/demo) land in the folder
        try:
            code, _, err = call(real_argv, command)
        finally:
            os.chdir(cwd)
        assert code in (0, 2), f"exit {code!r} for {real_argv}:\n{err}"
        assert "Traceback" not in err, err
        after = _tree(folder)
        assert not [p for p in after if p.endswith((".partial", ".tmp"))], after
        if code == 2:
            lines = err.strip("\n").splitlines()
            assert lines and ERROR_LINE.match(lines[-1]), f"{real_argv}:\n{err}"
            assert all(line.startswith("ledsim: ") and not ERROR_LINE.match(line)
                       for line in lines[:-1]), f"{real_argv}:\n{err}"
            assert after == before, f"{real_argv} left {sorted(after - before)}"
    finally:
        shutil.rmtree(folder, ignore_errors=True)


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_every_flag_of_every_command_gives_an_exit_code_never_a_traceback(command, files):
    @settings(max_examples=EXAMPLES.get(command, 20) * SOAK, deadline=None,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
    @given(argv=argv_of(command))
    def fuzz(argv):
        # argv[0], not ``command``: the inner functions share hypothesis's database key,
        # so a failure saved for one command is replayed in the others' runs
        check(argv, argv[0], files)

    fuzz()


def test_the_fuzz_reads_every_command_and_the_range_of_every_number():
    """The parser is read, not listed: the commands are all there (a new one is fuzzed
    with 20 examples), and every flag with a type is a ``number`` whose range the fuzz
    reads (``ledsim.cli.options``: finite, in a physical range)."""
    assert set(EXAMPLES) <= set(COMMANDS)
    for command, parser in COMMANDS.items():
        ranged = [a.dest for a in parser._actions if a.type is not None
                  and a.dest not in SPECIAL and number_bounds(a.type) is None]
        assert not ranged, f"{command}: {ranged} are not ledsim.cli.options.number"
