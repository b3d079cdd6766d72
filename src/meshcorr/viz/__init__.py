"""Pictures of meshes and correspondences.

- :mod:`meshcorr.maps.colors` -- per-vertex colourings (parts, coordinates,
  colour maps); numpy only.
- :mod:`meshcorr.viz.render` -- headless static pictures (PNG) with
  matplotlib's Agg back end (``pip install meshcorr[plot]``).
- :mod:`meshcorr.viz.figures` -- the paper's pictures: colour transfer,
  eigenvectors, the spectral embedding.
- :mod:`meshcorr.viz.report` -- a self-contained interactive HTML report;
  numpy only, its viewer is inline JavaScript.
- :mod:`meshcorr.viz.notebook` -- :func:`show`: both meshes side by side in
  a notebook (``pip install meshcorr[notebook]``, plotly).
- :mod:`meshcorr.viz.pick` -- the landmark picker: a local server and a page
  (the report's viewer) to click landmark pairs, save them and match again
  (``meshcorr pick``, ``result.pick()``); standard library only.

``import meshcorr`` imports this package but none of its submodules (they
load matplotlib or plotly on first use); :func:`show` imports its own.
"""


def show(source, target, mapping, **options):
    """Source and target side by side with linked colours (:func:`meshcorr.viz.notebook.show`)."""
    from .notebook import show as _show

    return _show(source, target, mapping, **options)
