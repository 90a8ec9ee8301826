"""The HTML report in a real headless browser (Debian's ``chromium``): the page renders to a PNG
that is not blank and the rendered DOM holds the flutter-change table (paper Table 5) with its rows.

Skipped only when ``chromium`` is not on PATH (``.ci/run`` installs it with apt-get).
"""
from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest
from matplotlib.image import imread

from pipeline.report import write_report
from tests.pipeline.run_fixture import EXPECTED_CHANGE, make_run
from tests.pipeline.test_report import Tables

CHROMIUM = shutil.which("chromium")
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="chromium is not on PATH (Debian: "
                                "apt-get install -y chromium; .ci/run installs it)")
WIDTH, HEIGHT = 1280, 4000


def _chromium(tmp_path, *args) -> subprocess.CompletedProcess:
    """One headless chromium run with its own profile folder (no state shared between runs)."""
    return subprocess.run(
        [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
         f"--user-data-dir={tmp_path / 'profile'}", f"--window-size={WIDTH},{HEIGHT}", *args],
        capture_output=True, text=True, timeout=300, check=True)


def _ink(png) -> tuple[float, int]:
    """Fraction of pixels that are not (near) white and the number of distinct colours (RGB
    quantised to 32 levels) of a screenshot."""
    rgb = imread(png)[..., :3]
    assert rgb.shape[:2] == (HEIGHT, WIDTH)
    levels = np.round(rgb * 31).astype(int).reshape(-1, 3)
    colours = np.unique(levels[:, 0] * 1024 + levels[:, 1] * 32 + levels[:, 2]).size
    return float(np.mean(np.any(rgb < 0.94, axis=-1))), colours


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    case, run_dir = make_run(tmp_path_factory.mktemp("browser"))
    return write_report(case, run_dir)


def test_report_renders_in_chromium(page, tmp_path):
    shot = tmp_path / "report.png"
    _chromium(tmp_path, f"--screenshot={shot}", page.resolve().as_uri())
    ink, colours = _ink(shot)
    # an empty page rendered the same way is the reference for "blank"
    blank_page = tmp_path / "blank.html"
    blank_page.write_text("<!DOCTYPE html><html><body></body></html>")
    blank = tmp_path / "blank.png"
    _chromium(tmp_path, f"--screenshot={blank}", blank_page.resolve().as_uri())
    blank_ink, blank_colours = _ink(blank)
    assert blank_ink < 0.001 and blank_colours <= 2
    # text, tables and figures of the first 4,000 px: measured 0.067 of the pixels inked and 921
    # colours (chromium 156, Debian 12); text alone in one colour would give a handful
    assert ink > 0.02
    assert colours > 100


def test_rendered_dom_holds_the_flutter_change_table(page, tmp_path):
    dom = _chromium(tmp_path, "--dump-dom", page.resolve().as_uri()).stdout
    table = next(t for t in Tables(dom).tables if t["id"] == "flutter-change")
    assert "stage 1 speed change [%]" in table["header"]
    col = table["header"].index("stage 1 speed change [%]")
    rows = {(r[0], float(r[1]), int(r[3][0])): r[col] for r in table["rows"]}
    assert rows == {key: ("\u2013" if dv is None else f"{dv:+.2f}")
                    for key, (dv, _) in EXPECTED_CHANGE.items()}
