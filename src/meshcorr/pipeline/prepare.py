"""``prepare(mesh, settings)``: everything per shape that :func:`meshcorr.match` needs, computed once.

The per-shape work (docs/method.md, steps 1-3, and what scoring and
refining a map read from one mesh) depends on the per-shape settings only
(:func:`meshcorr.pipeline.settings.shape_settings`); the result is a
:class:`meshcorr.shapes.prepared.PreparedShape`, which :func:`meshcorr.match`
takes in place of a mesh and maps bit for bit as the mesh.
"""

from __future__ import annotations

from ..core.mesh import MeshLike
from ..shapes.prepared import PreparedShape, load_mesh, prepare_mesh
from ..spectral.modes import resolve_memory, select_mode
from .settings import Settings, as_settings, shape_settings

__all__ = ["prepare"]


def prepare(mesh: MeshLike, settings: Settings | None = None, *, name: str | None = None, cache=None,
            **overrides) -> PreparedShape:
    """Everything per shape that :func:`meshcorr.match` needs, computed once.

    Parameters
    ----------
    mesh : path, trimesh.Trimesh, Mesh or (vertices, faces)
    settings : Settings, optional
        The settings of the matches to come (default: ``Settings()``);
        keywords override single fields (``prepare(mesh, k=8)``). Only
        ``k``, ``geodesic``, ``scale_eigenvalues``, ``n_samples``,
        ``refine``, ``refine_k``, ``largest_component``, ``random_state`` and
        ``fill_holes`` change what is computed; :func:`meshcorr.match`
        refuses a shape prepared with other values (a shape for the partial
        mode or a one-to-one map needs ``fill_holes=False``). ``mode``,
        ``max_memory`` and ``scalable_above`` choose the mode, resolved for
        this mesh alone ("auto": dense up to ``scalable_above`` vertices). A
        pair runs in the mode its larger mesh needs: prepare both shapes of
        a mixed pair with that mode.
    name : str, optional
        Name used in messages (default: the file name, or "mesh").
    cache : ShapeCache, path or None
        Look the shape up in this on-disk cache (:mod:`meshcorr.shapes.cache`) and
        store it there when it was not found.
    **overrides
        Single fields of :class:`Settings`.

    Returns
    -------
    shape : PreparedShape

    Raises
    ------
    ParameterError
        A setting :class:`Settings` refuses, or an unknown keyword.
    """
    settings = as_settings(settings, overrides)
    per_shape = shape_settings(settings)
    loaded = load_mesh(mesh, per_shape, name=name)
    mode = select_mode(settings.mode, loaded.n_vertices, loaded.n_vertices,
                       max_memory=resolve_memory(settings.max_memory), scalable_above=settings.scalable_above)
    if cache is not None:
        from ..shapes.cache import as_cache

        return as_cache(cache).prepare(loaded, per_shape, mode)
    return prepare_mesh(loaded, per_shape, mode)
