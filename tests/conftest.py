"""Fixtures shared by several test modules.

Each fixture is named for what it holds. They keep the module scope the tests had when each module
defined its own copy: every module that asks for one gets its own, freshly built objects (the meshes'
per-shape caches are not shared between modules).
"""

import numpy as np
import pytest
import trimesh

from meshcorr import datasets as ds
from meshcorr.core.mesh import as_mesh


def rest_and_bent_moved(resolution: int = 1):
    """The creature at rest (source side) and bent, rotated, moved and re-indexed (target side).

    Returns ``(rest, bent, truth, back)``: the two meshes (named "rest" and "bent"; 500 vertices each at
    resolution 1, 2000 at 3), ``truth`` of shape ``(n_rest,)``: source vertex -> its target vertex, and
    ``back`` of shape ``(n_bent,)``: target vertex -> its source vertex.
    """
    rest = ds.creature(resolution=resolution)
    bent = ds.creature(resolution=resolution, pose="bent", random_state=1)
    moved, index = ds.rigid_copy(bent, random_state=3)
    truth = index[ds.ground_truth(rest, bent)]
    back = ds.ground_truth(bent, rest)[np.argsort(index)]  # target vertex -> source vertex
    return as_mesh((rest.vertices, rest.faces), name="rest"), as_mesh((moved.vertices, moved.faces), name="bent"), \
        truth, back


@pytest.fixture(scope="module")
def creature_rest_and_bent_moved():
    """:func:`rest_and_bent_moved` at resolution 1 (500 vertices). Used by the tests of holes
    (meshcorr.core.holes), partial shapes (meshcorr.pipeline.partial) and the sign search."""
    return rest_and_bent_moved(1)


@pytest.fixture(scope="module")
def large_creature_rest_and_bent_moved():
    """:func:`rest_and_bent_moved` at resolution 3 (2000 vertices): large enough for coarse copies of
    400 vertices (meshcorr.core.coarse, the pipeline's coarse-to-fine path)."""
    return rest_and_bent_moved(3)


@pytest.fixture(scope="module")
def tube_files_with_truth(tmp_path_factory):
    """A tube (22 x 10) as ``source.off`` and a rotated, half-size, re-indexed copy as ``target.ply``.

    Returns ``(source_path, target_path, truth)`` with the paths as strings and ``truth`` of shape
    ``(n,)``: source vertex -> its copy's vertex. Used by the command-line tests.
    """
    folder = tmp_path_factory.mktemp("pair")
    shape = ds.tube(n_along=22, n_around=10)
    copy, truth = ds.rigid_copy(shape, scale=0.5, random_state=2)
    src, tgt = folder / "source.off", folder / "target.ply"
    trimesh.Trimesh(shape.vertices, shape.faces, process=False).export(src)
    trimesh.Trimesh(copy.vertices, copy.faces, process=False).export(tgt)
    return str(src), str(tgt), truth


@pytest.fixture
def no_read_permission(monkeypatch):
    """``no_read_permission(name)``: reading a text file called ``name`` (``Path.read_text``, as the readers of
    maps, truths and landmarks do) then fails as without read permission. The tests run as root, which may
    read a chmod-000 file."""
    import errno
    import os
    import pathlib

    names = set()
    read_text = pathlib.Path.read_text

    def refuse(self, *args, **kwargs):
        if self.name in names:
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(self))
        return read_text(self, *args, **kwargs)

    monkeypatch.setattr(pathlib.Path, "read_text", refuse)
    return names.add
