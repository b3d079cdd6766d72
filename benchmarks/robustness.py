"""Right maps on data nobody tuned for (issue 12): flips, partial swaps, non-isometric pairs.

One command scores ``meshcorr.match`` (default settings) and pyFM's automatic
pipeline on the same pairs of several sets, per set and pooled:

- ``tosca5k``: within-class TOSCA pairs (a class-stratified sample of
  ``test_pairs.txt``), 5000 template points;
- ``tosca-noniso``: the gorilla -> man / woman pairs, 900 landmarks; and the
  same pairs again with 5 landmark pairs taken from the truth
  (``tosca-noniso+5``: farthest-point spread over the truth's points, given to
  meshcorr as ``landmarks=`` and to pyFM as its ``landmarks``);
- ``shrec07-human`` and ``shrec07-fourleg``: raw SHREC'07 models within each
  class, scored at the hand-picked feature points (mirrored truth from the
  ``*.sym.info`` left/right pairs);
- ``cat-lion``: Sumner's cat reference -> lion reference at the 55 markers.

Per pair: the mean geodesic error on the target (divided by sqrt(target
area)) with flips counted (the truth only) and forgiven (per point, the
nearer of the truth and the mirrored truth), and the seconds of the map. Per
set: the means, the number of **full flips** (the error against the mirrored
truth is smaller) and of **partial swaps** (neither: the error is more than
twice the forgiven one, e.g. legs swapped under a right upper body).

Rows are appended to a CSV as they finish, so an interrupted run resumes;
``--report`` writes the Markdown table. Usage::

    nice -n 10 python benchmarks/robustness.py [--quick] [--methods meshcorr pyfm meshcorr-oriented] \\
        [--out benchmarks/cache/robustness.csv] [--report benchmarks/RESULTS-robustness-table.md]

Needs ``../shared/data`` beside the repository; exits with a message when it
is absent. pyFM is optional (``pip install pyfmaps``).
"""

from __future__ import annotations

import argparse
import ast
import contextlib
import csv
import itertools
import os
import platform
import re
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import meshcorr
from meshcorr.evaluation.benchmark import stratified_sample
from meshcorr.evaluation.metrics import GeodesicCache, geodesic_errors
from meshcorr.evaluation.ground_truth import read_vts
from meshcorr.core.sampling import farthest_point_sampling
from meshcorr.core.mesh import as_mesh
from tosca_symmetry import pyfm_map  # the same pyFM settings as the other benchmarks

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
FIELDS = ["set", "source", "target", "method", "mean_error", "forgiven_error", "flipped", "partial",
          "seconds", "n_points", "margin", "probability"]
N_TRUTH_LANDMARKS = 5


@dataclass
class Pair:
    """One scored pair: mesh paths and the truth (source point k <-> target point k)."""

    set: str
    source_name: str
    target_name: str
    source_path: Path
    target_path: Path
    source_points: np.ndarray
    target_points: np.ndarray
    target_sym_points: np.ndarray | None


def tosca_pairs(root: Path, set_name: str, n_pairs: int | None) -> list[Pair]:
    """TOSCA-style pairs (``test_pairs.txt``, ``corres/*.vts``, mirrored ``*.sym.vts``)."""
    listed = [tuple(line.split()) for line in (root / "test_pairs.txt").read_text().splitlines()
              if len(line.split()) == 2]
    pairs = stratified_sample(listed, n_pairs, random_state=0)
    return [Pair(set_name, a, b, root / f"{a}.off", root / f"{b}.off", read_vts(root / "corres" / f"{a}.vts"),
                 read_vts(root / "corres" / f"{b}.vts"), read_vts(root / "corres" / f"{b}.sym.vts"))
            for a, b in pairs]


def _shrec_points(path: Path) -> np.ndarray:
    """A SHREC'07 ``Corrs/<id>.vts`` file: a 0-based vertex index and its x y z a line."""
    return np.array([int(line.split()[0]) for line in path.read_text().splitlines() if line.strip()],
                    dtype=np.int64)


def _shrec_swap(path: Path, n_points: int) -> np.ndarray:
    """Feature-number permutation swapping the left/right pairs listed in a ``*.sym.info`` file."""
    order = np.arange(n_points)
    for line in path.read_text().splitlines():
        fields = [int(f) for f in line.split()]
        if len(fields) == 2:
            order[fields[0]], order[fields[1]] = fields[1], fields[0]
    return order


def shrec_pairs(root: Path, ids: range, sym_info: str, set_name: str, n_pairs: int | None) -> list[Pair]:
    """All ordered-by-id pairs within one SHREC'07 class, the first ``n_pairs`` of a fixed shuffle."""
    combos = list(itertools.combinations(ids, 2))
    if n_pairs is not None and n_pairs < len(combos):
        order = np.random.default_rng(0).permutation(len(combos))[:n_pairs]
        combos = [combos[i] for i in sorted(order)]
    pairs = []
    for a, b in combos:
        pa, pb = _shrec_points(root / "Corrs" / f"{a}.vts"), _shrec_points(root / "Corrs" / f"{b}.vts")
        swap = _shrec_swap(root / "Corrs" / sym_info, len(pb))
        pairs.append(Pair(set_name, str(a), str(b), root / "Meshes" / f"{a}.off", root / "Meshes" / f"{b}.off",
                          pa, pb, pb[swap]))
    return pairs


def cat_lion_pair(root: Path) -> list[Pair]:
    """Sumner cat reference -> lion reference at the 55 hand-placed markers."""
    text = (root / "markers-cat-lion.yml").read_text()
    rows = re.findall(r'"(\d+):(\d+)"\s*(?:#(.*))?', text)
    cat = np.array([int(r[0]) for r in rows], dtype=np.int64)
    lion = np.array([int(r[1]) for r in rows], dtype=np.int64)
    notes = [r[2].strip().lower() for r in rows]
    # Mirrored truth: the marker whose note swaps "left" and "right" (itself when there is none).
    swapped = [re.sub(r"\b(left|right)\b", lambda m: {"left": "right", "right": "left"}[m.group(1)], n)
               for n in notes]
    sym = np.array([lion[notes.index(s)] if s in notes else lion[i] for i, s in enumerate(swapped)])
    return [Pair("cat-lion", "cat-reference", "lion-reference", root / "cat-poses" / "cat-reference.obj",
                 root / "lion-poses" / "lion-reference.obj", cat, lion, sym)]


def build_sets(quick: bool) -> dict[str, list[Pair]]:
    """The pairs of every set (``quick``: a few pairs of each, for a smoke run)."""
    scale = (lambda n: min(n, 8)) if quick else (lambda n: n)
    sets = {
        "tosca5k": tosca_pairs(DATA / "tosca5k", "tosca5k", scale(80)),
        "tosca-noniso": tosca_pairs(DATA / "tosca-noniso", "tosca-noniso", scale(30)),
        "shrec07-human": shrec_pairs(DATA / "shrec07", range(11, 21), "1.sym.info", "shrec07-human", scale(40)),
        "shrec07-fourleg": shrec_pairs(DATA / "shrec07", range(391, 401), "20.sym.info", "shrec07-fourleg",
                                       scale(40)),
        "cat-lion": cat_lion_pair(DATA / "sumner"),
    }
    sets["tosca-noniso+5"] = [Pair(**{**p.__dict__, "set": "tosca-noniso+5"}) for p in sets["tosca-noniso"]]
    return sets


def truth_landmarks(pair: Pair, source, count: int = N_TRUTH_LANDMARKS) -> np.ndarray:
    """``count`` truth pairs spread over the source by farthest-point sampling (Euclidean, seeded)."""
    points = np.asarray(source.vertices)[pair.source_points]
    chosen = farthest_point_sampling(lambda i: np.linalg.norm(points - points[i], axis=1), len(points), count,
                                     start=0).indices
    return np.stack([pair.source_points[chosen], pair.target_points[chosen]], axis=1)


def score_points(target, predicted: np.ndarray, truth: np.ndarray, sym: np.ndarray | None,
                 cache: GeodesicCache) -> dict:
    """Flips-counted and forgiven errors of predicted target vertices against the truth (and its mirror)."""
    errors = geodesic_errors(target, predicted, truth, cache=cache)
    row = {"mean_error": float(errors.mean()), "n_points": len(errors)}
    if sym is None:
        return {**row, "forgiven_error": row["mean_error"], "flipped": 0, "partial": 0}
    sym_errors = geodesic_errors(target, predicted, sym, cache=cache)
    forgiven = float(np.minimum(errors, sym_errors).mean())
    flipped = sym_errors.mean() < errors.mean()
    partial = (not flipped) and row["mean_error"] > 2 * forgiven and row["mean_error"] > 0.05
    return {**row, "forgiven_error": forgiven, "flipped": int(flipped), "partial": int(partial)}


def score(pair: Pair, target, mapping: np.ndarray, cache: GeodesicCache) -> dict:
    """Flips-counted and forgiven errors of one map at the pair's truth points."""
    return score_points(target, mapping[pair.source_points], pair.target_points, pair.target_sym_points, cache)


def run_pair(pair: Pair, methods: list[str], options: dict | None = None) -> list[dict]:
    source = as_mesh(pair.source_path, name=pair.source_name)
    target = as_mesh(pair.target_path, name=pair.target_name)
    landmarks = truth_landmarks(pair, source) if pair.set.endswith("+5") else None
    cache = GeodesicCache("heat")
    rows = []
    for method in methods:
        start = time.perf_counter()
        if method.startswith("meshcorr"):  # "meshcorr-oriented": with oriented_starts=True
            extra = dict(options or {}, **({} if landmarks is None else {"landmarks": landmarks}))
            if method == "meshcorr-oriented":
                extra["oriented_starts"] = True
            result = meshcorr.match(source, target, **extra)
            mapping, confidence = result.map, result.confidence or {}
            margin, probability = confidence.get("margin"), confidence.get("probability")
        else:
            mapping, margin, probability = pyfm_map(source, target, landmarks), None, None
        seconds = time.perf_counter() - start
        rows.append(dict(set=pair.set, source=pair.source_name, target=pair.target_name, method=method,
                         seconds=round(seconds, 3), margin="" if margin is None else margin,
                         probability="" if probability is None else probability,
                         **score(pair, target, mapping, cache)))
    return rows


def _spread(pairs: list[Pair], count: int) -> list[Pair]:
    """``count`` pairs spread evenly over the list (all of them for 0 or more than there are)."""
    if count <= 0 or count >= len(pairs):
        return list(pairs)
    return [pairs[i] for i in np.linspace(0, len(pairs) - 1, count).round().astype(int)]


def with_paired_subset(rows: list[dict]) -> list[dict]:
    """Rows plus meshcorr's rows again as ``meshcorr@pyfm-pairs`` on the pairs pyFM ran on."""
    on_pyfm = {(r["set"], r["source"], r["target"]) for r in rows if r["method"] == "pyfm"}
    extra = [{**r, "method": "meshcorr@pyfm-pairs"} for r in rows
             if r["method"] == "meshcorr" and (r["set"], r["source"], r["target"]) in on_pyfm]
    return rows + extra


def summarize(rows: list[dict]) -> list[dict]:
    """Per set and method, and pooled over all sets: means, flips, partial swaps, seconds."""
    table = []
    keys = sorted({(r["set"], r["method"]) for r in rows})
    for set_name in list(dict.fromkeys(k[0] for k in keys)) + ["all"]:
        for method in sorted({k[1] for k in keys}):
            sel = [r for r in rows if r["method"] == method and (set_name == "all" or r["set"] == set_name)]
            if not sel:
                continue
            table.append(dict(set=set_name, method=method, pairs=len(sel),
                              mean=np.mean([float(r["mean_error"]) for r in sel]),
                              forgiven=np.mean([float(r["forgiven_error"]) for r in sel]),
                              flips=sum(int(r["flipped"]) for r in sel),
                              partial=sum(int(r["partial"]) for r in sel),
                              seconds=np.median([float(r["seconds"]) for r in sel])))
    return table


def markdown(table: list[dict]) -> str:
    lines = ["| set | method | pairs | mean error (flips counted) | forgiving flips | full flips | "
             "partial swaps | median s/pair |", "|---|---|---|---|---|---|---|---|"]
    for t in table:
        lines.append(f"| {t['set']} | {t['method']} | {t['pairs']} | {t['mean']:.4f} | {t['forgiven']:.4f} | "
                     f"{t['flips']} | {t['partial']} | {t['seconds']:.2f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--methods", nargs="+", default=["meshcorr", "pyfm"],
                        choices=["meshcorr", "meshcorr-oriented", "pyfm"],
                        help="meshcorr-oriented: meshcorr with oriented_starts=True (default: meshcorr pyfm)")
    parser.add_argument("--sets", nargs="+", default=None, help="subset of the set names")
    parser.add_argument("--quick", action="store_true", help="at most 8 pairs per set")
    parser.add_argument("--pyfm-pairs", type=int, default=12,
                        help="pyFM on this many pairs of each set, spread evenly (it takes ~10x longer); "
                             "0: all")
    parser.add_argument("--out", type=Path, default=Path("benchmarks/cache/robustness.csv"))
    parser.add_argument("--report", type=Path, default=None, help="write the Markdown table here")
    parser.add_argument("--option", action="append", default=[], metavar="NAME=VALUE",
                        help="a setting of meshcorr.match for this run, e.g. coarse_vertices=0 (repeatable)")
    parser.add_argument("--half", choices=("a", "b"), default=None,
                        help="only the pairs of one fixed half of each set (alternate pairs: a = 1st, 3rd, ...)")
    args = parser.parse_args(argv)
    options = {name: ast.literal_eval(value) for name, value in (o.split("=", 1) for o in args.option)}
    if not DATA.is_dir():
        print(f"robustness: {DATA} is absent; this benchmark needs ../shared/data. Skipping.", file=sys.stderr)
        return 0
    sets = build_sets(args.quick)
    chosen = args.sets or list(sets)
    rows = previous_rows(args.out)
    done = {(r["set"], r["source"], r["target"], r["method"]) for r in rows}
    with appending(args.out, FIELDS) as (handle, writer):
        for name in chosen:
            subset = _spread(sets[name], args.pyfm_pairs)
            for index, pair in enumerate(sets[name]):
                if args.half is not None and index % 2 != "ab".index(args.half):
                    continue
                todo = [m for m in args.methods if (name, pair.source_name, pair.target_name, m) not in done
                        and (m != "pyfm" or any(pair is q for q in subset))]
                if not todo:
                    continue
                for row in run_pair(pair, todo, options):
                    writer.writerow(row)
                    handle.flush()
                    rows.append(row)
                    print(f"{name} {pair.source_name}->{pair.target_name} {row['method']}: "
                          f"{row['mean_error']:.4f} (forgiven {row['forgiven_error']:.4f}"
                          f"{', FLIP' if row['flipped'] else ''}{', PARTIAL' if row['partial'] else ''}) "
                          f"{row['seconds']:.1f} s", file=sys.stderr, flush=True)
    rows = [r for r in rows if r["set"] in chosen and r["method"] in args.methods]
    text = markdown(summarize(with_paired_subset(rows)))
    publish(text, "robustness.py", argv, args.report)
    return 0


def previous_rows(path: Path) -> list[dict]:
    """The rows of an earlier, possibly interrupted run (none if ``path`` does not exist)."""
    if not path.is_file():
        return []
    with path.open() as handle:
        return list(csv.DictReader(handle))


@contextlib.contextmanager
def appending(path: Path, fields: list[str]):
    """``(handle, csv.DictWriter)`` appending to ``path``; the header is written when the file is new."""
    path.parent.mkdir(parents=True, exist_ok=True)
    new_file = not path.is_file()
    with path.open("a", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=fields)
        if new_file:
            writer.writeheader()
        yield handle, writer


def publish(text: str, script: str, argv, report: Path | None) -> None:
    """Print a Markdown report under a line naming the command, machine and date; also write it to ``report``."""
    header = (f"Command: `python benchmarks/{script} {' '.join(argv or sys.argv[1:])}`; "
              f"{platform.node()}, {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
              f"{time.strftime('%Y-%m-%d')}, meshcorr {getattr(meshcorr, '__version__', '?')}.\n\n")
    print(header + text)
    if report is not None:
        report.write_text(header + text + "\n")


if __name__ == "__main__":
    sys.exit(main())
