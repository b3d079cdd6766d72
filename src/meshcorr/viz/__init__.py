"""Pictures of meshes and correspondences.

- :mod:`meshcorr.viz.colors` -- per-vertex colourings (parts, coordinates,
  colour maps); numpy only.
- :mod:`meshcorr.viz.render` -- headless static pictures (PNG) with
  matplotlib's Agg back end (``pip install meshcorr[plot]``).
- :mod:`meshcorr.viz.figures` -- the paper's pictures: colour transfer,
  eigenvectors, the spectral embedding.
- :mod:`meshcorr.viz.report` -- a self-contained interactive HTML report;
  numpy only, its viewer is inline JavaScript.

Nothing here is imported by ``import meshcorr``; import the submodules.
"""
