"""Architecture rule: estimation (observer/) never depends on the physical world (ledsim/)."""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_observer_never_imports_ledsim():
    offenders = []
    for path in (ROOT / "observer").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                names = [node.module]
            offenders += [f"{path.name}: {n}" for n in names if n.split(".")[0] == "ledsim"]
    assert not offenders, offenders
