"""``meshcorr pick``: click landmark pairs on the two meshes in the browser, save them, match again."""

from __future__ import annotations

import argparse
import sys
import webbrowser

import numpy as np

from ..errors import InputError, ParameterError
from .set_values import checked_set, literal_value

HELP = "click landmark pairs on SOURCE and TARGET in the browser and save them for match --landmarks"

DESCRIPTION = """\
Serve a page on this machine (127.0.0.1, a free port) that draws SOURCE and
TARGET side by side, and open it in the browser (--no-browser prints its
address instead). Nothing is loaded from the network; the page works offline.

On the page: drag to turn both views together, the mouse wheel zooms both.
Click a point on SOURCE and then its partner on TARGET (or the other way
round): the pair gets a number and the same colour on both. Each pair's row
below the views has 'move' (the next click on either view moves that end)
and 'delete'. 'Save' writes the pairs to -o LANDMARKS.txt (atomically), one
'source_vertex target_vertex' pair a line, 0-based, the file that
'meshcorr match SOURCE TARGET --landmarks LANDMARKS.txt' reads.

With --map, SOURCE takes TARGET's part colours through the map, and the
pointer over SOURCE shows where the map sends that point (a black ring on
TARGET). 'Match again' runs meshcorr match with the pairs (and the --set
options) in this process, with a progress bar, and shows the new map; the
regions whose landmarks would settle the map's global choice (left/right,
front/back, which limb is which) are marked with dashed rings: click those
first (a --map file holds no such report: they appear after 'Match again').
The run's warnings (a pair that looks wrong) are shown on the page. The
warning of 'meshcorr match' about an unsure choice names this command.

--landmarks FILE starts from the pairs in FILE (it may also be the -o file).
Closing the page, 'Close' on it, or Ctrl-C here stops the server; -o keeps
the pairs saved last (nothing is written without 'Save').

Safety: the server listens on 127.0.0.1 only, answers only requests that
carry the random token in the address it prints, serves only the two meshes
and its own page (never other files), and writes only the -o file.
"""


def add_parser(sub) -> None:
    p = sub.add_parser("pick", help=HELP, description=DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("source", metavar="SOURCE", help="the mesh (or point cloud) whose vertices are mapped")
    p.add_argument("target", metavar="TARGET", help="the mesh they are mapped onto")
    p.add_argument("-o", "--output", required=True, metavar="LANDMARKS.txt",
                   help="the landmark file 'Save' writes (atomically)")
    p.add_argument("--map", metavar="MAP", help="a vertex map to show (as written by meshcorr match -o)")
    p.add_argument("--landmarks", metavar="FILE", dest="landmarks_file",
                   help="start from the pairs in FILE ('source target' a line, 0-based)")
    p.add_argument("--port", type=int, default=0, help="the port on 127.0.0.1 (default: a free one)")
    p.add_argument("--no-browser", action="store_true",
                   help="print the page's address on stdout instead of opening a browser")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="an option of meshcorr.match for 'Match again', e.g. --set k=12 (repeatable; VALUE is "
                        "read as a Python literal)")
    p.set_defaults(run=run)


def match_options(items) -> dict:
    """The ``--set KEY=VALUE`` items as options of :func:`meshcorr.match`, each checked by :class:`Settings`."""
    from ..pipeline.settings import Settings

    options = {}
    for item in items:
        key, sep, value = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise ParameterError(f"--set takes KEY=VALUE, e.g. k=12; got {item!r}.")
        if key == "landmarks":
            raise ParameterError("--set landmarks: the landmarks are the pairs clicked on the page; "
                                 "use --landmarks FILE to start from a file.")
        options[key] = literal_value(value)
        checked_set(item, lambda: Settings(**{key: options[key]}))
    return options


def _matcher(source, target, options: dict):
    """'Match again': :func:`meshcorr.match` on the meshes as read, with the page's pairs."""
    from ..pipeline.run import match

    def run_match(pairs: np.ndarray, progress):
        result = match(source, target, landmarks=pairs.tolist() if len(pairs) else None,
                       progress=progress, **options)
        return result.map, result.confidence

    return run_match


def run(args) -> int:
    from ..io import check_outputs, read_mesh
    from ..stages.landmarks import read_landmarks
    from ..viz.pick import PickSession, start_server
    from ._mapfile import read_checked_map

    options = match_options(args.set)
    check_outputs({"-o": args.output}, {"SOURCE": args.source, "TARGET": args.target, "--map": args.map})
    source = read_mesh(args.source, name=args.source)
    target = read_mesh(args.target, name=args.target)
    mapping = None if args.map is None else read_checked_map(args.map, len(source[0]), len(target[0]))
    landmarks = None if args.landmarks_file is None else read_landmarks(args.landmarks_file)
    try:
        session = PickSession(source, target, mapping=mapping, landmarks=landmarks, output=args.output,
                              matcher=_matcher(source, target, options), names=(args.source, args.target),
                              record_warnings=True)
    except ParameterError as exc:  # a landmark off the meshes: the file is at fault
        raise InputError(f"--landmarks {args.landmarks_file}: {exc}") from None
    server = start_server(session, port=args.port)
    try:
        if args.no_browser:
            print(server.url, flush=True)
        elif not args.quiet:
            print(f"meshcorr: the picker is at {server.url}", file=sys.stderr, flush=True)
        if not args.quiet:
            print("meshcorr: close the page or press Ctrl-C to stop", file=sys.stderr, flush=True)
        if not args.no_browser and not webbrowser.open(server.url) and not args.quiet:
            print("meshcorr: no browser could be started here: open the address above in one",
                  file=sys.stderr, flush=True)
        server.serve_forever(poll_interval=0.2)
    except KeyboardInterrupt:
        _farewell(args, session)
        raise
    finally:
        server.server_close()
    _farewell(args, session)
    return 0


def _farewell(args, session) -> None:
    if args.quiet:
        return
    what = (f"{args.output} holds the {session.saved} pairs saved last" if session.saved is not None
            else f"nothing was saved: {args.output} was not written")
    print(f"meshcorr: the picker stopped; {what}", file=sys.stderr, flush=True)
