"""A landmark picker in the browser: click pairs of points on two meshes, save them, match again.

:class:`PickSession` holds one session's state: the two meshes, the
landmark pairs, the current map and the run of "Match again" in a worker
thread. :func:`start_server` serves it on the loopback interface
(``127.0.0.1``, a free port unless one is given) with the standard
library's :class:`http.server.ThreadingHTTPServer`; ``meshcorr pick`` and
:meth:`meshcorr.Correspondence.pick` (through :class:`Picker`, for
notebooks) start it.

The page draws with the HTML report's viewer (``viewer.js``, inlined with
``pick_page.js``; nothing is loaded from elsewhere). The server answers a
fixed list of routes and maps no path onto the file system:

=====================  ====  ==================================================
route                  verb  answer
=====================  ====  ==================================================
``/``                  GET   the page
``/api/meshes``        GET   both meshes (faces thinned past ``max_faces``)
``/api/map``           GET   the current map, the target's colours, suggestions
``/api/landmarks``     GET   the pairs; POST: replace them (in memory)
``/api/status``        GET   the run of "Match again": stage, done, total
``/api/save``          POST  write the pairs to the output file (atomically)
``/api/match``         POST  run ``match`` with the pairs in a worker thread
``/api/close``         POST  the page was closed: stop unless it comes back
=====================  ====  ==================================================

Every request must carry the session's random token (``?token=`` in the
address or the ``X-Meshcorr-Token`` header) and name the server's own
host; anything else is refused (403, 404). Landmark pairs travel and are
written in the numbering of the input files (``source_ids``, ``target_ids``
translate when the meshes drawn are a part of them).
"""

from __future__ import annotations

import hmac
import html
import json
import secrets
import threading
import time
import warnings
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Callable
from urllib.parse import parse_qs, urlsplit

import numpy as np

from ..errors import MeshcorrError, ParameterError
from ..io import atomic_write
from ..maps.colors import mesh_coloring
from ..maps.transfer import check_map
from ..runtime.progress import RunProgress
from .render import camera_frame
from .report import mesh_payload, viewer_script

__all__ = ["MAX_FACES", "PickSession", "PickServer", "Picker", "landmark_text", "start_server"]

#: Faces per mesh the page draws; more are thinned (every k-th face), as in the report.
MAX_FACES = 40000

#: Seconds a closed page has to come back (a reload) before the server stops.
CLOSE_GRACE = 2.0

#: The largest request body accepted (bytes): landmark pairs are a few dozen bytes each.
MAX_BODY = 1 << 20

#: ``matcher(pairs, progress) -> (map, confidence)``: pairs ``(L, 2)`` and the map ``(n_source,)`` in the
#: drawn meshes' numbering; ``confidence`` as ``Correspondence.confidence`` (input numbering) or None.
Matcher = Callable[[np.ndarray, Callable], tuple[np.ndarray, dict | None]]


def landmark_text(pairs, header: str = "") -> str:
    """The text of a landmark file as ``meshcorr match --landmarks`` reads it.

    Parameters
    ----------
    pairs : (L, 2) int
        ``source_vertex target_vertex`` rows, 0-based.
    header : str
        Comment lines to put first (each is prefixed with ``# ``).

    Returns
    -------
    text : str
        One pair a line (:func:`meshcorr.stages.landmarks.read_landmark_lines`).
    """
    lines = [f"# {line}" for line in header.splitlines()]
    lines += [f"{int(s)} {int(t)}" for s, t in np.asarray(pairs, dtype=np.int64).reshape(-1, 2)]
    return "\n".join(lines) + "\n"


class PickSession:
    """One picking session: the meshes, the pairs, the current map and the matching run.

    Parameters
    ----------
    source, target : ((n1, 3) float, (m1, 3) int), ((n2, 3) float, (m2, 3) int)
        The meshes drawn (``m = 0``: a point cloud).
    mapping : (n1,) int, optional
        Target vertex of each source vertex (-1: unmapped), in these meshes' numbering.
    landmarks : (L, 2) int, optional
        The pairs to start from, in the input numbering.
    output : path, optional
        The landmark file "Save" writes (atomically); None: the pairs stay in memory.
    matcher : callable, optional
        Runs "Match again" (:data:`Matcher`); None: the page offers no matching.
    confidence : dict, optional
        ``Correspondence.confidence`` of ``mapping``: its suggested landmarks are marked.
    source_ids, target_ids : (n1,) int, (n2,) int, optional
        Input index of each drawn vertex (default: the same numbers).
    names : (str, str)
        The meshes' names on the page and in the saved file.
    max_faces : int
        Faces per mesh sent to the page.
    record_warnings : bool
        Keep the warnings of "Match again" (a landmark that looks wrong, an unsure choice) for the
        page (``status()["warnings"]``) instead of letting them through. Python's warning filters
        are process-wide: while a match runs, warnings of other threads are caught too (the
        command line sets it; a notebook, where other code runs meanwhile, should not).

    Raises
    ------
    ParameterError
        A map or landmarks that do not fit the meshes.
    """

    def __init__(self, source, target, *, mapping=None, landmarks=None, output=None,
                 matcher: Matcher | None = None, confidence: dict | None = None, source_ids=None,
                 target_ids=None, names: tuple[str, str] = ("source", "target"), max_faces: int = MAX_FACES,
                 record_warnings: bool = False):
        (self._V1, self._F1), (self._V2, self._F2) = source, target
        self.n = (len(self._V1), len(self._V2))
        self.ids = [np.arange(n) if ids is None else np.asarray(ids, dtype=np.int64)
                    for ids, n in zip((source_ids, target_ids), self.n)]
        self.output = None if output is None else Path(output)
        self.names = names
        self._matcher = matcher
        self._max_faces = max_faces
        self._lock = threading.Lock()
        self._meshes_json: bytes | None = None
        self._colors = mesh_coloring("parts", self._V2, self._F2)
        self._map = None if mapping is None else check_map(mapping, *self.n)
        self._confidence = confidence
        self._version = 0 if mapping is None else 1
        self._pairs = np.zeros((0, 2), dtype=np.int64)
        if landmarks is not None and len(landmarks):
            self._pairs = self.to_drawn(landmarks)
        self.saved: int | None = None
        self._record_warnings = record_warnings
        self._run = {"state": "idle", "stage": "", "done": 0, "total": 0, "error": None, "warnings": []}
        self._plan: RunProgress | None = None

    # ------------------------------------------------------------- numbering

    def to_drawn(self, pairs) -> np.ndarray:
        """``(L, 2)`` int: input-numbered pairs in the drawn meshes' numbering (ParameterError if one is not drawn)."""
        pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
        out = np.empty_like(pairs)
        for column, side in ((0, "source"), (1, "target")):
            ids = self.ids[column]
            order = np.argsort(ids, kind="stable")
            at = np.minimum(np.searchsorted(ids, pairs[:, column], sorter=order), len(ids) - 1)
            found = ids[order[at]] == pairs[:, column]
            if not found.all():
                row = int(np.flatnonzero(~found)[0])
                raise ParameterError(f"Landmark {row}: {side} vertex {int(pairs[row, column])} is not a vertex of "
                                     f"the {side} mesh drawn (it has {self.n[column]} vertices, 0-based).")
            out[:, column] = order[at]
        return out

    def to_input(self, pairs) -> np.ndarray:
        """``(L, 2)`` int: drawn-numbered pairs in the input numbering."""
        pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
        return np.stack([self.ids[0][pairs[:, 0]], self.ids[1][pairs[:, 1]]], axis=1)

    def check_pairs(self, value) -> np.ndarray:
        """Pairs sent by the page, in input numbering, as ``(L, 2)`` int in the drawn numbering.

        Raises :class:`ParameterError` for anything but a list of ``[source, target]`` vertex
        numbers in range, or a source vertex given two targets.
        """
        if (not isinstance(value, list) or len(value) > 100000
                or not all(isinstance(p, list) and len(p) == 2 and all(type(v) is int for v in p) for p in value)):
            raise ParameterError("Expected the pairs as a list of [source vertex, target vertex] whole numbers.")
        pairs = self.to_drawn(value)
        sources, counts = np.unique(pairs[:, 0], return_counts=True)
        if (counts > 1).any():
            raise ParameterError(f"Source vertex {int(self.ids[0][sources[counts > 1][0]])} has two landmarks; "
                                 "give each source vertex one target vertex.")
        return pairs

    # ----------------------------------------------------------------- state

    @property
    def landmarks(self) -> np.ndarray:
        """``(L, 2)`` int: the current pairs, input numbering."""
        with self._lock:
            return self.to_input(self._pairs)

    @property
    def mapping(self) -> np.ndarray | None:
        """``(n1,)`` int: the current map in the drawn numbering, or None."""
        with self._lock:
            return None if self._map is None else self._map.copy()

    def set_pairs(self, value) -> int:
        """Replace the pairs with the page's (input numbering); their count."""
        pairs = self.check_pairs(value)
        with self._lock:
            self._pairs = pairs
        return len(pairs)

    def save(self, value) -> int:
        """Keep the page's pairs and write them to the output file (atomically); their count."""
        self.set_pairs(value)
        pairs = self.landmarks
        if self.output is not None:
            header = (f"landmarks of {self.names[0]} -> {self.names[1]}, written by meshcorr pick: one "
                      "'source_vertex target_vertex' pair a line, 0-based\n"
                      f"use: meshcorr match {self.names[0]} {self.names[1]} --landmarks {self.output.name}")
            text = landmark_text(pairs, header)
            atomic_write(self.output, lambda file: file.write(text.encode("ascii")))
        self.saved = len(pairs)
        return len(pairs)

    # --------------------------------------------------------------- payloads

    def meshes_json(self) -> bytes:
        """``/api/meshes``: both meshes as the viewer draws them, and the first camera."""
        if self._meshes_json is None:
            grey = np.full((1, 3), 200, dtype=np.int64)
            src, step1 = mesh_payload(self._V1, self._F1, grey.repeat(self.n[0], 0), self._max_faces)
            tgt, step2 = mesh_payload(self._V2, self._F2, grey.repeat(self.n[1], 0), self._max_faces)
            data = {"source": src, "target": tgt, "names": list(self.names), "thinned": max(step1, step2),
                    "camera": camera_frame(30.0, -60.0, "z").ravel().round(12).tolist(),
                    "ids": [None if np.array_equal(ids, np.arange(n)) else ids.tolist()
                            for ids, n in zip(self.ids, self.n)]}
            self._meshes_json = json.dumps(data, separators=(",", ":")).encode()
        return self._meshes_json

    def map_payload(self) -> dict:
        """``/api/map``: the map (drawn numbering, or None), the target's colours and the suggestions."""
        with self._lock:
            mapping, confidence, version = self._map, self._confidence, self._version
        return {"version": version, "map": None if mapping is None else mapping.tolist(),
                "target_colors": self._colors.ravel().tolist(), **self._suggestions(confidence)}

    def _suggestions(self, confidence: dict | None) -> dict:
        """The confidence report's suggested landmarks in the drawn numbering (rows not drawn are left out)."""
        if not confidence:
            return {"suggestions": [], "low": False, "margin": None}
        rows = []
        for row in confidence.get("suggested_landmarks") or ():
            try:
                (s, c), (_, r) = self.to_drawn([[row["source"], row["chosen"]], [row["source"], row["rival"]]])
            except ParameterError:
                continue
            rows.append({"source": int(s), "chosen": int(c), "rival": int(r)})
        margin = confidence.get("margin")
        return {"suggestions": rows, "low": bool(confidence.get("low")),
                "margin": None if margin is None else float(margin)}

    def status(self) -> dict:
        """``/api/status``: the run of "Match again" (with the share of it done and an estimate of the
        seconds left while it runs), the map's version and the saved count."""
        with self._lock:
            plan = self._plan
            if plan is not None and self._run["state"] == "running":
                plan.tick()
            left = None if plan is None else plan.seconds_left()
            return {**self._run, "version": self._version, "saved": self.saved, "landmarks": len(self._pairs),
                    "fraction": 0.0 if plan is None else round(plan.fraction, 4),
                    "seconds_left": None if left is None else round(left, 1),
                    "can_match": self._matcher is not None,
                    "output": None if self.output is None else str(self.output)}

    # --------------------------------------------------------------- matching

    def start_match(self, value) -> None:
        """Run the matcher with the page's pairs in a worker thread (ParameterError if one runs already)."""
        pairs = self.check_pairs(value)
        if self._matcher is None:
            raise ParameterError("This picker has no matcher: give it the meshes' files (meshcorr pick) or a result.")
        with self._lock:
            if self._run["state"] == "running":
                raise ParameterError("A match is running already; wait for it to end.")
            self._pairs = pairs
            self._run = {"state": "running", "stage": "starting", "done": 0, "total": 0, "error": None,
                         "warnings": []}
            self._plan = RunProgress()
        threading.Thread(target=self._match, args=(self.to_input(pairs),), daemon=True,
                         name="meshcorr-pick-match").start()

    def wait(self, timeout: float | None = None) -> dict:
        """Wait for a running match to end (polling); :meth:`status` then."""
        end = None if timeout is None else time.monotonic() + timeout
        while self.status()["state"] == "running" and (end is None or time.monotonic() < end):
            time.sleep(0.05)
        return self.status()

    def _progress(self, stage, done, total) -> None:
        with self._lock:
            self._run.update(stage=str(stage), done=int(done or 0), total=int(total or 0))
            self._plan.update(str(stage), int(done or 0), int(total or 0))

    def _match(self, pairs: np.ndarray) -> None:
        if not self._record_warnings:
            return self._run_matcher(pairs)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            self._run_matcher(pairs)
        with self._lock:
            self._run["warnings"] = [str(w.message) for w in caught]

    def _run_matcher(self, pairs: np.ndarray) -> None:
        try:
            mapping, confidence = self._matcher(pairs, self._progress)
            mapping = check_map(mapping, *self.n)
        except MeshcorrError as exc:
            error = str(exc)
        except Exception as exc:  # noqa: BLE001 - the page shows it; the server goes on
            error = f"internal error: {type(exc).__name__}: {exc}"
        else:
            with self._lock:
                self._map, self._confidence = mapping, confidence
                self._version += 1
                self._run.update(state="done", stage="done")
                self._plan.finish()
            return
        with self._lock:
            self._run.update(state="error", error=error)


# ------------------------------------------------------------------ the server

_STYLE = """
body { font-family: system-ui, sans-serif; margin: 1em; color: #222; }
h1 { font-size: 1.2em; margin: 0 0 0.4em; }
.bar { display: flex; gap: 8px; align-items: center; flex-wrap: wrap; margin-bottom: 0.6em; }
.views { display: flex; gap: 12px; flex-wrap: wrap; }
.views figure { margin: 0; } figcaption { font-size: 0.9em; text-align: center; }
canvas { border: 1px solid #ccc; cursor: crosshair; touch-action: none; }
table { border-collapse: collapse; font-size: 0.9em; margin-top: 0.5em; }
td, th { border: 1px solid #ddd; padding: 2px 8px; text-align: right; }
th { background: #f0f0f0; } tr.moving { background: #fff3c4; }
.swatch { display: inline-block; width: 0.9em; height: 0.9em; border-radius: 50%; vertical-align: middle; }
#errors { display: none; color: #a00; background: #fee; padding: 0.5em; }
#message { font-size: 0.9em; } #message.bad { color: #a00; }
.note { font-size: 0.85em; color: #555; max-width: 70em; }
#suggestions.low { background: #fff3c4; padding: 0.3em 0.6em; }
"""

#: Headers of every answer: nothing cached, nothing loaded from elsewhere, nothing sniffed.
_HEADERS = {"Cache-Control": "no-store", "X-Content-Type-Options": "nosniff", "Referrer-Policy": "no-referrer",
            "Content-Security-Policy": "default-src 'none'; script-src 'unsafe-inline'; "
                                       "style-src 'unsafe-inline'; connect-src 'self'; img-src data:"}


def page_html(session: PickSession, token: str) -> str:
    """The picker's page: the layout, the token and both scripts inline (no other request but the API's)."""
    source, target = (html.escape(name) for name in session.names)
    config = json.dumps({"token": token, "output": None if session.output is None else str(session.output),
                         "can_match": session.status()["can_match"]}).replace("</", "<\\/")
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>meshcorr pick: {source} -> {target}</title><style>{_STYLE}</style></head>\n<body>\n"
            f"<h1>Landmarks: {source} &rarr; {target}</h1>\n<pre id=\"errors\"></pre>\n"
            '<div class="bar"><button id="save">Save</button><button id="match">Match again</button>'
            '<button id="reset">Reset view</button><button id="close">Close</button>'
            '<progress id="progress" max="1" value="0" hidden></progress><span id="message"></span></div>\n'
            '<div class="views">'
            '<figure><canvas id="view-source" width="540" height="460"></canvas>'
            f'<figcaption>source: {source} (<span id="n-source"></span> vertices)</figcaption></figure>'
            '<figure><canvas id="view-target" width="540" height="460"></canvas>'
            f'<figcaption>target: {target} (<span id="n-target"></span> vertices)</figcaption></figure></div>\n'
            '<p id="suggestions" class="note"></p>\n'
            '<table id="pairs"><thead><tr><th>pair</th><th>source vertex</th><th>target vertex</th><th></th>'
            "</tr></thead><tbody></tbody></table>\n"
            '<p class="note">Click a point on the source, then its partner on the target (or the other way '
            "round): the pair gets a number and a colour on both. Drag to turn both views, the wheel zooms "
            "both. <b>move</b> on a row: the next click on either view moves that end of the pair; Esc "
            "cancels. With a map the source takes the target's colours through it, and the pointer over "
            "the source shows where the map sends that point (a black ring on the target). Dashed "
            "rings: where landmarks would settle the map's global choice (on the target: a = where the "
            "map sends the point, b = where the best other map does). Save writes the file that "
            "meshcorr match --landmarks reads; Close (or closing this page) ends the picker.</p>\n"
            f'<script type="application/json" id="pick-config">{config}</script>\n'
            f"<script>\n{viewer_script('pick_page.js')}\n</script>\n</body></html>\n")


class _Handler(BaseHTTPRequestHandler):
    """The fixed routes of :mod:`meshcorr.viz.pick`; everything else is refused."""

    server: "PickServer"
    server_version = "meshcorr-pick"
    sys_version = ""

    def log_message(self, format, *args) -> None:  # noqa: A002 - the library never prints
        return

    def do_GET(self) -> None:  # noqa: N802 - http.server's name
        self._answer("GET")

    def do_POST(self) -> None:  # noqa: N802
        self._answer("POST")

    def _answer(self, verb: str) -> None:
        url = urlsplit(self.path)
        server = self.server
        token = parse_qs(url.query).get("token", [""])[0] or self.headers.get("X-Meshcorr-Token", "")
        if self.headers.get("Host") not in server.hosts or not hmac.compare_digest(token, server.token):
            return self._send(403, {"error": "Forbidden: this picker answers only its own address, with its token."})
        route = _ROUTES.get((verb, url.path))
        if route is None:
            return self._send(404, {"error": f"No such route: {verb} {url.path[:80]}"})
        server.touch()
        try:
            body = self._body() if verb == "POST" else None
            return route(self, body)
        except MeshcorrError as exc:
            return self._send(400, {"error": str(exc)})

    def _body(self):
        try:
            length = int(self.headers.get("Content-Length") or 0)
        except ValueError:
            length = -1
        if not 0 <= length <= MAX_BODY:
            raise ParameterError(f"The request's Content-Length must be a number of bytes up to {MAX_BODY}.")
        raw = self.rfile.read(length) if length else b"null"
        try:
            return json.loads(raw)
        except (ValueError, UnicodeDecodeError):
            raise ParameterError("The request's body is not JSON.") from None

    def _send(self, code: int, payload, kind: str = "application/json") -> None:
        data = payload if isinstance(payload, bytes) else (
            payload.encode() if isinstance(payload, str) else json.dumps(payload).encode())
        self.send_response(code)
        self.send_header("Content-Type", kind + "; charset=utf-8")
        self.send_header("Content-Length", str(len(data)))
        for name, value in _HEADERS.items():
            self.send_header(name, value)
        self.end_headers()
        self.wfile.write(data)

    # The routes: (handler, body) -> None.
    def page(self, _):
        self._send(200, page_html(self.server.session, self.server.token), "text/html")

    def meshes(self, _):
        self._send(200, self.server.session.meshes_json())

    def map(self, _):
        self._send(200, self.server.session.map_payload())

    def get_pairs(self, _):
        self._send(200, {"pairs": self.server.session.landmarks.tolist()})

    def set_pairs(self, body):
        self._send(200, {"pairs": self.server.session.set_pairs((body or {}).get("pairs"))})

    def status(self, _):
        self._send(200, self.server.session.status())

    def save(self, body):
        session = self.server.session
        self._send(200, {"saved": session.save((body or {}).get("pairs")),
                         "output": None if session.output is None else str(session.output)})

    def match(self, body):
        self.server.session.start_match((body or {}).get("pairs"))
        self._send(202, {"started": True})

    def close(self, _):
        self._send(200, {"closing": True})
        self.server.request_close(self.server.close_grace)


_ROUTES = {("GET", "/"): _Handler.page, ("GET", "/api/meshes"): _Handler.meshes, ("GET", "/api/map"): _Handler.map,
           ("GET", "/api/landmarks"): _Handler.get_pairs, ("POST", "/api/landmarks"): _Handler.set_pairs,
           ("GET", "/api/status"): _Handler.status, ("POST", "/api/save"): _Handler.save,
           ("POST", "/api/match"): _Handler.match, ("POST", "/api/close"): _Handler.close}


class PickServer(ThreadingHTTPServer):
    """The picker's HTTP server on 127.0.0.1 (:func:`start_server` makes one).

    Attributes
    ----------
    session : PickSession
    token : str
        The random token every request must carry.
    url : str
        The page's address, token included.
    closed : threading.Event
        Set when the page asked to close and did not come back within ``close_grace`` seconds
        (:data:`CLOSE_GRACE`; the server stops serving then).
    """

    daemon_threads = True

    def __init__(self, session: PickSession, port: int = 0, token: str | None = None):
        super().__init__(("127.0.0.1", port), _Handler)
        self.session = session
        self.token = token or secrets.token_urlsafe(24)
        self.port = self.server_address[1]
        self.hosts = {f"127.0.0.1:{self.port}", f"localhost:{self.port}"}
        self.url = f"http://127.0.0.1:{self.port}/?token={self.token}"
        self.closed = threading.Event()
        self.close_grace = CLOSE_GRACE
        self._last = time.monotonic()

    def handle_error(self, request, client_address) -> None:
        """A request that broke off (the page closed while an answer was sent): nothing to print."""
        return

    def touch(self) -> None:
        """A request came: a close asked for before it is called off."""
        self._last = time.monotonic()

    def request_close(self, grace: float = CLOSE_GRACE) -> None:
        """Stop serving in ``grace`` seconds unless another request comes in meanwhile (a reload)."""
        asked = self._last = time.monotonic()

        def stop():
            if self._last <= asked:
                self.closed.set()
                self.shutdown()

        timer = threading.Timer(grace, stop)
        timer.daemon = True
        timer.start()


def start_server(session: PickSession, *, port: int = 0, token: str | None = None) -> PickServer:
    """Listen for the picker's page on 127.0.0.1 (not yet serving: call ``serve_forever``).

    Parameters
    ----------
    session : PickSession
    port : int
        0: a free port.
    token : str, optional
        Default: a new ``secrets.token_urlsafe(24)``.

    Returns
    -------
    server : PickServer

    Raises
    ------
    ParameterError
        The port is in use or may not be opened.
    """
    if not 0 <= port <= 65535:
        raise ParameterError(f"--port must be from 0 (a free port) to 65535; got {port}.")
    try:
        return PickServer(session, port, token)
    except OSError as exc:
        raise ParameterError(f"Cannot listen on 127.0.0.1 port {port}: {exc.strerror or exc}. Give another "
                             "--port, or leave it out to use a free one.") from None


class Picker:
    """A picker served from a background thread, for notebooks (:meth:`meshcorr.Correspondence.pick`).

    Displays the page in an ``<iframe>`` in Jupyter; :attr:`landmarks` holds the pairs as the page
    last sent them, :attr:`mapping` the map of the last "Match again". The frame loads from
    127.0.0.1: the browser must run on the kernel's machine, or reach it through a forwarded port.

    Parameters
    ----------
    session : PickSession
    port : int
        0: a free port.
    height : int
        Height of the frame in a notebook, pixels.
    """

    def __init__(self, session: PickSession, *, port: int = 0, height: int = 820):
        self.session = session
        self.server = start_server(session, port=port)
        self.url = self.server.url
        self.height = height
        self._thread = threading.Thread(target=self.server.serve_forever, kwargs={"poll_interval": 0.2},
                                        daemon=True, name="meshcorr-pick-server")
        self._thread.start()

    @property
    def landmarks(self) -> np.ndarray:
        """``(L, 2)`` int: the pairs, input numbering."""
        return self.session.landmarks

    @property
    def mapping(self) -> np.ndarray | None:
        """``(n1,)`` int: the current map (the drawn meshes' numbering), or None."""
        return self.session.mapping

    def close(self) -> None:
        """Stop the server (the pairs stay in :attr:`landmarks`)."""
        if self._thread.is_alive():
            self.server.shutdown()
        self.server.server_close()

    def __enter__(self) -> "Picker":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"Picker({self.url!r}, {len(self.landmarks)} pairs)"

    def _repr_html_(self) -> str:
        return (f'<iframe src="{html.escape(self.url)}" width="100%" height="{int(self.height)}" '
                'style="border: 1px solid #ccc"></iframe>')
