"""``meshcorr bench``: run and score methods over a dataset of shape pairs."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ..core.geodesics import GEODESIC_METHODS
from ..pipeline.settings import Settings
from .exits import EXIT_FAILED_RUNS
from .match import seed
from .set_values import checked_set, literal_value

#: The defaults of the options bench shares with :func:`meshcorr.match` (the seed).
DEFAULTS = Settings()

HELP = "benchmark methods on a dataset of pairs with ground truth (resumable)"

DESCRIPTION = """\
Map every pair of DATASET_DIR/test_pairs.txt (or a class-stratified sample of
--pairs of them) with each method, score it against the ground truth
(corres/NAME.vts, 1-based; corres/NAME.sym.vts for flips) with the geodesic
error divided by sqrt(target area), and write into --out:
  results.csv   one row per pair and method (rewritten after each one)
  summary.md    per-method table: mean error, % under 0.05/0.1/0.25, flip
                rate, seconds per pair; and the mean error per class
  summary.csv   the same table
  curves.png    cumulative error curves (needs meshcorr[plot])
A restarted run with the same --out skips the pairs already done; a method
that fails on a pair is recorded as 'failed' and the run goes on; the exit
code is then 4. --out/run.json keeps the settings and the dataset's identity
(its folder, pair list and a hash of each mesh and truth file): a rerun there
with other settings, on another dataset or on one whose files changed is
refused before any work (exit 2), as is a --set value that its method refuses.
"""


def add_parser(sub) -> None:
    p = sub.add_parser("bench", help=HELP, description=DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("dataset", metavar="DATASET_DIR",
                   help="folder with NAME.off, corres/NAME.vts and test_pairs.txt (TOSCA layout)")
    p.add_argument("--methods", default="spectral",
                   help="comma-separated methods: spectral, shapiro-brady, shapiro-brady-scaled, "
                        "tps-rpm, icp, shape-context (default: spectral)")
    p.add_argument("--pairs", type=int, default=None, metavar="N",
                   help="a deterministic, class-stratified sample of N pairs (default: all)")
    p.add_argument("--out", default="bench-out", metavar="DIR", help="output folder (default: bench-out)")
    g = p.add_argument_group("method options")
    g.add_argument("-k", type=k_value, default=None,
                   help=f"eigenpairs, {K_RANGE[0]}..{K_RANGE[1]}, for spectral and shapiro-brady[-scaled] "
                        "(default: each method's)")
    g.add_argument("--geodesic", choices=GEODESIC_METHODS, default=None,
                   help="geodesic solver of the spectral methods (default: each method's)")
    g.add_argument("--set", action="append", default=[], metavar="METHOD:KEY=VALUE",
                   help="any option of one method, e.g. --set spectral:reorder=greedy or --set icp:trim=0.8 "
                        "(repeatable; VALUE is a Python literal such as 8, 0.5, True or None, other text a "
                        "string; the seed is --seed). A value the method refuses stops the run before any "
                        "work (exit 2)")
    p.add_argument("--eval-geodesic", choices=GEODESIC_METHODS, default="heat",
                   help="geodesic solver of the evaluation (default: heat)")
    p.add_argument("--seed", type=seed, default=DEFAULTS.random_state,
                   help=f"seed of the sample and of every method (default: {DEFAULTS.random_state})")
    p.add_argument("--retry-failed", action="store_true", help="run failed (pair, method) rows again")
    p.add_argument("--no-plot", action="store_true", help="do not draw curves.png")
    p.set_defaults(run=run)


#: The eigenpairs the spectral methods take (meshcorr.match and shapiro-brady check the same range).
K_RANGE = (2, 10)


def k_value(text: str) -> int:
    """``-k``: an integer in ``K_RANGE`` (out of it, every pair failed and the folder kept the setting)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if not K_RANGE[0] <= value <= K_RANGE[1]:
        raise argparse.ArgumentTypeError(f"expected an integer from {K_RANGE[0]} to {K_RANGE[1]}, got {value}")
    return value


#: Keywords bench sets itself: --set must not give them (``method`` ran another method under this one's
#: name; ``random_state`` and ``progress`` failed every pair).
_RESERVED = {"method": "--methods", "random_state": "--seed", "progress": "-q", "source": "DATASET_DIR",
             "target": "DATASET_DIR"}


def _options_of(method: str) -> tuple[str, ...]:
    """The keywords ``--set METHOD:KEY=VALUE`` may give ``method`` (an unknown one failed every pair)."""
    from ..pipeline.methods import applicable

    return tuple(name for name in applicable(method) if name not in _RESERVED and name != "n_landmarks")


def options_by_method(methods: list[str], k, geodesic, settings: list[str]) -> dict[str, dict]:
    """``{method: {option: value}}`` from -k, --geodesic and --set METHOD:KEY=VALUE."""
    from ..evaluation.benchmark import SPECTRAL_FAMILY
    from ..errors import ParameterError
    from ..pipeline.methods import check_options

    try:  # the baselines say which options each method takes
        from ..baselines import method_options as takes
    except ImportError:
        def takes(method):
            return ("k", "geodesic") if method in SPECTRAL_FAMILY else ()
    options: dict[str, dict] = {m: {} for m in methods}
    for method in methods:
        for key, value in (("k", k), ("geodesic", geodesic)):
            if value is not None and key in takes(method):
                options[method][key] = value
    for item in settings:
        method, sep, rest = item.partition(":")
        key, eq, value = rest.partition("=")
        if not sep or not eq or not key:
            raise ParameterError(f"--set takes METHOD:KEY=VALUE, e.g. spectral:reorder=greedy; got {item!r}.")
        if method not in options:
            raise ParameterError(f"--set {item!r} names method {method!r}, which is not in --methods.")
        if key in _RESERVED:
            raise ParameterError(f"--set {item!r}: bench sets {key!r} itself; use {_RESERVED[key]} instead.")
        allowed = _options_of(method)
        if key not in allowed:
            raise ParameterError(f"--set {item!r}: the method {method!r} has no option {key!r}. Its options are: "
                                 f"{', '.join(allowed)}.")
        given = dict(options[method], **{key: literal_value(value)})
        checked_set(item, lambda: check_options(method, **given))  # a value every pair would fail on
        options[method] = given
    return {m: o for m, o in options.items() if o}


class PairProgress:
    """Progress over (pair, method) tasks on stderr: a bar on a terminal, lines otherwise."""

    def __init__(self, stream=None) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self.start = time.perf_counter()

    def __call__(self, done: int, total: int, message: str) -> None:
        width = 24
        filled = int(width * done / max(total, 1))
        bar = "#" * filled + "-" * (width - filled)
        elapsed = time.perf_counter() - self.start
        text = f"[bench] [{bar}] {done}/{total} {elapsed:.0f} s  {message}"
        finished = not message.endswith("running")
        if self.tty:
            self.stream.write("\r\033[K" + text + ("\n" if finished else ""))
        elif finished:
            self.stream.write(text + "\n")
        self.stream.flush()


def run(args) -> int:
    import os

    from ..evaluation.benchmark import check_methods, run_benchmark, summarize, write_summary
    from ..errors import ParameterError

    methods = check_methods([m.strip() for m in args.methods.split(",") if m.strip()])
    options = options_by_method(methods, args.k, args.geodesic, args.set)
    if os.path.isdir(args.dataset) and os.path.realpath(args.out) == os.path.realpath(args.dataset):
        raise ParameterError(f"--out {args.out} is the dataset folder DATASET_DIR: the results would be mixed "
                             "with its meshes. Give another --out folder.")
    if not args.no_plot:
        from ..viz.plots import require_matplotlib

        require_matplotlib()
    rows = run_benchmark(args.dataset, methods, args.out, n_pairs=args.pairs, method_options=options,
                         geodesic=args.eval_geodesic, random_state=args.seed,
                         retry_failed=args.retry_failed,
                         progress=None if args.quiet else PairProgress(sys.stderr))
    table, curves = summarize(rows, args.out)
    md, _ = write_summary(table, args.out, title=f"meshcorr bench {args.dataset}")
    if curves and not args.no_plot:
        from ..viz.plots import plot_cumulative_curves

        styles = {label: "--" if label.endswith("(flips forgiven)") else "-" for label in curves}
        colour = {m: f"C{i}" for i, m in enumerate(e["method"] for e in table)}
        colors = {label: colour.get(label.split(" ")[0]) for label in curves}
        plot_cumulative_curves(Path(args.out) / "curves.png", curves, styles=styles, colors=colors,
                               title=f"{len({(r['source'], r['target']) for r in rows})} pairs")
    sys.stdout.write(md.read_text())
    failed = sum(e["failed"] for e in table)
    if failed:
        if not args.quiet:
            print(f"meshcorr: {failed} (pair, method) runs failed; see the 'error' column of "
                  f"{Path(args.out) / 'results.csv'}", file=sys.stderr)
        return EXIT_FAILED_RUNS
    return 0
