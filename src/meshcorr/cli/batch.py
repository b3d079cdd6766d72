"""``meshcorr batch``: map many pairs, each shape prepared once, on a local or remote Dask cluster."""

from __future__ import annotations

import argparse
import os
import sys
import time

from ..core.geodesics import GEODESIC_METHODS
from ..pipeline.settings import Settings
from ..spectral.modes import MODES
from .exits import EXIT_FAILED_RUNS
from .set_values import checked_set, literal_value

#: The defaults of the method options: those of :func:`meshcorr.match`.
DEFAULTS = Settings()

HELP = "map many pairs (a list, all pairs of a collection, or onto a template) on Dask (resumable)"

DESCRIPTION = """\
Map every pair with the spectral method, each shape prepared once (its
embedding, orientation, curvature and refinement basis), as a Dask graph: one
task per shape, one per pair. By default a local cluster of one worker process
per core is started and stopped; --scheduler tcp://HOST:PORT runs the same
graph on an existing Dask cluster (its workers must see the mesh files and
--out at the same absolute paths). Needs meshcorr[dask].

Pairs: --pairs FILE (one "SOURCE TARGET" a line), --all-pairs SHAPES... (every
ordered pair, n(n-1) maps) or --template T SHAPES... (T onto each shape: every
map is indexed by T's vertices).

--out DIR receives maps/SOURCE__TARGET.txt (line i: the TARGET vertex of SOURCE
vertex i) as each pair finishes, summary.json and summary.csv (per pair:
status, seconds, the error with --gt) and run.json (the settings). A rerun
with the same --out skips the pairs done (not those whose mesh files' content
changed, whose --gt differs or whose map file is damaged or cut short); a
failed pair (e.g. a bad mesh) is recorded and the others go on. One batch at a
time writes into a folder: a second one into the same --out is refused (exit
2). A --cache folder that cannot be written is warned about once and the batch
runs without it. Ctrl-C or SIGTERM stops the batch (exit 130 or 143) with the
maps finished so far recorded. Exit code: 0 if every pair was mapped, 4 if
any failed. With --all-pairs, --consistency also reports the cycle-consistency
error and writes maps made consistent through the collection (see
meshcorr.collection.consistency).

--all-pairs with --hub SHAPE (or --hub auto: the shape whose Laplace-Beltrami
spectrum is most like the others') matches only the n-1 pairs from each shape
onto that hub, inverts them for the hub's maps onto the shapes, and composes
every other map through it (SOURCE -> hub -> TARGET): n times fewer matches,
and maps that agree with each other ("via" and "made" columns of the
summary). A wrong map onto the hub is repeated in every map made with it:
use it for one shape in many poses, not for shapes of different builds or
species (measured in benchmarks/RESULTS-collections.md).
"""


def add_parser(sub) -> None:
    p = sub.add_parser("batch", help=HELP, description=DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    which = p.add_mutually_exclusive_group(required=True)
    which.add_argument("--pairs", metavar="PAIRS.txt", help='file of "SOURCE TARGET" lines')
    which.add_argument("--all-pairs", nargs="+", metavar="SHAPE", help="every ordered pair of these meshes")
    which.add_argument("--template", metavar="T", help="map T onto each of the SHAPES")
    p.add_argument("shapes", nargs="*", metavar="SHAPES", help="the meshes of --template")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (created if missing)")
    p.add_argument("--gt", metavar="identity|DIR",
                   help="score each map: 'identity' (same vertex order) or a folder of SHAPE.vts files")
    p.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                   help="an existing Dask scheduler (default: a local cluster started here)")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="worker processes of the local cluster, 1 to 4 per core (default: one per core; "
                        "not used with --scheduler)")
    p.add_argument("--cache", metavar="DIR", nargs="?", const=True, default=None,
                   help="keep prepared shapes in this on-disk cache (no DIR: the default cache, "
                        "see 'meshcorr cache info')")
    p.add_argument("--hub", metavar="SHAPE|auto",
                   help="with --all-pairs: match each shape onto SHAPE only (auto: the shape most like the "
                        "others by its spectrum), and invert and compose those maps for the others")
    p.add_argument("--consistency", action="store_true",
                   help="with --all-pairs: cycle-consistency error and consistent maps (consistent/)")
    g = p.add_argument_group("method options (as in 'meshcorr match')")
    g.add_argument("-k", type=int, default=DEFAULTS.k, help=f"eigenpairs (default: {DEFAULTS.k})")
    g.add_argument("--geodesic", choices=GEODESIC_METHODS, default=DEFAULTS.geodesic,
                   help=f"geodesic solver (default: {DEFAULTS.geodesic})")
    g.add_argument("--seed", type=int, default=DEFAULTS.random_state,
                   help=f"random seed (default: {DEFAULTS.random_state})")
    g.add_argument("--refine", action=argparse.BooleanOptionalAction, default=DEFAULTS.refine,
                   help=f"ZoomOut refinement (default: {_on(DEFAULTS.refine)})")
    g.add_argument("--shells", action=argparse.BooleanOptionalAction, default=DEFAULTS.shells,
                   help=f"smooth-shell alignment after the refinement, meshes only (default: {_on(DEFAULTS.shells)})")
    g.add_argument("--oriented-starts", action="store_true", default=DEFAULTS.oriented_starts,
                   help="also start maps from the tips by an orientation-preserving fit (people standing; "
                        f"worse across species; default: {_on(DEFAULTS.oriented_starts)})")
    g.add_argument("--mode", choices=MODES, default=DEFAULTS.mode,
                   help=f"dense, scalable or auto (default: {DEFAULTS.mode})")
    g.add_argument("--samples", type=int, default=DEFAULTS.n_samples, metavar="N",
                   help=f"Nystrom samples of the scalable mode (default: {DEFAULTS.n_samples})")
    g.add_argument("--partial", choices=("source", "target"), default=DEFAULTS.partial,
                   help="in every pair, the SOURCE (or the TARGET) is a part of the other shape "
                        "(as 'meshcorr match --partial'; default: both whole)")
    g.add_argument("--fill-holes", action=argparse.BooleanOptionalAction, default=DEFAULTS.fill_holes,
                   help="close each shape's holes before matching, as 'meshcorr match --fill-holes' "
                        f"(default: {_on(DEFAULTS.fill_holes)})")
    g.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="any other option of meshcorr.match, e.g. --set symmetry=cost (repeatable; VALUE is a "
                        "Python literal such as 8, 0.5, True or None, other text a string). A value meshcorr.match "
                        "refuses stops the batch before any work (exit 2)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
    p.set_defaults(run=run)


def _on(switch: bool) -> str:
    return "on" if switch else "off"


def _pairs(args) -> list[tuple[str, str]]:
    from ..collection.cluster import MAX_WORKERS, WORKERS_PER_CORE, max_workers
    from ..collection.pairs import all_pairs, read_pair_list, template_pairs
    from ..errors import ParameterError

    if args.shapes and not args.template:
        raise ParameterError("Mesh files after the options are the SHAPES of --template T; with --all-pairs "
                             "list them after --all-pairs, with --pairs put them in the file.")
    if args.consistency and not args.all_pairs:
        raise ParameterError("--consistency needs --all-pairs (it compares the maps of every ordered pair).")
    if args.consistency and len(set(args.all_pairs)) < 3:
        raise ParameterError("--consistency needs at least three shapes (it follows maps round triples "
                             f"A -> B -> C -> A); got {len(set(args.all_pairs))}.")
    if args.workers is not None and args.scheduler:
        raise ParameterError("--workers sets the local cluster's size; with --scheduler the cluster's own "
                             "workers run the batch: leave out one of them.")
    most = max_workers()
    if args.workers is not None and args.workers > most:  # it started processes until the machine gave out
        raise ParameterError(f"--workers {args.workers} would start {args.workers} processes on this machine's "
                             f"{os.cpu_count() or 1} core(s): give at most {most} ({WORKERS_PER_CORE} per core, "
                             f"at most {MAX_WORKERS}), or run a larger cluster and pass --scheduler.")
    if isinstance(args.cache, str) and os.path.isfile(args.cache):
        raise ParameterError(f"--cache took {args.cache} as its folder: write --cache=DIR, or put --cache (the "
                             "default folder) after the mesh files.")
    if args.hub and not args.all_pairs:
        raise ParameterError("--hub needs --all-pairs (it composes the maps between every two shapes through "
                             "the hub); with --template T, T is the hub already.")
    if args.pairs:
        return read_pair_list(args.pairs)
    if args.all_pairs:
        return all_pairs(args.all_pairs)
    return template_pairs(args.template, args.shapes)


#: Options of meshcorr.match that have a flag of their own here: --set must not give them
#: (the flag's default would silently win).
FLAGGED = {"k": "-k", "geodesic": "--geodesic", "random_state": "--seed", "refine": "--refine / --no-refine",
           "shells": "--shells / --no-shells", "mode": "--mode", "n_samples": "--samples",
           "oriented_starts": "--oriented-starts", "partial": "--partial",
           "fill_holes": "--fill-holes / --no-fill-holes"}


def _options(items: list[str], flags: dict | None = None) -> dict:
    """The options of meshcorr.match: ``flags`` (given by this command's flags), then each --set KEY=VALUE.

    Each is checked as :func:`meshcorr.collection.batch.batch` checks its options (every value as
    meshcorr.match would take it, :func:`meshcorr.pipeline.methods.check_options`), before any work: a
    value that every pair would fail on names its --set item.
    """
    from ..collection.options import split_options
    from ..errors import ParameterError

    options = dict(flags or {})
    split_options(options)  # the flags alone
    for item in items:
        key, eq, value = item.partition("=")
        if not eq or not key:
            raise ParameterError(f"--set takes KEY=VALUE, e.g. symmetry=cost; got {item!r}.")
        if key.strip() in FLAGGED:
            raise ParameterError(f"--set {item}: {key.strip()} has its own option here, {FLAGGED[key.strip()]}.")
        given = dict(options, **{key.strip(): literal_value(value)})
        checked_set(item, lambda: split_options(given))
        options = given
    return options


class BatchBar:
    """``progress(done, total, failed, seconds_left)`` on stderr: a bar on a terminal, lines otherwise."""

    def __init__(self, stream=None) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self.start = time.perf_counter()

    def __call__(self, done: int, total: int, failed: int, seconds_left) -> None:
        width = 24
        filled = int(width * done / max(total, 1))
        left = "" if seconds_left is None else f", ~{_duration(seconds_left)} left"
        text = (f"[batch] [{'#' * filled}{'-' * (width - filled)}] {done}/{total} pairs, {failed} failed, "
                f"{_duration(time.perf_counter() - self.start)}{left}")
        if self.tty:
            self.stream.write("\r\033[K" + text + ("\n" if done == total else ""))
        else:
            self.stream.write(text + "\n")
        self.stream.flush()


def _duration(seconds: float) -> str:
    seconds = int(round(seconds))
    return f"{seconds // 60}m{seconds % 60:02d}s" if seconds >= 60 else f"{seconds}s"


def run(args) -> int:
    from ..collection.batch import batch

    pairs = _pairs(args)
    flags = dict(k=args.k, geodesic=args.geodesic, random_state=args.seed, refine=args.refine, shells=args.shells,
                 mode=args.mode, n_samples=args.samples)
    if args.oriented_starts:
        flags["oriented_starts"] = True
    if args.partial is not None:
        flags["partial"] = args.partial
    if not args.fill_holes:
        flags["fill_holes"] = False
    options = _options(args.set, flags)
    client = None
    if args.scheduler:
        from ..collection.cluster import connect

        client = connect(args.scheduler)
    try:
        records = batch(pairs, args.out, client=client, ground_truth=args.gt, cache=args.cache,
                        n_workers=args.workers, progress=None if args.quiet else BatchBar(sys.stderr),
                        hub=args.hub, **options)
    finally:
        if client is not None:
            client.close()
    failed = [r for r in records if r["status"] != "ok"]
    if args.consistency:
        from ..collection.consistency import consistency_report

        report = consistency_report(args.out, args.all_pairs, records, geodesic=args.geodesic,
                                    random_state=args.seed)
        direct, through = (f"{v:.4f}" if v is not None else "n/a (no mapped vertex sampled)"
                           for v in (report["cycle_error"], report["consistent_cycle_error"]))
        made = "the batch's maps, made through its hub" if args.hub else "the batch's maps"
        print(f"meshcorr: cycle-consistency error {direct} ({made}), {through} (all composed through "
              f"{report['hub']}, the shape that agrees best with the others); see {report['path']}", file=sys.stderr)
    if not args.quiet:
        hubs = {r["via"] for r in records if r.get("via")}
        made = sum(bool(r.get("via")) and r["status"] == "ok" for r in records)
        print(f"meshcorr: {len(records) - len(failed)} of {len(records)} pairs mapped into {args.out}"
              + (f" ({made} made through {', '.join(sorted(hubs))})" if hubs else "")
              + (f"; {len(failed)} failed, see the 'error' column of summary.csv" if failed else ""),
              file=sys.stderr)
    if failed:
        return EXIT_FAILED_RUNS
    return 0
