"""The README's picture of a partial match (docs/partial_match.png), from the project's own shapes.

The synthetic creature (:func:`meshcorr.datasets.creature`, 2000 vertices) at rest is cut by a plane to
70 % of its area and matched into the whole creature, bent, rotated and re-indexed, with
``meshcorr.match(part, whole, partial="source")``. Panels, drawn with :mod:`meshcorr.viz.render`:
the whole coloured by part with the unmatched region in grey, the part through the map, the part
through the ground truth, and the default whole-to-whole map of the same part for comparison.

Usage (needs ``pip install meshcorr[plot]``; no data beside the repository)::

    python benchmarks/partial_picture.py [-o docs/partial_match.png]
"""

from __future__ import annotations

import argparse
import sys
import warnings

import numpy as np

import meshcorr
from meshcorr.evaluation import cuts as cuts
from meshcorr import datasets as ds
from meshcorr.evaluation.metrics import geodesic_errors
from meshcorr.core.mesh import as_mesh
from meshcorr.transfer import pull_back
from meshcorr.maps.colors import UNMAPPED_COLOR, mesh_coloring
from meshcorr.viz.render import Panel, render_panels


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("-o", "--output", default="docs/partial_match.png")
    parser.add_argument("--dpi", type=int, default=80)
    args = parser.parse_args(argv)
    rest = ds.creature(resolution=3)
    bent = ds.creature(resolution=3, pose="bent", random_state=1)
    moved, index = ds.rigid_copy(bent, random_state=3)
    truth = index[ds.ground_truth(rest, bent)]
    source, whole = as_mesh((rest.vertices, rest.faces), name="rest"), as_mesh((moved.vertices, moved.faces))
    part, kept = cuts.cut_by_plane(source, keep=0.7, random_state=2)
    result = meshcorr.match(part, whole, partial="source")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", meshcorr.MeshWarning)  # the PartialShapeWarning this picture shows
        default = meshcorr.match(part, whole)
    errors = {name: float(geodesic_errors(whole, r.map, truth[kept]).mean())
              for name, r in (("partial", result), ("default", default))}
    colors = mesh_coloring("parts", whole.vertices, whole.faces)
    matched = np.where(result.matched_region[:, None], colors, UNMAPPED_COLOR)
    # The whole drawn in the part's frame (the copy was rotated): undo the rigid motion for the picture.
    drawn = np.empty_like(whole.vertices)
    drawn[index] = bent.vertices
    panels = [
        Panel(drawn, whole.faces, matched, f"whole: matched region ({result.matched_area_fraction:.0%})"),
        Panel(part.vertices, part.faces, pull_back(colors, result.map, fill=UNMAPPED_COLOR),
              f"part, partial='source': error {errors['partial']:.3f}"),
        Panel(part.vertices, part.faces, pull_back(colors, truth[kept], fill=UNMAPPED_COLOR),
              "part, ground truth"),
        Panel(part.vertices, part.faces, pull_back(colors, default.map, fill=UNMAPPED_COLOR),
              f"part, default mode: error {errors['default']:.3f}"),
    ]
    render_panels(panels, args.output, ncols=2, elev=25.0, azim=-60.0, dpi=args.dpi,
                  footer="a 70 % part of the creature; error: mean geodesic error / sqrt(area of the whole)")
    print(f"wrote {args.output}: partial {errors['partial']:.4f}, default {errors['default']:.4f}, "
          f"matched {result.matched_area_fraction:.3f} of the whole (the part is "
          f"{part.area / source.area:.3f} of the source)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
