"""``meshcorr pick``: its bad inputs (each a one-line error and an exit code), and the server it runs
as a user runs it: the address on stdout, Save, then Ctrl-C or a closed page."""

from __future__ import annotations

import http.client
import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from meshcorr import datasets
from meshcorr.cli import main
from meshcorr.io import write_map, write_mesh
from meshcorr.stages.landmarks import read_landmarks

SRC = Path(__file__).resolve().parents[2] / "src"


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("pick")
    source = datasets.tube(n_along=8, n_around=6, bend=0.0)
    target = datasets.tube(n_along=8, n_around=6, bend=1.0)
    write_mesh(folder / "a.off", source.vertices, source.faces)
    write_mesh(folder / "b.off", target.vertices, target.faces)
    write_map(folder / "map.txt", np.arange(source.n_vertices))
    write_map(folder / "short.txt", np.arange(5))
    (folder / "landmarks.txt").write_text("0 1\n2 3\n")
    (folder / "far.txt").write_text("0 1\n2 999\n")
    (folder / "bad.txt").write_text("0 1 2\n")
    return folder


@pytest.mark.parametrize("extra, code, words", [
    (["--map", "{f}/missing.txt"], 3, "missing.txt"),
    (["--map", "{f}/short.txt"], 3, "short.txt"),
    (["--landmarks", "{f}/bad.txt"], 3, "line 1: expected a 0-based vertex pair"),
    (["--landmarks", "{f}/far.txt"], 3, "--landmarks {f}/far.txt: Landmark 1: target vertex 999 is not a vertex"),
    (["--landmarks", "{f}/none.txt"], 3, "No such landmark file"),
    (["--set", "k"], 2, "--set takes KEY=VALUE"),
    (["--set", "k=-3"], 2, "--set 'k=-3'"),
    (["--set", "landmarks=[[0, 1]]"], 2, "use --landmarks FILE"),
    (["--port", "70000"], 2, "--port must be from 0"),
])
def test_bad_inputs_are_one_line_errors(files, capsys, extra, code, words):
    extra = [e.format(f=files) for e in extra]
    assert main(["pick", str(files / "a.off"), str(files / "b.off"), "-o", str(files / "out.txt"),
                 "--no-browser", *extra]) == code
    err = capsys.readouterr().err
    assert words.format(f=files) in err and err.startswith("meshcorr: error:") and "Traceback" not in err
    assert not (files / "out.txt").exists()


def test_a_missing_mesh_and_an_output_onto_an_input_are_refused(files, capsys):
    assert main(["pick", str(files / "nope.off"), str(files / "b.off"), "-o", str(files / "out.txt"),
                 "--no-browser"]) == 3
    assert "nope.off" in capsys.readouterr().err
    assert main(["pick", str(files / "a.off"), str(files / "b.off"), "-o", str(files / "a.off"),
                 "--no-browser"]) == 2
    assert "-o" in capsys.readouterr().err


def test_a_port_in_use_is_refused(files, capsys):
    import socket

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        assert main(["pick", str(files / "a.off"), str(files / "b.off"), "-o", str(files / "out.txt"),
                     "--no-browser", "--port", str(port)]) == 2
    err = capsys.readouterr().err
    assert f"port {port}" in err and "another --port" in err


def test_help_explains_the_page(capsys):
    with pytest.raises(SystemExit) as done:
        main(["pick", "--help"])
    assert done.value.code == 0
    out = capsys.readouterr().out
    for words in ("127.0.0.1", "--no-browser", "Match again", "Ctrl-C", "token", "--landmarks", "exit codes"):
        assert words in out


def _start(files, *extra) -> tuple[subprocess.Popen, str]:
    process = subprocess.Popen([sys.executable, "-m", "meshcorr", "pick", str(files / "a.off"), str(files / "b.off"),
                                "-o", str(files / "saved.txt"), "--no-browser", *extra],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               env={**os.environ, "PYTHONPATH": str(SRC)},
                               # A test run started in the background ignores SIGINT, and the child would inherit it.
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    url = process.stdout.readline().strip()
    assert url.startswith("http://127.0.0.1:"), process.stderr.read() if process.poll() is not None else url
    return process, url


def _post(url: str, path: str, body) -> tuple[int, dict]:
    port, token = url.split(":")[2].split("/")[0], url.split("token=")[1]
    connection = http.client.HTTPConnection("127.0.0.1", int(port), timeout=10)
    connection.request("POST", f"{path}?token={token}", body=json.dumps(body))
    answer = connection.getresponse()
    data = json.loads(answer.read())
    connection.close()
    return answer.status, data


def test_ctrl_c_stops_the_server_and_the_file_keeps_what_was_saved(files):
    process, url = _start(files, "--landmarks", str(files / "landmarks.txt"))
    try:
        assert _post(url, "/api/save", {"pairs": [[0, 1], [2, 3], [4, 5]]}) == (200, {"saved": 3, "output": str(files / "saved.txt")})
        assert _post(url, "/api/landmarks", {"pairs": [[9, 9]]})[0] == 200  # not saved
        process.send_signal(signal.SIGINT)
        assert process.wait(20) == 130
    finally:
        process.kill()
    assert "saved.txt holds the 3 pairs saved last" in process.stderr.read()
    np.testing.assert_array_equal(read_landmarks(files / "saved.txt"), [[0, 1], [2, 3], [4, 5]])


def test_closing_the_page_stops_the_server(files):
    process, url = _start(files)
    try:
        assert _post(url, "/api/close", None)[0] == 200
        assert process.wait(20) == 0
    finally:
        process.kill()
    assert "nothing was saved" in process.stderr.read()


def test_match_names_the_picker_with_its_files_when_the_choice_is_unsure(files, capsys, monkeypatch):
    import meshcorr
    from meshcorr.cli import match as match_command

    result = meshcorr.match(str(files / "a.off"), str(files / "b.off"))
    result.confidence = {"low": True, "margin": 0.01, "rival": "extremities-0", "suggested_landmarks": []}
    monkeypatch.setattr(match_command, "_match", lambda args, landmarks: result)
    out = files / "unsure map.txt"
    assert main(["match", str(files / "a.off"), str(files / "b.off"), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert f"meshcorr pick {files / 'a.off'} {files / 'b.off'} --map '{out}' -o landmarks.txt" in err
    result.confidence = {"low": False, "margin": 1.0, "rival": None, "suggested_landmarks": []}
    assert main(["match", str(files / "a.off"), str(files / "b.off"), "-o", str(out)]) == 0
    assert "meshcorr pick" not in capsys.readouterr().err


def test_a_browser_that_cannot_start_is_said(files, capsys, monkeypatch):
    import webbrowser

    import meshcorr.viz.pick as pick_module

    class Server:  # serves nothing: returns at once, as after a closed page
        url = "http://127.0.0.1:1/?token=t"

        def serve_forever(self, poll_interval):
            pass

        def server_close(self):
            pass

    monkeypatch.setattr(pick_module, "start_server", lambda session, port: Server())
    monkeypatch.setattr(webbrowser, "open", lambda url: False)
    assert main(["pick", str(files / "a.off"), str(files / "b.off"), "-o", str(files / "out.txt")]) == 0
    err = capsys.readouterr().err
    assert "picker is at http://127.0.0.1:1/?token=t" in err and "no browser could be started" in err
    assert "nothing was saved" in err and not (files / "out.txt").exists()
