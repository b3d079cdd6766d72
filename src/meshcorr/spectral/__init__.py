"""Spectra of one shape: the embedding of the paper and the Laplace-Beltrami bases of the refinements.

- :mod:`~meshcorr.spectral.embedding`: Gaussian affinities and the
  embedding scaled by sqrt(eigenvalue) (docs/method.md, steps 2-3);
- :mod:`~meshcorr.spectral.nystrom`: the same from sampled geodesic rows
  (the scalable mode);
- :mod:`~meshcorr.spectral.spectrum`, :mod:`~meshcorr.spectral.modes`: the
  :class:`~meshcorr.spectral.spectrum.Spectrum` a pair uses, and the choice
  between the dense and the scalable mode;
- :mod:`~meshcorr.spectral.basis`, :mod:`~meshcorr.spectral.nearest`: the
  Laplace-Beltrami bases and the nearest-row searches that ZoomOut, the
  smooth shells, functional maps and the partial mode share;
- :mod:`~meshcorr.spectral.fmap`: functional maps (``meshcorr.fmap``).
"""
