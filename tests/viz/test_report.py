"""The self-contained HTML report (`meshcorr match --report`), checked without a browser."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from meshcorr import datasets
from meshcorr.cli import main
from meshcorr.errors import ParameterError
from meshcorr.io import write_map, write_mesh
from meshcorr.viz.report import report_html

SUMMARY = {
    "timings": {"geodesics": 1.5, "embedding": 0.5},
    "configuration": {"perm": [0, 2, 1], "signs": [1, -1, 1], "cost": 0.0125},
    "runner_up": {"perm": [0, 1, 2], "signs": [1, 1, 1], "cost": 0.05},
    "n_configurations": 48,
    "params": {"k": 4},
}


@pytest.fixture(scope="module")
def shape():
    return datasets.tube(n_along=10, n_around=6)


def _data(page: str) -> dict:
    found = re.search(r'<script type="application/json" id="report-data">(.*?)</script>', page, re.S)
    return json.loads(found.group(1))


def test_report_is_self_contained_and_complete(shape):
    V, F = shape.vertices, shape.faces
    mapping = np.arange(len(V))[::-1].copy()
    mapping[0] = -1
    page = report_html((V, F), (V, F), mapping, SUMMARY, errors=np.array([0.0, 0.01, np.nan, 0.3]))
    # Offline: no external scripts, styles or fetches.
    assert not re.search(r'(src|href)=["\']?(https?:)?//', page)
    assert "fetch(" not in page and "XMLHttpRequest" not in page
    assert page.count("<canvas") == 2 and 'id="errors"' in page
    assert "dataset.status" in page  # the viewer itself is inlined
    data = _data(page)
    assert len(data["source"]["faces"]) == F.size and len(data["target"]["vertices"]) == V.size
    colors = np.array(data["source"]["colors"]).reshape(-1, 3)
    target_colors = np.array(data["target"]["colors"]).reshape(-1, 3)
    np.testing.assert_array_equal(colors[1:], target_colors[mapping[1:]])
    np.testing.assert_array_equal(colors[0], [170, 170, 170])
    camera = np.array(data["camera"]).reshape(3, 3)
    np.testing.assert_allclose(camera @ camera.T, np.eye(3), atol=1e-9)
    # Timings, chosen configuration and runner-up, error curve (2 of 4 within 0.05).
    for text in ("geodesics", "2.000", "runner-up", "1 3 2", "+ - +", "0.0125", "48 configurations",
                 'id="error-curve"', "50.0 % within 0.05"):
        assert text in page, text
    assert "not the cheapest" not in page  # the chosen configuration is the cheaper one here
    mirror = dict(SUMMARY, configuration=SUMMARY["runner_up"], runner_up=SUMMARY["configuration"],
                  params={"symmetry": "auto"})
    assert "not the cheapest: the symmetry rule (auto)" in report_html((V, F), (V, F), mapping, mirror)


def test_report_thins_large_meshes_and_checks_the_map(shape):
    V, F = shape.vertices, shape.faces
    page = report_html((V, F), (V, F), np.arange(len(V)), {}, max_faces=50)
    assert len(_data(page)["source"]["faces"]) <= 3 * 50 and "face only" in page
    assert "error-curve" not in page and "runner-up" not in page
    with pytest.raises(ParameterError, match="entries but the source mesh"):
        report_html((V, F), (V, F), np.arange(len(V) - 1), {})


def test_match_writes_report(tmp_path, capsys):
    shape = datasets.tube(n_along=12, n_around=8)
    mesh = tmp_path / "tube.off"
    write_mesh(mesh, shape.vertices, shape.faces)
    gt = tmp_path / "gt.txt"
    write_map(gt, np.arange(len(shape.vertices)))
    report = tmp_path / "report.html"
    assert main(["match", str(mesh), str(mesh), "-o", str(tmp_path / "map.txt"), "-q",
                 "--report", str(report), "--gt", str(gt)]) == 0
    page = report.read_text(encoding="utf-8")
    assert "error-curve" in page and "Stage timings" in page and "chosen" in page
    # --gt without --report, and an unwritable report, fail before matching.
    assert main(["match", str(mesh), str(mesh), "-o", str(tmp_path / "m2.txt"), "--gt", str(gt)]) == 2
    assert "--report" in capsys.readouterr().err
    assert main(["match", str(mesh), str(mesh), "-o", str(tmp_path / "m3.txt"),
                 "--report", str(tmp_path / "no" / "r.html")]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert not (tmp_path / "m2.txt").exists() and not (tmp_path / "m3.txt").exists()
