"""The staged API: ``Matcher(**settings).fit(source, target) -> Correspondence``.

In the style of scikit-learn's estimators: ``__init__`` only stores the
settings, :meth:`Matcher.fit` validates them (:class:`meshcorr.Settings`),
runs :func:`meshcorr.match` and keeps the result in
``result_``; :meth:`get_params` / :meth:`set_params` make the settings
inspectable. :func:`meshcorr.match` stays the one-call shortcut of the same
work.
"""

from __future__ import annotations

from ..errors import MeshcorrError, ParameterError
from ..core.mesh import MeshLike
from ..runtime.progress import MATCH_PLAN, as_progress
from ..maps.result import Correspondence
from .settings import Settings

__all__ = ["Matcher"]


class Matcher:
    """Dense correspondence from a source mesh to a target mesh, with stored settings.

    Parameters
    ----------
    settings : Settings, optional
        A whole set of settings; keywords override single ones.
    **options
        Any field of :class:`Settings` (``k=6``, ``method="icp"``, ...).

    Attributes
    ----------
    settings_ : Settings
        The validated settings of the last :meth:`fit`.
    result_ : Correspondence
        The result of the last :meth:`fit`.

    Examples
    --------
    >>> from meshcorr import Matcher, datasets
    >>> source, target = datasets.figure(), datasets.figure(pose="bent")
    >>> matcher = Matcher(k=6, refine=False)
    >>> result = matcher.fit(source, target)  # doctest: +SKIP
    >>> result.map.shape == (source.n_vertices,)  # doctest: +SKIP
    True
    """

    def __init__(self, settings: Settings | None = None, **options) -> None:
        if settings is not None and not isinstance(settings, Settings):
            raise ParameterError(f"settings must be a meshcorr.Settings (or None, with keywords: Matcher(k=6, ...)); "
                                 f"got {type(settings).__name__}. Pass single settings as keywords: "
                                 "Matcher(**options).")
        self.settings = settings
        self.options = options

    def get_params(self) -> dict:
        """Every setting this matcher would use, ``{name: value}`` (validated)."""
        return self._settings().as_dict()

    def set_params(self, **options) -> "Matcher":
        """Change some settings; returns the matcher."""
        self.options = {**self.options, **options}
        return self

    def _settings(self) -> Settings:
        base = self.settings if self.settings is not None else Settings()
        return base.replace(**self.options) if self.options else base

    def fit(self, source: MeshLike, target: MeshLike, *, progress=None) -> Correspondence:
        """Compute the correspondence from ``source`` to ``target``.

        Parameters
        ----------
        source, target : path, trimesh.Trimesh, Mesh or (vertices, faces)
            The meshes (see :func:`meshcorr.match`).
        progress : bool or callable, optional
            True for a progress bar (tqdm, notebook-aware), or a callback
            ``progress(stage, done, total)``.

        Returns
        -------
        result : Correspondence
            ``result.map[i]`` is the target vertex of source vertex i; the
            result keeps both meshes (``result.source``, ``result.target``)
            for :meth:`~Correspondence.show`, :meth:`~Correspondence.precise_map` and
            :meth:`~Correspondence.evaluate`.

        Raises
        ------
        ParameterError
            A setting that is unknown, invalid, or unused by the method.
        MeshError
            A mesh that cannot be used.
        """
        from .run import match

        settings = self._settings()
        reporter = as_progress(progress, MATCH_PLAN)  # one bar for the run
        try:
            result = match(source, target, settings, progress=reporter)
        finally:
            if hasattr(reporter, "close"):
                reporter.close()
        self.settings_, self.result_ = settings, result
        return result

    def __repr__(self) -> str:
        try:
            changed = self._settings().changed() if self.settings is not None or self.options else {}
        except MeshcorrError:  # settings not valid (yet): shown as given; fit() says what is wrong
            changed = dict(self.options)
        inner = ", ".join(f"{key}={value!r}" for key, value in changed.items())
        return f"Matcher({inner})"
