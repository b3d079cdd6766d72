"""Exceptions raised by meshcorr.

Every problem with user input raises one of these with a message that names
the problem and the fix; the CLI turns them into a one-line error and a
non-zero exit code.
"""

from __future__ import annotations


class MeshcorrError(Exception):
    """Base class of every error meshcorr raises on purpose."""


class MeshError(MeshcorrError, ValueError):
    """A mesh cannot be used: unreadable, malformed, or unsuitable for the method."""


class ParameterError(MeshcorrError, ValueError):
    """An option has an invalid value."""


class InputError(ParameterError):
    """An input data file other than a mesh (vertex map, ground truth) cannot be used.

    A :class:`ParameterError` too, for code written before the CLI told bad
    data (exit code 3) apart from bad usage (exit code 2).
    """


class OutputError(ParameterError):
    """An output cannot be written where asked (no folder, no permission, an input's path)."""


class PreparedShapeError(MeshcorrError, ValueError):
    """A prepared shape (or cache file) was made for another mesh, other settings or another version."""


class PartialityError(ParameterError):
    """The declared partiality (``partial=``) contradicts the shapes, or does not go with another option."""


class MeshWarning(UserWarning):
    """A mesh was changed on input (e.g. polygons triangulated) or is suspicious."""


class MemoryLimitError(ParameterError):
    """The chosen mode would need more memory than it is allowed (see ``max_memory``)."""


class PartialShapeWarning(MeshWarning):
    """One shape looks like a part of the other, but ``partial`` was not given (see :mod:`meshcorr.partial`)."""
