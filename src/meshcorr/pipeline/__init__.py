"""The pipeline: the thin ``match`` that runs the stages in the paper's order, and what surrounds it.

``run.match`` (the method, top to bottom), ``partial`` (a part against a
whole), ``settings`` (every option and its default, :class:`meshcorr.Settings`),
``prepare`` (:func:`meshcorr.prepare`), ``matcher`` (the staged API) and ``methods`` (the registry of the spectral method and its
baselines). ``meshcorr.pipeline.match`` and the other names of the former
``meshcorr.pipeline`` module are looked up in ``run`` on first use.
"""

from .._moved import forwarding

__getattr__ = forwarding(__name__, "run")
