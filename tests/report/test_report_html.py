"""The HTML report of a model, opened in a real browser (headless Chromium)."""

import shutil
import subprocess

import pytest

import mechatron as mt
from mechatron.cli import main
from mechatron.report.html import render_report

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


def test_report_has_its_sections_and_embedded_images():
    text = render_report(mt.models.get("dc_motor"))
    for section in ("diagram", "parameters", "plots", "expected", "comparison", "profile"):
        assert f'id="{section}"' in text
    assert "<svg" in text                              # the schematic, inline
    assert text.count("data:image/png;base64,") == 2   # outputs and overlay
    assert "seed table 6-1" in text                    # provenance of the parameters
    assert 'class="bad"' not in text                   # expected values and variants hold


def test_report_refuses_a_missing_folder(tmp_path, capsys):
    assert main(["report", "dc_motor", "--out", str(tmp_path / "nope" / "r.html")]) == 2
    assert "does not exist" in capsys.readouterr().err


@pytest.mark.skipif(CHROMIUM is None, reason="Chromium not installed (make test installs "
                                             "it when run as root)")
@pytest.mark.skipif(shutil.which("dot") is None, reason="Graphviz `dot` not installed")
def test_report_opens_in_headless_chromium(tmp_path):
    out = tmp_path / "dc_motor.html"
    assert main(["report", "dc_motor", "--out", str(out)]) == 0
    run = subprocess.run(
        [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
         "--no-first-run", "--disable-background-networking", "--disable-component-update",
         "--disable-sync", f"--user-data-dir={tmp_path / 'profile'}", "--dump-dom",
         out.as_uri()], capture_output=True, timeout=120, text=True)
    dom = run.stdout
    assert run.returncode == 0, run.stderr[-2000:]
    # the DOM as the browser parsed it: the diagram is an SVG element with the parts
    start = dom.index('id="diagram"')
    assert "<svg" in dom[start:start + 400]
    assert "RotationalEMF" in dom and "emf" in dom
    # plots are decoded images, the tables have their rows
    assert dom.count('src="data:image/png;base64,') == 2
    params = dom[dom.index('id="parameters"'):]
    params = params[:params.index("</table>")]
    assert params.count("<tr>") == 1 + len(mt.models.get("dc_motor").parameters)
    assert "Solver profile" in dom
