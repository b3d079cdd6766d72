"""Open the HTML report in a real headless browser (Debian's chromium).

Skipped when no ``chromium`` is on PATH (``.ci/run`` installs it). Checks
that the page's script runs to its end without JavaScript errors, that
dragging one view turns both (the page's ``#selftest``), and that a
screenshot of the views is not blank.
"""

from __future__ import annotations

import re
import shutil
import subprocess

import numpy as np
import pytest

from meshcorr import datasets
from meshcorr.viz.report import write_report

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed "
                                "(apt-get install -y chromium; .ci/run installs it)")

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--hide-scrollbars"]


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    folder = tmp_path_factory.mktemp("browser")
    source = datasets.tube(n_along=16, n_around=10, bend=0.0)
    target = datasets.tube(n_along=16, n_around=10, bend=1.5)
    path = folder / "report.html"
    summary = {"timings": {"geodesics": 0.1},
               "configuration": {"perm": [0, 1], "signs": [1, 1], "cost": 0.01}}
    write_report(path, (source.vertices, source.faces), (target.vertices, target.faces),
                 datasets.ground_truth(source, target), summary,
                 errors=np.linspace(0.0, 0.1, 20))
    return folder, path


def _chromium(folder, *args) -> subprocess.CompletedProcess:
    return subprocess.run([CHROMIUM, *FLAGS, f"--user-data-dir={folder / 'profile'}", *args],
                          capture_output=True, text=True, timeout=120)


def test_report_runs_without_errors_and_views_are_linked(report):
    folder, path = report
    done = _chromium(folder, "--virtual-time-budget=5000", "--dump-dom",
                     path.as_uri() + "#selftest")
    body = re.search(r"<body[^>]*>", done.stdout)
    assert body, done.stderr[-2000:]
    assert 'data-status="ok"' in body.group(0), done.stdout[:3000]
    assert 'data-linked="yes"' in body.group(0)
    errors = re.search(r'<pre id="errors"[^>]*>(.*?)</pre>', done.stdout, re.S)
    assert errors and errors.group(1).strip() == ""


def test_report_screenshot_is_not_blank(report):
    from matplotlib.image import imread

    folder, path = report
    shot = folder / "shot.png"
    _chromium(folder, f"--screenshot={shot}", "--window-size=1200,700", path.as_uri())
    image = imread(str(shot))[:, :, :3]
    # The two canvases sit side by side below the title (each 560 px wide, ~100 px down).
    for left in (20, 600):
        view = image[110:540, left:left + 560]
        background = np.all(np.abs(view - 0xF4 / 255) < 0.02, axis=2)
        white = np.all(view > 0.97, axis=2)
        mesh = ~(background | white)
        coloured = mesh & (view.max(axis=2) - view.min(axis=2) > 0.15)
        assert mesh.mean() > 0.03, f"view at x={left}: {mesh.mean():.3f} drawn"
        assert coloured.mean() > 0.02
