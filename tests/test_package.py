"""Package-wide conventions: ``python -m mechatron``, no ``print`` in library code (it
logs to the ``mechatron`` logger), the license the package declares."""

from __future__ import annotations

import ast
import os
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "mechatron"


def test_python_dash_m_mechatron_runs_the_command():
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(ROOT / "src"), *filter(None, [os.environ.get("PYTHONPATH")])]))
    proc = subprocess.run([sys.executable, "-m", "mechatron", "--version"], env=env,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and proc.stdout.startswith("mechatron "), proc.stderr
    proc = subprocess.run([sys.executable, "-m", "mechatron", "show", "no_such_model"],
                          env=env, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.startswith("error: no model 'no_such_model'")
    assert proc.stderr.count("\n") == 1


def _is_command_line(path: Path) -> bool:
    """The command-line modules, the only ones that may print."""
    return path.name in ("cli.py", "hil_cli.py", "__main__.py")


def test_library_code_does_not_print():
    offenders = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if _is_command_line(path):
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) \
                    and node.func.id == "print":
                offenders.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert offenders == [], "use the mechatron logger instead: " + ", ".join(offenders)


def test_license_is_the_apache_2_text_that_pyproject_declares():
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert meta["license"] == "Apache-2.0"
    text = (ROOT / "LICENSE").read_text()
    assert "Apache License" in text and "Version 2.0, January 2004" in text
    for section in ("1. Definitions.", "2. Grant of Copyright License.",
                    "3. Grant of Patent License.", "4. Redistribution.",
                    "9. Accepting Warranty or Additional Liability.",
                    "END OF TERMS AND CONDITIONS"):
        assert section in text
