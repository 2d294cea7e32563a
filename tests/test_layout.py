"""The architecture, pinned: which package may import which, and module size.

    observer/          estimation; imports nothing of ledsim
    ledsim/physics     the plant in MuJoCo (world, sensors, water, disturbances)
    ledsim/radiometry  the plant's optics and link presets; never mujoco
    ledsim/agent       the control step and the vehicle's autopilot; reads the plant
    ledsim/paper       the closed-form world; never mujoco, never physics or loop
    ledsim/loop        runs in MuJoCo; never paper or cli
    ledsim/envs        the Gymnasium environment; never paper or cli
    ledsim/experiment  what every experiment shares; never a world of its own
    ledsim/files       what ledsim reads and writes; imports nothing of ledsim but errors
    ledsim/*.py        constants, errors, key=value input; never a subpackage (the
                       constants' receiver layout, and the CLI's entry, excepted)"""

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SHARED_MAY_IMPORT = {"ledsim.cli": None}  # the CLI wires everything together
RUNS = ("ledsim.loop", "ledsim.paper", "ledsim.envs", "ledsim.cli")
AGENT_AND_RUNS = ("ledsim.agent", "ledsim.experiment", *RUNS)

FORBIDDEN = {
    "observer": ("ledsim",),
    "ledsim.physics": AGENT_AND_RUNS,
    "ledsim.radiometry": ("mujoco", "ledsim.physics", *AGENT_AND_RUNS),
    "ledsim.agent": ("ledsim.experiment", *RUNS),
    "ledsim.paper": ("mujoco", "ledsim.physics", "ledsim.loop", "ledsim.envs", "ledsim.cli"),
    "ledsim.loop": ("ledsim.paper", "ledsim.envs", "ledsim.cli"),
    "ledsim.envs": ("ledsim.paper", "ledsim.cli"),
    "ledsim.experiment": ("mujoco", "ledsim.physics", *RUNS),
    "ledsim.files": ("mujoco", "ledsim.physics", "ledsim.radiometry", *AGENT_AND_RUNS),
    "ledsim": ("ledsim.physics", "ledsim.radiometry", "ledsim.files", *AGENT_AND_RUNS, "mujoco"),
}
# the one exception at the top: the constants carry the receiver's layout (plain data)
ALLOWED = {"ledsim.constants": ("ledsim.physics.layout",)}


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports_of(path: Path, module: str | None = None) -> set[str]:
    """Absolute names of the modules that ``path`` imports (relative imports resolved)."""
    package = (module or module_name(path)).split(".")
    if path.name != "__init__.py":
        package = package[:-1]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else []
            mod = ".".join(base + ([node.module] if node.module else []))
            found.add(mod)
            found |= {f"{mod}.{a.name}" for a in node.names}
    return found


def rule_for(module: str) -> tuple[str, tuple[str, ...]]:
    """The most specific rule of FORBIDDEN that applies to ``module``."""
    if module.startswith("ledsim.") and module.count(".") >= 1:
        sub = ".".join(module.split(".")[:2])
        if sub in FORBIDDEN:
            return sub, FORBIDDEN[sub]
        if sub in SHARED_MAY_IMPORT or sub == "ledsim.__main__":
            return sub, ()
        return "ledsim", FORBIDDEN["ledsim"]
    if module == "ledsim":
        return "ledsim", ("ledsim.physics", "ledsim.loop", "ledsim.cli", "mujoco")  # its __init__
    return module.split(".")[0], FORBIDDEN.get(module.split(".")[0], ())


def sources():
    for pkg in ("ledsim", "observer"):
        yield from sorted((ROOT / pkg).rglob("*.py"))


@pytest.mark.parametrize("path", list(sources()), ids=lambda p: str(p.relative_to(ROOT)))
def test_import_rules(path):
    rule, forbidden = rule_for(module_name(path))
    module = module_name(path)
    allowed = ALLOWED.get(module, ())
    bad = sorted(n for n in imports_of(path)
                 if any(n == f or n.startswith(f + ".") for f in forbidden)
                 and not any(n == a or n.startswith(a + ".") for a in allowed))
    assert not bad, f"{module_name(path)} ({rule}) imports {bad}"


@pytest.mark.parametrize("path", list(sources()), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_module_over_300_lines(path):
    assert len(path.read_text().splitlines()) <= 300


def test_the_rules_catch_a_violation(tmp_path):
    """The checker itself can fail: a paper module importing mujoco is caught."""
    fake = ROOT / "ledsim" / "paper" / "model.py"
    assert rule_for(module_name(fake))[1] == FORBIDDEN["ledsim.paper"]
    bad = tmp_path / "x.py"
    bad.write_text("import mujoco\nfrom ..physics import world\n")
    found = imports_of(bad, "ledsim.paper.x")
    assert "mujoco" in found and "ledsim.physics.world" in found


def assert_not_imported(module: str, code: str) -> None:
    """Run ``code`` in a fresh interpreter and check it never imported ``module``."""
    code = f"import sys\n{code}assert {module!r} not in sys.modules, '{module} imported'\n"
    r = subprocess.run([sys.executable, "-c", code + "print('ok')\n"], capture_output=True,
                       text=True, cwd=ROOT, timeout=300)
    assert r.returncode == 0 and "ok" in r.stdout, r.stderr


def test_the_paper_world_runs_without_mujoco():
    """Evaluating a paper scenario never loads mujoco (checked in a fresh interpreter)."""
    assert_not_imported("mujoco",
                        "from ledsim.paper.evaluate import EvaluationConfig, evaluate\n"
                        "evaluate(EvaluationConfig(scenario='if1', seeds=1, starts=0, workers=1,"
                        " estimators=('kkl', 'ekf')), progress=False)\n")


def test_torch_is_imported_only_when_needed():
    """The CLI and a filter-driven run never import torch (2-3 s of start-up)."""
    assert_not_imported("torch",
                        "from ledsim.cli import build_parser\n"
                        "build_parser()\n"
                        "from ledsim.loop.closed_loop import run_once\n"
                        "from ledsim.loop.run_config import RunConfig\n"
                        "run_once(RunConfig(estimator='ekf', seconds=0.1), 0)\n")


def _project_modules():
    for pkg in ("ledsim", "observer"):
        for path in sorted((ROOT / pkg).rglob("*.py")):
            yield module_name(path), path


def test_no_import_cycle():
    """No module imports itself back through others (imports inside functions count)."""
    names = {name for name, _ in _project_modules()}
    graph = {}
    for name, path in _project_modules():
        deps = set()
        for n in imports_of(path):
            while n and n not in names:  # ``from pkg import name``: the module is pkg
                n = n.rpartition(".")[0]
            if n and n != name and not name.startswith(n + "."):
                deps.add(n)
        graph[name] = deps - {n for n in deps if n.count(".") == 0}  # package roots
    state: dict[str, int] = {}

    def visit(node, stack):
        state[node] = 1
        for dep in graph.get(node, ()):
            if state.get(dep) == 1:
                cycle = stack[stack.index(dep):] + [dep]
                if not all(m.endswith("__init__") or m in ("ledsim", "observer")
                           for m in cycle[:-1]):
                    raise AssertionError(" -> ".join(cycle))
            elif state.get(dep) is None:
                visit(dep, stack + [dep])
        state[node] = 2

    for node in sorted(graph):
        if node not in state:
            visit(node, [node])


def test_link_world_privates_stay_in_world_py():
    """Other modules read the world through its named accessors and ``world.ids``."""
    import re

    pattern = re.compile(r"\b(world|w0|w|wd)\._(?!_)[a-z]")
    bad = []
    for pkg in ("ledsim", "observer", "scripts"):
        for path in sorted((ROOT / pkg).rglob("*.py")):
            if path.name == "world.py":
                continue
            for k, line in enumerate(path.read_text().splitlines(), 1):
                if pattern.search(line):
                    bad.append(f"{path.relative_to(ROOT)}:{k}: {line.strip()}")
    assert not bad, "\n".join(bad)
