"""A wider search for the global choice: every sign configuration of the first Laplace-Beltrami functions (issue 34).

For each pair named, on coarse copies of 2000 vertices (:mod:`meshcorr.core.coarse`): every sign
configuration of Laplace-Beltrami functions 1..K (2^K maps, each the nearest neighbour in the
signed spectral coordinates refined by a short ZoomOut, K+1 -> 20 functions), those that keep the
orientation (score >= 0.5) aligned by the smooth shells (6, 8, ..., 20 functions), lifted to the
full meshes and scored against the truth. Per map: the energies a choice could rank by (what is
left of the alignment in the product space and in the coordinates, the last deformation, the
curvature disagreement on the full meshes) next to its error. The question: is the right map
among them, and does one of these energies put it first? Usage::

    python benchmarks/sign_search_study.py shrec07-human 11-15 13-17 [--k 6]

Needs ``../shared/data``; the set names and pairs are those of ``benchmarks/robustness.py``.
"""

from __future__ import annotations

import argparse
import itertools
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import robustness as rb  # noqa: E402
from meshcorr.choice.curvature import curvature_disagreement  # noqa: E402
from meshcorr.core.coarse import coarse_copy  # noqa: E402
from meshcorr.core.map_orientation import orientation_score  # noqa: E402
from meshcorr.core.mesh import as_mesh  # noqa: E402
from meshcorr.evaluation.metrics import GeodesicCache  # noqa: E402
from meshcorr.spectral.basis import pair_bases  # noqa: E402
from meshcorr.spectral.nearest import nearest_vertices  # noqa: E402
from meshcorr.stages.refine import zoomout  # noqa: E402
from meshcorr.stages.shells import shell_refine  # noqa: E402


def sign_maps(c1, c2, k: int):
    """(signs, coarse map) of every sign configuration of functions 1..k that keeps the orientation."""
    p1, p2 = pair_bases(c1.mesh, c2.mesh, 30)
    for signs in itertools.product((1.0, -1.0), repeat=k):
        s = np.array((1.0,) + signs)
        start = nearest_vertices(p1[:, :k + 1] * s, p2[:, :k + 1])
        mapping, _ = zoomout(p1[:, :20], p2[:, :20], start, k_start=k + 1, step=1, n_sample=300)
        if orientation_score(c1.mesh, c2.mesh, mapping) >= 0.5:
            yield s, mapping


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("set")
    parser.add_argument("pairs", nargs="+", help="SOURCE-TARGET names, e.g. 11-15")
    parser.add_argument("--k", type=int, default=6)
    args = parser.parse_args(argv)
    if not rb.DATA.is_dir():
        print(f"sign_search_study: {rb.DATA} is absent; skipping.", file=sys.stderr)
        return 0
    for pair in rb.build_sets(False)[args.set]:
        if f"{pair.source_name}-{pair.target_name}" not in args.pairs:
            continue
        src, tgt = as_mesh(pair.source_path), as_mesh(pair.target_path)
        c1, c2 = coarse_copy(src, 2000), coarse_copy(tgt, 2000)
        cache, rows = GeodesicCache("heat"), []
        for signs, mapping in sign_maps(c1, c2, args.k):
            energy: dict = {}
            shelled = c1.lift_map(shell_refine(c1.mesh, c2.mesh, mapping, k=30, scales=tuple(range(6, 21, 2)),
                                               energy=energy), c2)
            scored = rb.score(pair, tgt, shelled, cache)
            rows.append((energy["alignment"], energy["extrinsic"], energy["deformation"],
                         curvature_disagreement(src, tgt, shelled), scored["mean_error"], scored["flipped"], signs))
        print(f"{pair.source_name}-{pair.target_name}: {len(rows)} orientation-keeping configurations")
        print("| alignment | extrinsic | deformation | curvature | error | flip | signs |")
        print("|---|---|---|---|---|---|---|")
        for row in sorted(rows, key=lambda r: r[0])[:12]:
            print("| %.4f | %.5f | %.4f | %.3f | %.3f | %d | %s |" % (row[:6] + (row[6].astype(int).tolist(),)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
