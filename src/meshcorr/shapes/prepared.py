"""Prepare a shape once, match it many times: :class:`PreparedShape` (made by :func:`meshcorr.prepare`).

Most of the time of a pair goes into work that depends on one mesh only:
its geodesic rows and spectral embedding (docs/method.md, steps 1-3), the
outward orientation and the curvature field that score candidate maps
(:mod:`meshcorr.core.orientation`, :mod:`meshcorr.choice.curvature`), and the
Laplace-Beltrami basis of the refinement (:mod:`meshcorr.stages.refine`).
:func:`meshcorr.prepare` (:mod:`meshcorr.pipeline.prepare`) computes all of it with the very
functions :func:`meshcorr.match` calls, for the settings that affect it
(:data:`SHAPE_SETTING_NAMES`), and :func:`meshcorr.match` accepts the result in
place of a mesh: the map is the same, bit for bit, as from the meshes.

Where the data lives
    The spectrum (:class:`meshcorr.spectral.spectrum.Spectrum`) is held by the
    prepared shape; everything else is the mesh's own cache
    (``Mesh.store``, :mod:`meshcorr.core.store`: ``key tuple -> value``, filled by the cached functions
    of the pipeline, which look there before they compute). A new per-shape
    quantity computed through such a cached function is carried, saved and
    loaded without any change here; :func:`warm` is where :func:`meshcorr.prepare`
    asks for it (one line).

File format (:meth:`PreparedShape.save`, version :data:`FORMAT_VERSION`)
    One uncompressed ``.npz`` (NumPy's zip of ``.npy`` arrays, read with
    ``allow_pickle=False``). The array ``header`` holds UTF-8 JSON:
    ``format`` (this version), ``meshcorr`` (the version that wrote it),
    ``settings`` (:data:`SHAPE_SETTING_NAMES` and the resolved ``mode``),
    ``mesh_sha256`` (:func:`mesh_digest`), ``name``, ``n_original``,
    ``cloud`` (whether the shape is a point cloud: then ``faces`` is empty,
    shape ``(0, 3)``; format 2 on), ``n_caps`` (vertices added to close
    holes, :mod:`meshcorr.core.holes`; format 3 on) and
    ``entries``, the structure of the cached values: ``{"array": NAME}``,
    ``{"tuple": [...]}``, ``{"float"|"int"|"bool"|"str": value}``,
    ``{"kdtree": NAME}`` (a :class:`scipy.spatial.cKDTree` rebuilt from its
    points) or ``{"orientation": {...}}``. Arrays: ``vertices``, ``faces``,
    ``kept``, ``spectrum.eigenvalues``, ``spectrum.embedding``,
    ``spectrum.row_vertices`` / ``spectrum.rows`` (the scalable mode's
    geodesic rows) and ``cache.N`` for the cached values.
    :meth:`PreparedShape.load` refuses a file of another format or meshcorr
    version, and, when asked to check, one made for another mesh or other
    settings (:class:`~meshcorr.errors.PreparedShapeError`).
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import zipfile
from dataclasses import fields

import numpy as np
from scipy.spatial import cKDTree

from ..errors import PreparedShapeError
from ..core.holes import fill_holes
from ..core.mesh import Mesh, MeshLike, as_mesh
from ..spectral.modes import build_spectrum
from ..core.orientation import Orientation
from ..spectral.spectrum import Spectrum, dense_rows
from ..runtime.timing import StageTimer

#: Version of the file format of :meth:`PreparedShape.save` (2: point clouds, the header's ``cloud``;
#: 3: holes closed, the header's ``n_caps`` and the setting ``fill_holes``).
FORMAT_VERSION = 3
#: The settings of :func:`meshcorr.match` that change what :func:`meshcorr.prepare` computes, in the
#: order prepared-shape files and cache keys record them (their defaults and checks:
#: :class:`meshcorr.Settings`, the dict: :func:`meshcorr.pipeline.settings.shape_settings`).
SHAPE_SETTING_NAMES = ("k", "geodesic", "scale_eigenvalues", "n_samples", "refine", "refine_k",
                       "largest_component", "random_state", "fill_holes")


def mesh_digest(mesh: Mesh) -> str:
    """SHA-256 (hex) of a validated mesh: vertices, faces, kept vertices and the input vertex count."""
    digest = hashlib.sha256()
    for array in (mesh.vertices, mesh.faces, mesh.kept):
        digest.update(str(array.dtype).encode() + str(array.shape).encode())
        digest.update(np.ascontiguousarray(array).tobytes())
    digest.update(str(mesh.n_original).encode())
    return digest.hexdigest()


class PreparedShape:
    """One mesh with everything per shape that :func:`meshcorr.match` needs, for fixed settings.

    Made by :func:`meshcorr.prepare` or :meth:`load`; pass it to :func:`meshcorr.match`
    in place of a mesh. Treat it as immutable: its arrays are read-only.

    Attributes
    ----------
    mesh : Mesh
        The validated mesh; its cache holds the per-shape data.
    spectrum : Spectrum
        Steps 1-3: embedding ``(n, k - 1)``, eigenvalues ``(k,)``, geodesic rows.
    settings : dict
        :data:`SHAPE_SETTING_NAMES` it was made for, and the resolved ``mode``.
    """

    def __init__(self, mesh: Mesh, spectrum: Spectrum, settings: dict) -> None:
        self.mesh = mesh
        self.spectrum = spectrum
        self.settings = dict(settings, mode=spectrum.mode)

    @property
    def n_vertices(self) -> int:
        return self.mesh.n_vertices

    @property
    def digest(self) -> str:
        """:func:`mesh_digest` of the mesh."""
        return mesh_digest(self.mesh)

    def check(self, settings: dict, mode: str | None = None, *, role: str = "shape") -> None:
        """Refuse settings (or a ``mode``) other than those it was made for (those given: some may be left out).

        Raises
        ------
        PreparedShapeError
            Naming each differing option, its prepared value and the one asked for.
        """
        wanted = dict(settings, mode=self.settings["mode"] if mode is None else mode)
        if wanted["mode"] == "dense":  # the sample count only matters to the scalable mode
            wanted["n_samples"] = self.settings["n_samples"]
        differ = [f"{key}={self.settings.get(key)!r} (asked: {wanted[key]!r})"
                  for key in sorted(wanted) if self.settings.get(key) != wanted[key]]
        if differ:
            holes = (" (partial matching and one-to-one maps keep the holes: prepare with fill_holes=False)"
                     if self.settings.get("fill_holes") and not wanted.get("fill_holes", True) else "")
            raise PreparedShapeError(
                f"The prepared {role} {self.mesh.name!r} was made with other settings: {', '.join(differ)}. "
                f"Prepare it again with these settings (meshcorr.prepare){holes} or match with the settings "
                "it was prepared for.")

    def save(self, path) -> None:
        """Write it to ``path`` (``.npz``, the format in the module docstring), atomically."""
        payload = self.to_bytes()
        from ..io import atomic_write  # meshcorr.io imports trimesh: not at `import meshcorr`

        atomic_write(path, lambda file: file.write(payload))

    def to_bytes(self) -> bytes:
        """The file :meth:`save` writes, as bytes."""
        arrays: dict[str, np.ndarray] = {"vertices": self.mesh.vertices, "faces": self.mesh.faces,
                                         "kept": self.mesh.kept,
                                         "spectrum.eigenvalues": self.spectrum.eigenvalues,
                                         "spectrum.embedding": self.spectrum.embedding}
        rows = dict(self.spectrum.rows)
        vertices = np.array(sorted(rows), dtype=np.int64)
        arrays["spectrum.row_vertices"] = vertices
        arrays["spectrum.rows"] = (np.stack([rows[int(i)] for i in vertices]) if len(vertices)
                                   else np.zeros((0, self.n_vertices)))
        # Values of a type _encode has no rule for are left out: they are recomputed when needed.
        entries = [[list(key), spec] for key, value in list(self.mesh.store.items())
                   if (spec := _encode(value, arrays)) is not _SKIP and not _contains(spec, _SKIP)]
        header = dict(format=FORMAT_VERSION, meshcorr=meshcorr_version(), settings=self.settings,
                      mesh_sha256=self.digest, name=self.mesh.name, n_original=self.mesh.n_original,
                      n_caps=self.mesh.n_caps, cloud=self.mesh.is_cloud,
                      max_geodesic=self.spectrum.max_geodesic, entries=entries)
        arrays["header"] = np.frombuffer(json.dumps(header).encode(), dtype=np.uint8)
        buffer = io.BytesIO()
        np.savez(buffer, **arrays)
        return buffer.getvalue()

    @classmethod
    def from_bytes(cls, payload: bytes) -> PreparedShape:
        """The inverse of :meth:`to_bytes` (checks the format and version as :meth:`load` does)."""
        return cls._from_arrays(*_read(io.BytesIO(payload), name="the prepared shape"))

    def __reduce__(self):
        # Pickled (e.g. sent between Dask workers) as its file: the geodesic solver is rebuilt on demand.
        return (PreparedShape.from_bytes, (self.to_bytes(),))

    @classmethod
    def load(cls, path, *, mesh: MeshLike | None = None, settings: dict | None = None) -> PreparedShape:
        """Read a file written by :meth:`save`.

        Parameters
        ----------
        path : str or PathLike
        mesh : mesh-like, optional
            Refuse the file unless it was made for this mesh (same
            :func:`mesh_digest` after validation).
        settings : dict, optional
            Refuse the file unless it was made with these settings
            (:data:`SHAPE_SETTING_NAMES` keys, and ``mode`` if given).

        Raises
        ------
        PreparedShapeError
            Unreadable, another format or meshcorr version, another mesh or other settings.
        """
        header, arrays = _read(path)
        try:
            prepared = cls._from_arrays(header, arrays)
        except (KeyError, ValueError, TypeError, IndexError, AttributeError) as exc:  # a header or array malformed
            raise PreparedShapeError(f"{path} is damaged ({type(exc).__name__}: {exc}); prepare the mesh again "
                                     "(meshcorr.prepare) or clear the cache (meshcorr cache clear).") from None
        if mesh is not None:
            other = _closed(as_mesh(mesh, largest_component=prepared.settings["largest_component"]),
                            prepared.settings)
            if mesh_digest(other) != header["mesh_sha256"]:
                raise PreparedShapeError(f"{path} was prepared for another mesh than {other.name}: prepare "
                                         "this mesh again (meshcorr.prepare) instead of loading that file.")
        if settings is not None:
            settings = dict(settings)
            prepared.check(settings, settings.pop("mode", None))
        return prepared

    @classmethod
    def _from_arrays(cls, header: dict, arrays) -> PreparedShape:
        mesh = Mesh(arrays["vertices"], arrays["faces"], name=header["name"], kept=arrays["kept"],
                    n_original=header["n_original"], n_caps=header["n_caps"])
        if bool(header.get("cloud")) != mesh.is_cloud:
            raise PreparedShapeError(f"The prepared shape {mesh.name!r} says it is "
                                     f"{'a point cloud' if header.get('cloud') else 'a mesh'} but holds "
                                     f"{len(mesh.faces)} faces: the file is damaged. Prepare the shape again.")
        for key, spec in header["entries"]:
            mesh.store.put(tuple(key), _decode(spec, arrays))
        settings = dict(header["settings"])
        sigma = float(header["max_geodesic"])
        if settings["mode"] == "dense":
            rows: dict = {}
            geodesics_from = dense_rows(mesh.geodesic_matrix(settings["geodesic"]), sigma)
        else:
            from ..spectral.nystrom import sampled_rows

            rows = {int(i): _read_only(row) for i, row in zip(arrays["spectrum.row_vertices"],
                                                                arrays["spectrum.rows"])}
            geodesics_from = sampled_rows(mesh, settings["geodesic"], rows, sigma)
        spectrum = Spectrum(_read_only(arrays["spectrum.eigenvalues"]), _read_only(arrays["spectrum.embedding"]),
                            geodesics_from, sigma, mode=settings.pop("mode"), rows=rows)
        return cls(mesh, spectrum, settings)

    def __repr__(self) -> str:
        s = self.settings
        return (f"PreparedShape(name={self.mesh.name!r}, n_vertices={self.n_vertices}, mode={s['mode']!r}, "
                f"k={s['k']}, geodesic={s['geodesic']!r}, random_state={s['random_state']!r})")


def load_mesh(shape: MeshLike, settings: dict, *, name: str | None) -> Mesh:
    """The validated :class:`Mesh` of user input, with enough vertices for ``settings["k"]``.

    Its holes are closed (:func:`meshcorr.core.holes.fill_holes`) when ``settings["fill_holes"]``.
    """
    k = settings["k"]
    mesh = as_mesh(shape, name=name, largest_component=settings["largest_component"], min_vertices=k + 2,
                   reason=f"the spectral embedding with k={k} (-k) needs k + 2 vertices")
    return _closed(mesh, settings)


def _closed(mesh: Mesh, settings: dict) -> Mesh:
    """``mesh`` with its holes closed (:func:`meshcorr.core.holes.fill_holes`) when ``settings["fill_holes"]``."""
    return fill_holes(mesh) if settings["fill_holes"] else mesh


def prepare_mesh(mesh: Mesh, settings: dict, mode: str, timer: StageTimer | None = None) -> PreparedShape:
    """:func:`meshcorr.prepare` of a validated mesh in a resolved ``mode`` ("dense" or "scalable")."""
    shape = PreparedShape(mesh, shape_spectrum(mesh, settings, mode, timer or StageTimer()), settings)
    warm(mesh, shape.spectrum, settings)
    return shape


def shape_spectrum(mesh: Mesh, settings: dict, mode: str, timer: StageTimer) -> Spectrum:
    """Steps 1-3 on one mesh (:func:`meshcorr.spectral.modes.build_spectrum`) with the per-shape settings."""
    return build_spectrum(mesh, mode, k=settings["k"], geodesic=settings["geodesic"],
                          scale=settings["scale_eigenvalues"], n_samples=settings["n_samples"],
                          random_state=settings["random_state"], timer=timer)


def warm(mesh: Mesh, spectrum: Spectrum, settings: dict) -> None:
    """Fill the mesh's cache (and the spectrum's geodesic rows) with the per-shape data of a pair.

    The orientation and curvature scores of a map onto the mesh itself fill
    exactly the cache entries that scoring a pair's candidates reads, in
    both roles (source and target), with the pipeline's own parameters
    (the orientation sample, its neighbourhoods and regions, the curvature
    table of :func:`meshcorr.choice.curvature.mapped_curvature`); the extremities
    (:mod:`meshcorr.choice.extremities`) and the seeded sources of the metric
    distortion (:func:`meshcorr.choice.selection.distortion_sources`) leave their
    geodesic rows in ``spectrum.rows``. A new per-shape quantity is one more
    line here.
    """
    from ..choice.curvature import curvature_disagreement
    from ..choice.extremities import spectrum_extremities
    from ..core.map_orientation import orientation_scores
    from ..stages.anchors import embedding_spread
    from ..spectral.basis import laplace_basis
    from ..choice.selection import distortion_sources

    seed = settings["random_state"]
    identity = np.arange(mesh.n_vertices)
    orientation_scores(mesh, mesh, identity, random_state=seed)  # sample, neighbourhoods, regions
    curvature_disagreement(mesh, mesh, identity, random_state=seed)
    spectrum_extremities(mesh, spectrum, random_state=seed)
    embedding_spread(spectrum)
    if seed is not None:  # the rows the whole-map choice's distortion reads on the source (meshcorr.choice.selection)
        for i in distortion_sources(mesh.n_vertices, seed):
            spectrum.geodesics_from(int(i))
    if settings["refine"]:
        laplace_basis(mesh, min(settings["refine_k"], mesh.n_vertices - 1), random_state=seed)


def pair_shapes(source: MeshLike | PreparedShape, target: MeshLike | PreparedShape, settings: dict
                ) -> tuple[Mesh | PreparedShape, Mesh | PreparedShape]:
    """Step "load" of :func:`meshcorr.match`: each input as a validated Mesh or a checked PreparedShape."""
    shapes = []
    for shape, role in ((source, "source"), (target, "target")):
        if isinstance(shape, PreparedShape):
            shape.check(settings, role=role)
            shapes.append(shape)
        else:
            # A file is named by its path in messages; arrays and objects by their role.
            shapes.append(load_mesh(shape, settings, name=None if isinstance(shape, (str, os.PathLike)) else role))
    return shapes[0], shapes[1]


def pair_spectrum(shape: Mesh | PreparedShape, settings: dict, mode: str, timer: StageTimer) -> Spectrum:
    """The spectrum of one shape of a pair in the pair's ``mode``: the prepared one, or computed now.

    Raises
    ------
    PreparedShapeError
        A shape prepared in another mode than the pair needs.
    """
    if isinstance(shape, PreparedShape):
        shape.check(settings, mode)
        return shape.spectrum
    return shape_spectrum(shape, settings, mode, timer)


def as_meshes(*shapes: Mesh | PreparedShape) -> list[Mesh]:
    """The :class:`Mesh` of each shape."""
    return [shape.mesh if isinstance(shape, PreparedShape) else shape for shape in shapes]


def meshcorr_version() -> str:
    """The version of meshcorr, written into (and required of) prepared-shape files and cache keys."""
    from .. import __version__

    return __version__


def _read_only(array: np.ndarray) -> np.ndarray:
    array = np.asarray(array)
    array.flags.writeable = False
    return array


def _read(path, *, name: str | None = None) -> tuple[dict, dict]:
    """Header and arrays of a prepared-shape file; refuses unreadable files and other versions."""
    name = name or str(path)
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {name: data[name] for name in data.files}
        # NumPy returns a member that is no .npy file as its raw bytes: a damaged file, not an AttributeError.
        raw = sorted(member for member, value in arrays.items() if not isinstance(value, np.ndarray))
        if raw:
            raise ValueError(f"its member {raw[0]!r} is not an array")
        header = json.loads(arrays.pop("header").tobytes().decode())
        version = header["format"]
    except FileNotFoundError:
        raise PreparedShapeError(f"{name} does not exist.") from None
    except (OSError, ValueError, KeyError, TypeError, AttributeError, UnicodeDecodeError, EOFError,
            zipfile.BadZipFile) as exc:
        # NumPy reads any file that is no archive as pickled data and advises allow_pickle: not for users.
        reason = "it is not an .npz archive" if "pickle" in str(exc) else exc
        raise PreparedShapeError(f"{name} is not a prepared shape written by meshcorr ({reason}); prepare the "
                                 "mesh again (meshcorr.prepare) or clear the cache (meshcorr cache clear).") from None
    if version != FORMAT_VERSION or header.get("meshcorr") != meshcorr_version():
        raise PreparedShapeError(
            f"{name} was written by meshcorr {header.get('meshcorr')} (format {version}); this is meshcorr "
            f"{meshcorr_version()} (format {FORMAT_VERSION}), whose results may differ. Prepare the mesh again or "
            "clear the cache (meshcorr cache clear).")
    return header, arrays


#: What :func:`_encode` returns for a value it has no rule for.
_SKIP = object()


def _contains(spec, item) -> bool:
    if spec is item:
        return True
    if isinstance(spec, dict):
        return any(_contains(v, item) for v in spec.values())
    if isinstance(spec, list):
        return any(_contains(v, item) for v in spec)
    return False


def _encode(value, arrays: dict):
    """The JSON structure of a cached value; its arrays go into ``arrays`` as ``cache.N``."""
    def stash(array) -> str:
        name = f"cache.{len(arrays)}"
        arrays[name] = np.asarray(array)
        return name

    if isinstance(value, np.ndarray):
        return {"array": stash(value)}
    if isinstance(value, cKDTree):
        return {"kdtree": stash(value.data)}
    if isinstance(value, Orientation):
        return {"orientation": {f.name: _encode(getattr(value, f.name), arrays) for f in fields(value)}}
    if isinstance(value, tuple):
        return {"tuple": [_encode(item, arrays) for item in value]}
    for kind, types in (("bool", (bool, np.bool_)), ("int", (int, np.integer)), ("float", (float, np.floating)),
                        ("str", str)):
        if isinstance(value, types):
            return {kind: {"bool": bool, "int": int, "float": float, "str": str}[kind](value)}
    return _SKIP


def _decode(spec: dict, arrays):
    (kind, value), = spec.items()
    if kind == "array":
        return _read_only(arrays[value])
    if kind == "kdtree":
        return cKDTree(arrays[value])
    if kind == "orientation":
        return Orientation(**{name: _decode(item, arrays) for name, item in value.items()})
    if kind == "tuple":
        return tuple(_decode(item, arrays) for item in value)
    return value
