"""Ctrl-C soak: interrupt a real ``ledsim`` command at random moments and count hangs.

    python scripts/interrupt_soak.py [--runs 50] [--seed 0] [--command run] [--json]

One uninterrupted run first measures how long the command takes (its wall time T);
then each of ``--runs`` runs gets SIGINT at a moment drawn uniformly from 0-T s after
its start (``--seed`` fixes the moments), like a terminal's Ctrl-C: to the whole process
group (the workers too), or every other run to the ledsim process alone (``kill -INT``).
Each run writes into an ``--out`` folder that already holds a finished run's files, so
an interrupt must leave it byte-identical (or, when the signal came after the commit,
complete with the new run's files), with no temporary left beside it. A sweep starts
from no folder (it would resume from the finished one and run nothing): it may leave
the cells it finished, each whole, for the next run to resume from.

A Ctrl-C in the first milliseconds, while Python itself starts (``site``, with an
editable install setuptools' finder; ``runpy``: 3-25 ms idle, up to 0.4 s loaded),
comes before ledsim's handler is installed (the first thing ``ledsim.cli.console``
does): Python's default handler prints a traceback then. Such tracebacks (no
``console`` frame) are counted apart.

Counted per run: a hang (no exit within ``--deadline`` s of the signal: the run is then
killed with SIGKILL), a traceback on stderr, a missing ``interrupted`` line or an exit
code other than 130 (0 if the run had finished), a broken ``--out``, a worker alive after
the run ended. Prints a table; with ``--json`` the counts and the exit times as JSON.
Exit status 1 when any run hung, printed a traceback or broke its output.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: The commands that can be soaked: all go through ``ledsim.experiment.montecarlo.run_jobs``.
COMMANDS = {
    "run": ["run", "--seconds", "{seconds}", "--seeds", "{seeds}", "--workers", "{workers}",
            "--save-trace"],
    "sweep": ["sweep", "--seconds", "{seconds}", "--seeds", "{seeds}", "--workers",
              "{workers}", "--estimator", "kkl", "--estimator", "ekf"],
    "demo": ["demo", "--seeds", "{seeds}"],
    "evaluate": ["evaluate", "--scenario", "if1", "--seeds", "{seeds}", "--workers",
                 "{workers}"],
}


def command(args, out: Path) -> list[str]:
    """The ledsim command line of a run writing to ``out`` (``python -m ledsim``)."""
    fill = {"seconds": f"{args.seconds:g}", "seeds": str(args.seeds),
            "workers": str(args.workers)}
    return [sys.executable, "-m", "ledsim", *[a.format(**fill) for a in
                                              COMMANDS[args.command]],
            "--quiet", "--out", str(out)]


def snapshot(folder: Path) -> dict[str, bytes]:
    """Every file under ``folder`` (relative path -> bytes); empty if it is absent."""
    if not folder.is_dir():
        return {}
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


def group_alive(pgid: int) -> bool:
    """Whether any process of the group ``pgid`` is still alive (not a zombie)."""
    for status in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = status.read_text().rsplit(")", 1)[1].split()
        except (OSError, IndexError):
            continue
        if int(fields[2]) == pgid and fields[0] != "Z":
            return True
    return False


def one_run(args, cmd_out: Path, original: dict, names: set, moment: float,
            to_group: bool) -> dict:
    """Start the command, SIGINT it ``moment`` s later, and judge how it ended: ``out``
    must hold ``original`` (the files it held before) or the run's files ``names``
    (a sweep: also a part of them, the cells finished, each whole)."""
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "osmesa")}
    proc = subprocess.Popen(command(args, cmd_out), stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, env=env, start_new_session=True,
                            cwd=cmd_out.parent)
    try:
        time.sleep(moment)
        finished = proc.poll() is not None
        t0 = time.perf_counter()
        if not finished:
            if to_group:
                os.killpg(proc.pid, signal.SIGINT)  # a terminal's Ctrl-C: the whole group
            else:
                proc.send_signal(signal.SIGINT)
        hang, late = False, None
        try:
            proc.wait(timeout=args.deadline)
        except subprocess.TimeoutExpired:
            hang = True
        elapsed = time.perf_counter() - t0
        if hang:
            try:  # how late, if at all
                proc.wait(timeout=args.patience)
                late = round(time.perf_counter() - t0, 3)
            except subprocess.TimeoutExpired:
                pass
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    except BaseException:  # the soak itself stopped: leave no run behind
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        raise
    time.sleep(0.2)  # the workers' SIGTERM from a dead parent is asynchronous
    orphans = group_alive(proc.pid)
    if orphans:
        os.killpg(proc.pid, signal.SIGKILL)
    err = proc.stderr.read().decode(errors="replace")
    proc.stderr.close()
    now = snapshot(cmd_out)
    leftovers = sorted(p.name for p in cmd_out.parent.iterdir() if p != cmd_out)
    complete = set(now) >= names and now != original
    resumable = args.command == "sweep" and set(now) <= names and all(
        _whole_json(data) for name, data in now.items() if name.endswith(".json"))
    return {"moment": round(moment, 3), "group": to_group, "finished": finished,
            "exit": proc.returncode, "seconds": None if hang else round(elapsed, 3),
            "hang": hang, "late_exit": late, "traceback": "Traceback" in err,
            # before ledsim's handler (installed first thing in console()): Python's own
            # start-up, out of ledsim's reach (see the module docstring)
            "before_handler": "Traceback" in err and ", in console" not in err,
            "interrupted": "interrupted" in err, "forced": "forced" in err,
            "out": "untouched" if now == original else "complete" if complete else
                   "resumable" if resumable else "broken",
            "leftovers": leftovers, "orphans": orphans,
            "stderr": err.strip().splitlines()[-3:]}


def _whole_json(data: bytes) -> bool:
    try:
        json.loads(data)
    except ValueError:
        return False
    return True


def judge(r: dict) -> list[str]:
    """What went wrong in one run (empty: nothing)."""
    wrong = []
    if r["hang"]:
        wrong.append("hang")
    if r["traceback"]:
        wrong.append("traceback")
    if r["out"] == "broken" or r["leftovers"]:
        wrong.append("broken output")
    if r["orphans"]:
        wrong.append("orphans")
    if not r["hang"] and r["exit"] != (0 if r["finished"] else 130):
        wrong.append(f"exit {r['exit']}")
    if not r["hang"] and not r["finished"] and not r["interrupted"]:
        wrong.append("no 'interrupted'")
    return wrong


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=50, help="interrupted runs")
    ap.add_argument("--seed", type=int, default=0, help="seed of the moments")
    ap.add_argument("--command", choices=sorted(COMMANDS), default="run")
    ap.add_argument("--seconds", type=float, default=40.0,
                    help="simulated seconds of each run (run, sweep)")
    ap.add_argument("--seeds", type=int, default=4, help="seeds of each run")
    ap.add_argument("--workers", type=int, default=2, help="worker processes")
    ap.add_argument("--deadline", type=float, default=2.0,
                    help="seconds from the signal to the exit before a run counts as hung")
    ap.add_argument("--patience", type=float, default=0.0,
                    help="seconds more to wait for a hung run before SIGKILL, to tell a "
                         "late exit from a hang that would last")
    ap.add_argument("--json", action="store_true", help="print the counts as JSON")
    args = ap.parse_args()
    if args.runs < 1 or args.deadline <= 0 or args.patience < 0:
        ap.error("--runs must be >= 1, --deadline > 0 and --patience >= 0")
    # Stopped (timeout, kill): unwind, so that no run and no folder is left behind.
    signal.signal(signal.SIGTERM, lambda signum, frame: sys.exit(1))
    work = Path(tempfile.mkdtemp(prefix="interrupt_soak."))
    try:
        ref = work / "ref" / "out"
        t0 = time.perf_counter()
        r = subprocess.run(command(args, ref), capture_output=True, text=True, cwd=work,
                           env={**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL",
                                                                          "osmesa")})
        span = time.perf_counter() - t0
        if r.returncode != 0:
            print(f"interrupt_soak: the uninterrupted run failed: {r.stderr.strip()}",
                  file=sys.stderr)
            return 1
        original = names = snapshot(ref)
        rng = random.Random(args.seed)
        moments = sorted(rng.uniform(0.0, span) for _ in range(args.runs))
        results = []
        for k, moment in enumerate(moments):
            folder = work / f"run{k}"
            if args.command == "sweep":  # it resumes from the cells it finds: none
                folder.mkdir()
                original = {}
            else:  # a finished run's folder: an interrupt must leave it as it was
                shutil.copytree(ref, folder / "out")
            res = one_run(args, folder / "out", original, set(names), moment,
                          to_group=k % 2 == 0)
            res["wrong"] = judge(res)
            results.append(res)
            shutil.rmtree(folder, ignore_errors=True)
            took = "hung" if res["hang"] else f"{res['seconds']:.2f} s"
            print(f"{k + 1:3d}/{len(moments)} at {moment:6.2f} s "
                  f"({'group' if res['group'] else 'parent'}): exit {res['exit']}, {took}, "
                  f"out {res['out']}{'; ' + ', '.join(res['wrong']) if res['wrong'] else ''}",
                  file=sys.stderr)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(summary_table(args, span, results))
    if args.json:
        print(json.dumps(summary(args, span, results), indent=2))
    bad = [r for r in results if r["hang"] or r["traceback"] or r["out"] == "broken"]
    return 1 if bad else 0


def summary(args, span: float, results: list[dict]) -> dict:
    """The counts and the exit times (seconds from the signal) of the soak."""
    times = [r["seconds"] for r in results if not r["finished"] and not r["hang"]]
    return {"command": args.command, "runs": len(results), "seed": args.seed,
            "run_seconds": round(span, 2), "deadline": args.deadline,
            "interrupted": sum(not r["finished"] for r in results),
            "finished_before_signal": sum(r["finished"] for r in results),
            "hangs": sum(r["hang"] for r in results),
            "hangs_that_ended_later": sum(r["late_exit"] is not None for r in results),
            "tracebacks": sum(r["traceback"] for r in results),
            "tracebacks_before_the_handler": sum(r["before_handler"] for r in results),
            "forced_exits": sum(r["forced"] for r in results),
            "broken_outputs": sum(r["out"] == "broken" or bool(r["leftovers"])
                                  for r in results),
            "orphans": sum(r["orphans"] for r in results),
            "wrong_exit_or_message": sum(any(w.startswith(("exit", "no ")) for w in
                                             r["wrong"]) for r in results),
            "exit_seconds_max": max(times, default=None),
            "exit_seconds_median": statistics.median(times) if times else None,
            "failures": [{k: r[k] for k in ("moment", "group", "exit", "seconds", "late_exit",
                                            "wrong", "stderr")} for r in results if r["wrong"]]}


def summary_table(args, span: float, results: list[dict]) -> str:
    s = summary(args, span, results)
    fmt = (lambda v: "-" if v is None else f"{v:.2f} s")  # noqa: E731
    workers = f", --workers {args.workers}" if "{workers}" in COMMANDS[args.command] else ""
    rows = [("command", f"ledsim {args.command} ({span:.1f} s uninterrupted{workers})"),
            ("interrupts", f"{s['interrupted']} of {s['runs']} runs "
                           f"({s['finished_before_signal']} finished first)"),
            (f"hangs (no exit within {args.deadline:g} s)", s["hangs"]),
            *([(f"... of which ended within {args.patience:g} s more",
                s["hangs_that_ended_later"])] if args.patience else []),
            ("tracebacks", s["tracebacks"]),
            ("... of which in Python's start-up, before ledsim's handler",
             s["tracebacks_before_the_handler"]),
            ("forced exits", s["forced_exits"]), ("broken outputs", s["broken_outputs"]),
            ("orphaned workers", s["orphans"]),
            ("wrong exit code or message", s["wrong_exit_or_message"]),
            ("time to exit, median", fmt(s["exit_seconds_median"])),
            ("time to exit, max", fmt(s["exit_seconds_max"]))]
    return "\n".join(["| measure | value |", "|---|---|",
                      *[f"| {a} | {b} |" for a, b in rows]])


if __name__ == "__main__":
    sys.exit(main())
