"""Cases of issue 31, item 8: a part given as a whole shape, and a cut closed as a hole, warn and name the mode."""

from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]


def _cut(name: str, keep: float):
    """The bundled example ``name`` cut to ``keep`` of its area by a plane that contains its long axis."""
    from meshcorr.core.mesh import as_mesh
    from meshcorr.evaluation.cuts import cut_by_plane

    mesh = as_mesh(str(ROOT / "examples" / name))
    axes = np.linalg.svd(mesh.vertices - mesh.vertices.mean(axis=0), full_matrices=False)[2]
    return cut_by_plane(mesh, keep=keep, normal=axes[2])[0]


def _write(tmp: Path, file: str, mesh) -> None:
    from meshcorr.io import write_mesh

    write_mesh(tmp / file, mesh.vertices, mesh.faces)


def _part(tmp: Path) -> None:
    _write(tmp, "part.off", _cut("creature_rest.off", 0.7))


def _two_parts(tmp: Path) -> None:
    _part(tmp)
    _write(tmp, "other.off", _cut("creature_bent.off", 0.75))


CASES = [
    dict(name="creature cut to 70 % along its long axis, matched as a whole shape", setup=_part,
         argv=["match", "{tmp}/part.off", "{B}", "-o", "{tmp}/m.txt", "--no-refine"], exit=0,
         stderr="meshcorr: warning: The source has an open boundary loop enclosing"),
    dict(name="two cut creatures matched as whole shapes: the closed cuts are reported", setup=_two_parts,
         argv=["match", "{tmp}/part.off", "{tmp}/other.off", "-o", "{tmp}/m.txt", "--no-refine"], exit=0,
         stderr="meshcorr: warning: Closed holes that look like cuts: on the source"),
]
