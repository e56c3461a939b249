"""The docs' code runs: every block marked ``<!-- test: run -->`` (the line before a
```python fence) is executed, the blocks of one page in order in one namespace, in a
temporary folder. Two more markers serve the tutorial: ``<!-- test: file NAME -->`` writes
the fenced block below it to the file NAME (a model file, a problem file) and
``<!-- test: shell -->`` runs each ``mechatron ...`` line of the fenced block below it
with :func:`mechatron.cli.main`, which must return 0."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = sorted([ROOT / "README.md", *(ROOT / "docs").rglob("*.md")])
MARK = re.compile(r"^<!-- test: run -->\n```python\n(.*?)^```", re.S | re.M)
#: Every marked block in order: (kind, file name or "", code).
BLOCK = re.compile(r"^<!-- test: (run|shell|file) ?(\S*) -->\n```\w*\n(.*?)^```",
                   re.S | re.M)


def runnable_blocks(page: Path) -> list[str]:
    return MARK.findall(page.read_text(encoding="utf-8"))


def test_marked_blocks_are_found():
    # the marker and the fence must stay together, or blocks would be skipped silently
    assert len(runnable_blocks(ROOT / "docs" / "modeling.md")) >= 3
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        marks = re.findall(r"^<!-- test: run -->$", text, re.M)
        assert len(marks) == len(runnable_blocks(page)), page
        every = re.findall(r"^<!-- test: .* -->$", text, re.M)
        assert len(every) == len(BLOCK.findall(text)), page


@pytest.mark.parametrize("page", [p for p in PAGES if BLOCK.findall(p.read_text())],
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_runnable_blocks_of_a_page(page, tmp_path, monkeypatch, capsys):
    import shlex

    from mechatron.cli import main
    monkeypatch.chdir(tmp_path)                # files a block writes go here
    monkeypatch.syspath_prepend(str(tmp_path))  # and modules it writes are importable
    namespace: dict = {"__name__": "__docs__"}
    for k, (kind, name, code) in enumerate(BLOCK.findall(page.read_text("utf-8")), 1):
        where = f"{page.name}, block {k}"
        if kind == "file":
            (tmp_path / name).write_text(code, encoding="utf-8")
        elif kind == "shell":
            for line in code.splitlines():
                if line.startswith("mechatron "):
                    code_ = main(shlex.split(line)[1:])
                    assert code_ == 0, (where, line, capsys.readouterr().err)
        else:
            exec(compile(code, where, "exec"), namespace)
    capsys.readouterr()
