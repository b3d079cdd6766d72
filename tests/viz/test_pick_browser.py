"""The landmark picker driven by real mouse clicks in a headless Chromium (Playwright).

Skipped without Playwright (``pip install meshcorr[test]``) or without
Debian's chromium (``.ci/run`` installs it); Playwright drives the system's
browser (``executable_path``), so ``playwright install`` is not needed.
One page session makes three pairs by clicking their vertices on the
canvases, deletes one, moves one, saves, checks the file, runs "Match
again" and checks the new map, then closes the page.
"""

from __future__ import annotations

import http.client
import shutil
import threading

import numpy as np
import pytest

import meshcorr
from meshcorr import datasets
from meshcorr.stages.landmarks import read_landmarks
from meshcorr.viz.pick import PickSession, start_server

sync_api = pytest.importorskip("playwright.sync_api", reason="Playwright is not installed (pip install meshcorr[test])")
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed "
                                "(apt-get install -y chromium; .ci/run installs it)")

SOURCE = datasets.tube(n_along=16, n_around=10, bend=0.0)
TARGET = datasets.tube(n_along=16, n_around=10, bend=1.5)
TRUTH = datasets.ground_truth(SOURCE, TARGET)

#: The vertices of a view that are drawn in front at their own place (a click there picks them).
VISIBLE = """side => {
  const view = meshcorrPick.views[side], out = [];
  for (let v = 0; v < view.n; v++) { const p = view.project(v); if (view.pick(p[0], p[1]) === v) out.push(v); }
  return out;
}"""


@pytest.fixture(scope="module")
def picker(tmp_path_factory):
    folder = tmp_path_factory.mktemp("pick")

    def matcher(pairs, progress):
        result = meshcorr.match((SOURCE.vertices, SOURCE.faces), (TARGET.vertices, TARGET.faces),
                                landmarks=pairs.tolist(), progress=progress)
        return result.map, result.confidence

    session = PickSession((SOURCE.vertices, SOURCE.faces), (TARGET.vertices, TARGET.faces),
                          output=folder / "landmarks.txt", matcher=matcher, record_warnings=True)
    server = _serve(session)
    with sync_api.sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        page, errors = _open(browser, server)
        yield page, session, server, folder, browser
        assert errors == []
        browser.close()
    server.server_close()


def _serve(session):
    server = start_server(session)
    server.close_grace = 0.3
    threading.Thread(target=server.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True).start()
    return server


def _open(browser, server):
    page = browser.new_page(viewport={"width": 1200, "height": 1000})
    errors = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    page.goto(server.url)
    page.wait_for_selector("body[data-status=ok]", timeout=15000)
    return page, errors


def _click(page, side: str, vertex: int) -> None:
    x, y = page.evaluate(f"meshcorrPick.screen({side!r}, {vertex})")
    page.mouse.click(x, y)


def _eventually(condition, timeout: float = 30.0) -> None:
    """Wait for ``condition()`` to hold: the page sends its edits to the server without blocking the clicks."""
    import time

    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, "the server did not receive the page's edit"
        time.sleep(0.02)


def _pairs_to_click(page, count: int) -> list[tuple[int, int]]:
    """``count`` true pairs (source vertex, its target vertex) both visible, spread along the tube."""
    source, target = set(page.evaluate(VISIBLE, "source")), set(page.evaluate(VISIBLE, "target"))
    both = [v for v in sorted(source) if TRUTH[v] in target]
    assert len(both) >= 3 * count, (len(source), len(target), len(both))
    return [(v, int(TRUTH[v])) for v in both[:: len(both) // count][:count]]


def test_click_pairs_delete_move_save_and_match_again(picker):
    page, session, server, folder, _ = picker
    pairs = _pairs_to_click(page, 4)
    (s1, t1), (s2, t2), (s3, t3), (_, t4) = pairs
    _click(page, "source", s1); _click(page, "target", t1)
    _click(page, "target", t2); _click(page, "source", s2)  # either order makes a pair
    _click(page, "source", s3); _click(page, "target", t1)  # a wrong partner, moved below
    assert page.get_attribute("body", "data-pairs") == "3"
    assert page.evaluate("meshcorrPick.state.pairs") == [[s1, t1], [s2, t2], [s3, t1]]
    rows = page.locator("#pairs tbody tr")
    assert rows.count() == 3
    rows.nth(1).locator("button.delete").click()
    assert page.get_attribute("body", "data-pairs") == "2"
    rows.nth(1).locator("button.move").click()
    _click(page, "target", t3)
    assert page.evaluate("meshcorrPick.state.pairs") == [[s1, t1], [s3, t3]]
    _eventually(lambda: np.asarray(session.landmarks).tolist() == [[s1, t1], [s3, t3]])  # sent before any Save
    assert not (folder / "landmarks.txt").exists()

    page.click("#save")
    page.wait_for_selector("body[data-saved='2']", timeout=5000)
    np.testing.assert_array_equal(read_landmarks(folder / "landmarks.txt"), [[s1, t1], [s3, t3]])

    # Match again with a third, deliberately displaced pair: the map must send each source vertex to its partner.
    _click(page, "source", s2); _click(page, "target", t4)
    page.click("#match")
    page.wait_for_selector("body[data-match=done]", timeout=60000)
    assert page.get_attribute("body", "data-version") == "1"
    # The third pair is displaced on purpose: the run warns that it looks wrong (shown on the page), and follows it.
    assert "look wrong" in page.text_content("#message") and "Warning:" in page.text_content("#message")
    mapping = session.mapping
    for s, t in ((s1, t1), (s3, t3), (s2, t4)):
        assert mapping[s] == t
    assert page.evaluate("meshcorrPick.state.map.length") == SOURCE.n_vertices
    # The source now takes the target's colours through the map (not the neutral grey it had).
    colours = np.array(page.evaluate("meshcorrPick.views.source.colors")).reshape(-1, 3)
    np.testing.assert_array_equal(colours[s1], np.array(page.evaluate("meshcorrPick.state.colors")).reshape(-1, 3)[t1])
    assert np.ptp(colours, axis=0).max() > 50
    # Hovering a source vertex shows where it lands.
    x, y = page.evaluate(f"meshcorrPick.screen('source', {s1})")
    page.mouse.move(x, y)
    page.wait_for_function(f"meshcorrPick.state.hover === {s1}", timeout=3000)
    np.testing.assert_array_equal(read_landmarks(folder / "landmarks.txt"), [[s1, t1], [s3, t3]])  # not saved


def test_orbit_and_zoom_move_both_views(picker):
    page = picker[0]
    before = page.evaluate("meshcorrPick.views.target.project(0)")
    box = page.locator("#view-source").bounding_box()
    page.mouse.move(box["x"] + 200, box["y"] + 200)
    page.mouse.down()
    page.mouse.move(box["x"] + 260, box["y"] + 230, steps=4)
    page.mouse.up()
    page.wait_for_timeout(100)
    after = page.evaluate("meshcorrPick.views.target.project(0)")
    assert page.evaluate("meshcorrPick.views.source.matrix") == page.evaluate("meshcorrPick.views.target.matrix")
    assert np.hypot(after[0] - before[0], after[1] - before[1]) > 5
    assert page.get_attribute("body", "data-pairs") == "3"  # a drag is no click
    page.mouse.wheel(0, -300)
    page.wait_for_timeout(100)
    assert page.evaluate("meshcorrPick.scene.zoom") == pytest.approx(np.exp(0.0015 * 300), rel=1e-6)


def test_requests_without_the_token_or_outside_the_routes_are_refused(picker):
    page, _, server, _, _ = picker
    assert page.evaluate("fetch('/api/status').then(r => r.status)") == 403  # the page's own fetch, no token
    for path, status in ((f"/../pyproject.toml?token={server.token}", 404), ("/../pyproject.toml", 403)):
        connection = http.client.HTTPConnection("127.0.0.1", server.port, timeout=10)
        connection.request("GET", path)
        answer = connection.getresponse()
        assert answer.status == status and b"[project]" not in answer.read()
        connection.close()


def test_suggested_landmarks_are_marked_and_named(picker):
    browser = picker[4]
    confidence = {"low": True, "margin": 0.02, "suggested_landmarks": [{"source": 5, "chosen": 7, "rival": 150}]}
    session = PickSession((SOURCE.vertices, SOURCE.faces), (TARGET.vertices, TARGET.faces),
                          mapping=np.arange(SOURCE.n_vertices), confidence=confidence)
    server = _serve(session)
    page, errors = _open(browser, server)
    text = page.text_content("#suggestions")
    assert "unsure (margin 0.02)" in text and "source 5 (a: target 7, b: 150)" in text
    assert page.get_attribute("#suggestions", "class") == "note low"
    assert page.evaluate("meshcorrPick.state.suggestions") == confidence["suggested_landmarks"]
    assert page.get_attribute("#match", "disabled") == ""  # no matcher: no "Match again"
    # Leaving the page ends the server (its "pagehide" beacon). Navigating away rather than closing the
    # tab: a headless browser may tear a closed tab down before the beacon leaves.
    page.goto("about:blank")
    assert server.closed.wait(30) and errors == []
    server.server_close()


def test_close_ends_the_server(picker):
    page, _, server, _, _ = picker
    page.click("#close")
    assert server.closed.wait(30)
