"""The landmark picker's server (meshcorr.viz.pick) over HTTP, without a browser."""

from __future__ import annotations

import http.client
import json
import threading
import time
import warnings

import numpy as np
import pytest

from meshcorr import datasets
from meshcorr.errors import LandmarkWarning, ParameterError
from meshcorr.stages.landmarks import read_landmarks
from meshcorr.viz.pick import PickSession, Picker, landmark_text, start_server

SOURCE = datasets.tube(n_along=8, n_around=6, bend=0.0)
TARGET = datasets.tube(n_along=8, n_around=6, bend=1.0)
N = SOURCE.n_vertices  # 48 on both


def _session(tmp_path, **options) -> PickSession:
    return PickSession((SOURCE.vertices, SOURCE.faces), (TARGET.vertices, TARGET.faces),
                       output=tmp_path / "landmarks.txt", **options)


@pytest.fixture
def served(tmp_path):
    """A server in a thread; ``request(verb, path, body=None, token=True, host=None) -> (status, json)``."""
    servers = []

    def serve(**options):
        session = _session(tmp_path, **options)
        server = start_server(session)
        threading.Thread(target=server.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True).start()
        servers.append(server)

        def request(verb, path, body=None, token=True, host=None):
            connection = http.client.HTTPConnection("127.0.0.1", server.port, timeout=10)
            headers = {"X-Meshcorr-Token": server.token} if token is True else (
                {"X-Meshcorr-Token": token} if token else {})
            if host:
                connection.putrequest(verb, path, skip_host=True)
                connection.putheader("Host", host)
                for name, value in headers.items():
                    connection.putheader(name, value)
                connection.endheaders()
            else:
                data = None if body is None else (body if isinstance(body, bytes) else json.dumps(body).encode())
                connection.request(verb, path, body=data, headers=headers)
            answer = connection.getresponse()
            raw = answer.read()
            connection.close()
            kind = answer.getheader("Content-Type", "")
            return answer.status, (json.loads(raw) if kind.startswith("application/json") else raw.decode())

        return session, server, request

    yield serve
    for server in servers:
        server.shutdown()
        server.server_close()


def test_landmark_text_is_what_match_reads(tmp_path):
    path = tmp_path / "l.txt"
    path.write_text(landmark_text([[3, 4], [10, 0]], "two pairs\nsecond line"))
    assert path.read_text().splitlines()[:2] == ["# two pairs", "# second line"]
    np.testing.assert_array_equal(read_landmarks(path), [[3, 4], [10, 0]])


def test_requests_without_the_token_or_for_other_paths_are_refused(served):
    _, server, request = served()
    assert request("GET", "/api/status")[0] == 200
    assert request("GET", "/api/status", token=False)[0] == 403
    assert request("GET", "/api/status", token="x" * len(server.token))[0] == 403
    assert request("GET", f"/?token={server.token}", token=False)[0] == 200  # the page's address works
    for path in ("/../pyproject.toml", "/%2e%2e/pyproject.toml", "/api/../../pyproject.toml", "/pick_page.js",
                 "/viewer.js", "/api/meshes/../../../etc/passwd"):
        status, answer = request("GET", path)
        assert status == 404 and "pyproject" not in str(answer).replace(path, "")
        assert request("GET", path, token=False)[0] == 403
    assert request("DELETE", "/api/status")[0] == 501  # http.server: no such verb handled
    assert request("GET", "/api/status", host="evil.example:80")[0] == 403  # another host name (DNS rebinding)
    assert server.server_address[0] == "127.0.0.1"


def test_the_page_is_self_contained(served):
    _, _, request = served()
    status, page = request("GET", "/")
    assert status == 200 and "MeshcorrViewer" in page and "meshcorrPick" in page
    assert "http://" not in page and "https://" not in page and "<script src" not in page


def test_save_writes_the_output_atomically_in_input_numbering(served, tmp_path):
    session, _, request = served()
    status, answer = request("POST", "/api/save", {"pairs": [[0, 5], [7, 9], [20, 30]]})
    assert status == 200 and answer["saved"] == 3
    np.testing.assert_array_equal(read_landmarks(tmp_path / "landmarks.txt"), [[0, 5], [7, 9], [20, 30]])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["landmarks.txt"]  # no temporary file left
    assert request("GET", "/api/landmarks")[1] == {"pairs": [[0, 5], [7, 9], [20, 30]]}
    assert session.saved == 3


@pytest.mark.parametrize("pairs, words", [
    ([[0, N]], "not a vertex of the target"),
    ([[-1, 0]], "not a vertex of the source"),
    ([[0, 1], [0, 2]], "two landmarks"),
    ([[0, 1.5]], "whole numbers"),
    ("0 1", "whole numbers"),
    ([[0, 1, 2]], "whole numbers"),
])
def test_bad_pairs_are_refused_and_nothing_is_written(served, tmp_path, pairs, words):
    _, _, request = served()
    status, answer = request("POST", "/api/save", {"pairs": pairs})
    assert status == 400 and words in answer["error"]
    assert not (tmp_path / "landmarks.txt").exists()


def test_a_body_that_is_not_json_is_refused(served):
    _, _, request = served()
    status, answer = request("POST", "/api/save", b"{not json")
    assert status == 400 and "not JSON" in answer["error"]


def test_match_runs_in_a_worker_and_the_map_honours_the_landmarks(served):
    calls = []

    def matcher(pairs, progress):
        calls.append(pairs.copy())
        progress("fake", 1, 2)
        warnings.warn("Landmark 0 looks odd.", LandmarkWarning)
        time.sleep(0.2)
        mapping = np.arange(N)
        mapping[pairs[:, 0]] = pairs[:, 1]
        return mapping, {"low": True, "margin": 0.1,
                         "suggested_landmarks": [{"source": 3, "chosen": 3, "rival": 40}]}

    session, _, request = served(matcher=matcher, record_warnings=True)
    assert request("GET", "/api/map")[1]["map"] is None
    assert request("POST", "/api/match", {"pairs": [[0, 10]]})[0] == 202
    status, answer = request("POST", "/api/match", {"pairs": [[0, 10]]})
    assert status == 400 and "running already" in answer["error"]
    assert request("GET", "/api/status")[1]["stage"] in ("starting", "fake")
    status = session.wait(10)
    assert status["state"] == "done" and status["fraction"] == 1.0 and status["landmarks"] == 1
    assert status["warnings"] == ["Landmark 0 looks odd."]  # for the page, not through to the terminal
    payload = request("GET", "/api/map")[1]
    assert payload["version"] == 1 and payload["map"][0] == 10 and payload["map"][1] == 1
    assert payload["suggestions"] == [{"source": 3, "chosen": 3, "rival": 40}] and payload["low"]
    assert len(payload["target_colors"]) == 3 * N
    np.testing.assert_array_equal(calls[0], [[0, 10]])


def test_a_failing_match_is_reported_and_the_server_goes_on(served):
    def matcher(pairs, progress):
        raise ParameterError("Landmark 0 is wrong in some way.")

    session, _, request = served(matcher=matcher, mapping=np.arange(N))
    assert request("POST", "/api/match", {"pairs": []})[0] == 202
    status = session.wait(10)
    assert status["state"] == "error" and "wrong in some way" in status["error"]
    assert request("GET", "/api/map")[1]["version"] == 1  # the map given stays


def test_without_a_matcher_match_is_refused(served):
    _, _, request = served()
    status, answer = request("POST", "/api/match", {"pairs": []})
    assert status == 400 and "no matcher" in answer["error"]


def test_close_stops_the_server_unless_the_page_comes_back(served):
    _, server, request = served()
    server.close_grace = 0.3
    assert request("POST", "/api/close")[0] == 200
    time.sleep(0.1)
    assert request("GET", "/")[0] == 200  # a reload within the grace keeps it
    time.sleep(0.5)
    assert not server.closed.is_set()
    assert request("POST", "/api/close")[0] == 200
    assert server.closed.wait(30)


def test_a_port_in_use_is_refused_with_the_fix(tmp_path):
    session = _session(tmp_path)
    first = start_server(session)
    try:
        with pytest.raises(ParameterError, match=f"port {first.port}.*another --port"):
            start_server(session, port=first.port)
    finally:
        first.server_close()
    with pytest.raises(ParameterError, match="from 0"):
        start_server(session, port=70000)


def test_landmarks_are_translated_between_input_and_drawn_numbering(tmp_path):
    ids = np.arange(N) + 100  # the drawn vertices are input vertices 100...
    session = _session(tmp_path, landmarks=[[100, 105]], source_ids=ids, target_ids=ids)
    np.testing.assert_array_equal(session.landmarks, [[100, 105]])
    assert session.set_pairs([[101, 147]]) == 1
    np.testing.assert_array_equal(session.to_drawn(session.landmarks), [[1, 47]])
    with pytest.raises(ParameterError, match="source vertex 5 is not a vertex"):
        session.set_pairs([[5, 100]])


def test_the_picker_serves_from_a_thread_and_shows_a_frame(tmp_path):
    with Picker(_session(tmp_path, landmarks=[[1, 2]])) as picker:
        assert picker.url.startswith("http://127.0.0.1:") and "token=" in picker.url
        assert f'src="{picker.url.replace("&", "&amp;")}"' in picker._repr_html_()
        connection = http.client.HTTPConnection("127.0.0.1", picker.server.port, timeout=10)
        connection.request("GET", "/api/landmarks", headers={"X-Meshcorr-Token": picker.server.token})
        assert json.loads(connection.getresponse().read()) == {"pairs": [[1, 2]]}
        connection.close()
        np.testing.assert_array_equal(picker.landmarks, [[1, 2]])
    assert not picker._thread.is_alive()


# Tiny tubes and k=6 (passed through to match): the maps without landmarks are far off, so the run doubts
# the true pairs it is given (a LandmarkWarning) and follows them.
@pytest.mark.filterwarnings("ignore::meshcorr.errors.LandmarkWarning")
def test_result_pick_starts_from_the_map_and_matches_again(tmp_path):
    import meshcorr

    result = meshcorr.match((SOURCE.vertices, SOURCE.faces), (TARGET.vertices, TARGET.faces))
    with result.pick(tmp_path / "l.txt", k=6) as picker:
        session = picker.session
        np.testing.assert_array_equal(picker.mapping, result.map)
        assert session.status()["can_match"] and session.map_payload()["version"] == 1
        truth = datasets.ground_truth(SOURCE, TARGET)
        pairs = [[0, int(truth[0])], [40, int(truth[40])]]
        session.start_match(pairs)
        assert session.wait(60)["state"] == "done", session.status()
        assert session.map_payload()["version"] == 2
        assert picker.mapping[0] == truth[0] and picker.mapping[40] == truth[40]
        np.testing.assert_array_equal(picker.landmarks, pairs)


def test_a_bad_content_length_is_refused(served):
    _, server, _ = served()
    connection = http.client.HTTPConnection("127.0.0.1", server.port, timeout=10)
    connection.putrequest("POST", "/api/save")
    connection.putheader("X-Meshcorr-Token", server.token)
    connection.putheader("Content-Length", "many")
    connection.endheaders()
    answer = connection.getresponse()
    assert answer.status == 400 and "Content-Length must be a number" in json.loads(answer.read())["error"]
    connection.close()
