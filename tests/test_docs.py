"""The docs' code runs: every block marked ``<!-- test: run -->`` (the line before a
```python fence) is executed, the blocks of one page in order in one namespace."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = sorted([ROOT / "README.md", *(ROOT / "docs").rglob("*.md")])
MARK = re.compile(r"^<!-- test: run -->\n```python\n(.*?)^```", re.S | re.M)


def runnable_blocks(page: Path) -> list[str]:
    return MARK.findall(page.read_text(encoding="utf-8"))


def test_marked_blocks_are_found():
    # the marker and the fence must stay together, or blocks would be skipped silently
    assert len(runnable_blocks(ROOT / "docs" / "modeling.md")) >= 3
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        marks = re.findall(r"^<!-- test: run -->$", text, re.M)
        assert len(marks) == len(runnable_blocks(page)), page


@pytest.mark.parametrize("page", [p for p in PAGES if runnable_blocks(p)],
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_runnable_blocks_of_a_page(page, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)                # files a block writes go here
    namespace: dict = {"__name__": "__docs__"}
    for k, code in enumerate(runnable_blocks(page), 1):
        exec(compile(code, f"{page.name}, runnable block {k}", "exec"), namespace)
    capsys.readouterr()
