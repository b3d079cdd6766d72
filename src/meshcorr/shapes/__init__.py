"""Prepared shapes: everything per shape, computed once, and the on-disk cache that keeps them.

- :mod:`~meshcorr.shapes.prepared`: :class:`~meshcorr.shapes.prepared.PreparedShape`
  (a mesh, its spectrum and its per-shape store) and its ``.npz`` file;
- :mod:`~meshcorr.shapes.cache`: the cache folder keyed by the mesh's
  content and the settings (``meshcorr cache``).

:func:`meshcorr.prepare` (:mod:`meshcorr.pipeline.prepare`) makes them.
"""
