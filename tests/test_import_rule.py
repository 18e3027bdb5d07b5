"""The method never sees the simulator: `fsv` imports neither benchmark, mujoco, dm_control nor pyrender."""

import ast
import pathlib
import subprocess
import sys

FORBIDDEN = {"benchmark", "mujoco", "dm_control", "pyrender"}
FSV = pathlib.Path(__file__).resolve().parents[1] / "fsv"


def test_no_forbidden_import_statement_in_fsv():
    bad = []
    for path in FSV.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                names = [node.module or ""]
            else:
                continue
            bad += [f"{path.name}:{node.lineno} {n}" for n in names if n.split(".")[0] in FORBIDDEN]
    assert not bad, bad


def test_importing_fsv_loads_no_forbidden_module():
    code = (
        "import sys, fsv, pkgutil, importlib\n"
        "for m in pkgutil.walk_packages(fsv.__path__, 'fsv.'): importlib.import_module(m.name)\n"
        f"print(sorted(m for m in sys.modules if m.split('.')[0] in {sorted(FORBIDDEN)!r}))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         cwd=FSV.parent).stdout.strip()
    assert out == "[]"
