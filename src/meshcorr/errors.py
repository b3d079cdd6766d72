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


class LandmarkError(ParameterError):
    """A user landmark pair cannot be used: an index out of range, a source vertex sent to two
    targets, or a vertex on a removed component.

    ``row`` is the pair's position in the given sequence, ``column`` 0 for its source index and
    1 for its target index, ``problem`` one of ``"range"``, ``"repeat"``, ``"removed"``,
    ``limit`` the mesh's vertex count (``"range"``) and ``first`` the row that gave the source
    vertex another target first (``"repeat"``): what a caller needs to name the line of a file.
    """

    def __init__(self, message: str, *, row: int, column: int, problem: str, limit: int = 0,
                 first: int = -1) -> None:
        super().__init__(message)
        self.row, self.column, self.problem, self.limit, self.first = row, column, problem, limit, first


class OutputError(ParameterError):
    """An output cannot be written where asked (no folder, no permission, an input's path)."""


class DiskFullError(OutputError):
    """An output could not be written because the disk, or the user's quota, is full (ENOSPC, EDQUOT).

    No usage error, although an :class:`OutputError`: the command line exits with code 3 (input or
    output data), not 2.
    """


class PreparedShapeError(MeshcorrError, ValueError):
    """A prepared shape (or cache file) was made for another mesh, other settings or another version."""


class PartialityError(ParameterError):
    """The declared partiality (``partial=``) contradicts the shapes, or does not go with another option."""


class MeshWarning(UserWarning):
    """A mesh was changed on input (e.g. polygons triangulated) or is suspicious."""


class MemoryLimitError(ParameterError):
    """The chosen mode would need more memory than it is allowed (see ``max_memory``)."""


class UnsureChoiceWarning(MeshWarning):
    """The whole-map choice found a map of another global configuration almost as good (``result.confidence``)."""


class PartialShapeWarning(MeshWarning):
    """One shape looks like a part of the other, but ``partial`` was not given (see :mod:`meshcorr.pipeline.partial`)."""


class LandmarkWarning(MeshWarning):
    """User landmarks look wrong: they disagree with each other or with every map found without them
    (:mod:`meshcorr.choice.landmark_doubts`); the pairs are named."""
