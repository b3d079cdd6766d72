"""Choose the unsure-choice threshold on one fixed half of each set, report it on the other (issue 34).

Reads the CSVs of ``benchmarks/robustness.py`` (their ``margin`` column:
``result.confidence["margin"]``, empty when no rival map competed). A map
is *wrong* when the benchmark marks it a full flip or a partial swap, or
its mean error is above ``--wrong-above`` (0.2 of sqrt(area): a limb or a
side sent elsewhere). Half "a" of each set is its 1st, 3rd, ... pair in
the benchmark's order (``robustness.py --half a``), half "b" the others.

For each threshold t of a grid, a map is flagged when its margin is below
t. The threshold kept is the largest share of wrong maps flagged on half
"a" with at most ``--max-right`` (10 %) of its right maps flagged; both
halves are reported at it. Usage::

    python benchmarks/confidence_threshold.py /tmp/rf/a.csv /tmp/rf/b.csv [--sets ...]
"""

from __future__ import annotations

import argparse
import csv
import sys
from collections import defaultdict


def load(paths: list[str], sets: list[str] | None) -> list[dict]:
    rows = []
    for path in paths:
        with open(path) as handle:
            rows += [r for r in csv.DictReader(handle) if r["method"] == "meshcorr"]
    if sets:
        rows = [r for r in rows if r["set"] in sets]
    order: dict[str, int] = defaultdict(int)
    for row in rows:  # the benchmark's order within each set: its half
        row["half"] = "ab"[order[row["set"]] % 2]
        order[row["set"]] += 1
    return rows


def is_wrong(row: dict, above: float) -> bool:
    return row["flipped"] in ("1", "True") or row["partial"] in ("1", "True") or float(row["mean_error"]) > above


def margin(row: dict) -> float:
    return float(row["margin"]) if row.get("margin") not in (None, "") else float("inf")


def rates(rows: list[dict], threshold: float, above: float) -> tuple[float, float, int, int]:
    wrong = [r for r in rows if is_wrong(r, above)]
    right = [r for r in rows if not is_wrong(r, above)]
    caught = sum(margin(r) < threshold for r in wrong)
    false = sum(margin(r) < threshold for r in right)
    return caught / max(len(wrong), 1), false / max(len(right), 1), len(wrong), len(right)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("csv", nargs="+")
    parser.add_argument("--sets", nargs="+", default=None)
    parser.add_argument("--wrong-above", type=float, default=0.2)
    parser.add_argument("--max-right", type=float, default=0.10)
    args = parser.parse_args(argv)
    rows = load(args.csv, args.sets)
    if not rows:
        print("confidence_threshold: no meshcorr rows with a margin column", file=sys.stderr)
        return 1
    half = {h: [r for r in rows if r["half"] == h] for h in "ab"}
    grid = [round(0.05 * i, 2) for i in range(0, 61)]
    best = max((t for t in grid if rates(half["a"], t, args.wrong_above)[1] <= args.max_right),
               key=lambda t: (rates(half["a"], t, args.wrong_above)[0], -t))
    print(f"threshold chosen on half a: {best}")
    print("| half | pairs | wrong | wrong flagged | right flagged |")
    print("|---|---|---|---|---|")
    for name in "ab":
        caught, false, n_wrong, n_right = rates(half[name], best, args.wrong_above)
        print(f"| {name} | {n_wrong + n_right} | {n_wrong} | {caught:.0%} | {false:.0%} |")
    print("\nper set (both halves), at that threshold:")
    print("| set | pairs | wrong | wrong flagged | right flagged |")
    print("|---|---|---|---|---|")
    for name in sorted({r["set"] for r in rows}):
        caught, false, n_wrong, n_right = rates([r for r in rows if r["set"] == name], best, args.wrong_above)
        print(f"| {name} | {n_wrong + n_right} | {n_wrong} | {caught:.0%} | {false:.0%} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
