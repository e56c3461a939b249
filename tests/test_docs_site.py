"""The documentation site, guides and API reference (mkdocs + mkdocstrings, configured in
mkdocs.yml), builds with ``--strict``: no warning (a broken link, a page left out of the
navigation, a docstring mkdocstrings cannot read, an object it cannot find)."""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_mkdocs_build_strict(tmp_path):
    for module in ("mkdocs", "mkdocstrings", "mkdocstrings_handlers.python"):
        try:
            found = importlib.util.find_spec(module) is not None
        except ModuleNotFoundError:
            found = False
        if not found:
            pytest.skip(f"{module} is not installed (pip install -e '.[dev]')")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(ROOT / "src"), *filter(None, [os.environ.get("PYTHONPATH")])]))
    proc = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict",
                           "--config-file", str(ROOT / "mkdocs.yml"),
                           "--site-dir", str(tmp_path / "site")],
                          capture_output=True, text=True, timeout=600, env=env, cwd=ROOT)
    warnings = [line for line in proc.stderr.splitlines()
                if line.startswith(("WARNING", "ERROR"))]
    assert proc.returncode == 0 and not warnings, proc.stderr[-4000:]
    api = tmp_path / "site" / "api" / "solvers" / "index.html"
    text = api.read_text(encoding="utf-8")
    assert "max_memory" in text and "SimResult" in text       # docstrings, rendered
    assert (tmp_path / "site" / "tutorial" / "index.html").exists()
    shutil.rmtree(tmp_path / "site")
