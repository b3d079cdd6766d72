"""The paper's pictures: colour transfer through a map, eigenvectors, the spectral embedding.

- :func:`correspondence_figure` -- the target coloured by part, the source
  coloured through the map (Jain & Zhang 2006, Figures 7-8); optionally the
  ground-truth colouring, or each source vertex's geodesic error.
- :func:`spectrum_figure` -- the first eigenvectors of the Gaussian affinity
  matrix as colour plots with their eigenvalues (Figure 6), and the 3-D
  spectral embedding drawn as a mesh (Figure 2).
"""

from __future__ import annotations

from contextlib import contextmanager, nullcontext

import numpy as np

from ..runtime.checks import check_int
from ..spectral.embedding import gaussian_affinity, top_eigenpairs
from ..errors import ParameterError
from ..evaluation.metrics import GeodesicCache, geodesic_errors
from ..core.mesh import as_mesh
from ..runtime.progress import as_progress
from ..maps.transfer import check_map, pull_back
from ..maps.colors import UNMAPPED_COLOR, mesh_coloring, scalar_colors
from .render import Panel, render_panels
from ..core.geodesics import DEFAULT_GEODESIC

__all__ = ["correspondence_errors", "correspondence_figure", "spectrum_figure"]


def correspondence_errors(target, mapping: np.ndarray, truth: np.ndarray, *,
                          geodesic: str = DEFAULT_GEODESIC, cache: GeodesicCache | None = None,
                          progress=None) -> np.ndarray:
    """Geodesic error of each source vertex, normalised by sqrt(target area).

    Parameters
    ----------
    target : (vertices, faces) or mesh-like
        The mesh the maps point into (validated: one component, manifold).
    mapping, truth : (n_source,) int
        Predicted and true target vertex of each source vertex (-1: none).
    geodesic : str
        Geodesic solver.
    cache : GeodesicCache, optional
        Reuse geodesic rows across calls (its solver must be ``geodesic``);
        e.g. the one given to :func:`meshcorr.evaluation.metrics.evaluate_map` for
        the same target.
    progress : callable or bool, optional
        ``progress("geodesic errors", done, total)`` as the single-source
        solves advance (``done`` of ``total`` solves, from 0 to ``total``;
        nothing when every row is cached), or True for a progress bar. The
        errors are the same with or without it.

    Returns
    -------
    errors : (n_source,) float
        NaN where either map leaves the vertex unmapped.
    """
    progress = as_progress(progress)
    mapping, truth = np.asarray(mapping), np.asarray(truth)
    both = (mapping >= 0) & (truth >= 0)
    errors = np.full(len(mapping), np.nan)
    if both.any():
        mesh = as_mesh(target, name="target")
        if progress is not None:  # the solves report through the cache (a cache passed in keeps the rows)
            cache = cache if cache is not None else GeodesicCache(geodesic)
        with nullcontext() if progress is None else cache.reporting(progress):
            errors[both] = geodesic_errors(mesh, mapping[both], truth[both], method=geodesic, cache=cache)
    return errors


@contextmanager
def _stage(progress, name: str):
    """Report a stage without sub-steps: ``(name, 0, 1)`` before it, ``(name, 1, 1)`` once done."""
    if progress is not None:
        progress(name, 0, 1)
    yield
    if progress is not None:
        progress(name, 1, 1)


def _vertices_faces(mesh, name: str) -> tuple[np.ndarray, np.ndarray]:
    """``(V, F)`` of a ``(vertices, faces)`` pair as given, or of anything :func:`meshcorr.as_mesh` reads."""
    if isinstance(mesh, (tuple, list)) and len(mesh) == 2:
        return np.asarray(mesh[0]), np.asarray(mesh[1])
    converted = as_mesh(mesh, name=name)
    return np.asarray(converted.vertices), np.asarray(converted.faces)


def correspondence_figure(source, target, mapping, path, *, truth=None, error: bool = False,
                          coloring: str = "parts", geodesic: str = DEFAULT_GEODESIC, elev: float = 30.0,
                          azim: float = -60.0, up: str = "z", dpi: int = 100,
                          map_name: str = "the map", cache: GeodesicCache | None = None,
                          progress=None) -> dict:
    """Picture of a vertex map by colour transfer, written as a PNG.

    The target is coloured by ``coloring``; source vertex ``i`` takes the
    colour of target vertex ``mapping[i]`` (grey where unmapped). With
    ``truth``, a second row shows the source coloured through the true
    map: the two source pictures agree where the map is right. With
    ``error``, the source is instead coloured by each vertex's geodesic
    error (blue: none; red: the largest), with a colour bar.

    Parameters
    ----------
    source, target : ((n1, 3) float, (m1, 3) int), path, trimesh.Trimesh or Mesh
        The two meshes, in any form :func:`meshcorr.match` takes.
    mapping : (n1,) int
        Target vertex of each source vertex, -1 where unmapped.
    path : str or path-like
        The PNG file.
    truth : (n1,) int, optional
        The true map; needed for ``error``.
    error : bool
        Colour the source by geodesic error instead of by transfer.
    coloring : {"parts", "xyz"}
        Colouring of the target (see :func:`meshcorr.maps.colors.mesh_coloring`).
    geodesic : str
        Geodesic solver for the errors.
    elev, azim, up, dpi
        Camera and resolution (see :func:`meshcorr.viz.render.render_panels`).
    map_name : str
        How error messages refer to the map (e.g. its file name).
    cache : GeodesicCache, optional
        Geodesic rows to reuse for the errors (its solver must be ``geodesic``).
    progress : callable or bool, optional
        ``progress(stage, done, total)`` as the long work advances, or True
        for a progress bar (:class:`meshcorr.runtime.progress.TqdmProgress`): the
        stage "geodesic errors" (with ``truth``; ``done`` of ``total``
        single-source solves, which take minutes on meshes of tens of
        thousands of vertices), then "drawing" (``0`` then ``1`` of ``1``).
        Nothing is printed; the picture is the same with or without it.

    Returns
    -------
    info : dict
        ``"mean_error"`` and ``"max_error"`` (sqrt-area normalised) when
        ``truth`` is given, else empty.

    Raises
    ------
    ParameterError
        If a map does not fit the meshes, or ``error`` is set without ``truth``.
    """
    progress = as_progress(progress)
    (V1, F1), (V2, F2) = _vertices_faces(source, "source"), _vertices_faces(target, "target")
    target = (V2, F2)
    mapping = check_map(mapping, len(V1), len(V2), name=map_name)
    if truth is not None:
        truth = check_map(truth, len(V1), len(V2), name="the ground truth")
    elif error:
        raise ParameterError("The error picture needs the ground-truth map: give --gt GT.")
    target_colors = mesh_coloring(coloring, V2, F2)
    n_mapped = int((mapping >= 0).sum())
    target_panel = Panel(V2, F2, target_colors, f"target ({len(V2)} vertices), coloured by {coloring}")
    info: dict = {}
    if truth is not None:
        errors = correspondence_errors(target, mapping, truth, geodesic=geodesic, cache=cache,
                                       progress=progress)
        if np.isfinite(errors).any():
            info = {"mean_error": float(np.nanmean(errors)), "max_error": float(np.nanmax(errors))}
    if error:
        vmax = info.get("max_error", 0.0) or 1.0
        source_panel = Panel(
            V1, F1, scalar_colors(errors, "error", vmin=0.0, vmax=vmax),
            f"source: geodesic error (mean {info.get('mean_error', float('nan')):.3f})",
            colorbar={"cmap": "error", "vmin": 0.0, "vmax": vmax, "label": "error / sqrt(area)"},
        )
        panels = [source_panel, target_panel]
    else:
        mapped_colors = pull_back(target_colors, mapping, fill=UNMAPPED_COLOR)
        panels = [Panel(V1, F1, mapped_colors,
                        f"source through the map ({n_mapped}/{len(V1)} mapped)"), target_panel]
        if truth is not None:
            true_colors = pull_back(target_colors, truth, fill=UNMAPPED_COLOR)
            panels += [Panel(V1, F1, true_colors, "source through the ground truth"), target_panel]
    footer = None
    if info:
        footer = f"geodesic error / sqrt(area): mean {info['mean_error']:.4f}, max {info['max_error']:.4f}"
    with _stage(progress, "drawing"):
        render_panels(panels, path, ncols=2, elev=elev, azim=azim, up=up, dpi=dpi, footer=footer)
    return info


def affinity_eigenpairs(vertices, faces, k: int, *, geodesic: str = DEFAULT_GEODESIC,
                        random_state: int | None = 0, progress=None) -> tuple[np.ndarray, np.ndarray]:
    """Top ``k`` eigenpairs of a mesh's Gaussian geodesic affinity matrix.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
    k : int
    geodesic : str
    random_state : int or None
    progress : callable or bool, optional
        ``progress(stage, done, total)``: "geodesics" (``done`` of ``n``
        single-source solves, from 0 to ``n``), then "eigenvectors" (``0``
        then ``1`` of ``1``); or True for a progress bar.

    Returns
    -------
    eigenvalues : (k,) float
        Descending.
    eigenvectors : (n, k) float
        Unit columns, signs by :func:`meshcorr.spectral.embedding.sign_convention`.
    """
    progress = as_progress(progress)
    mesh = as_mesh((vertices, faces), name="mesh", min_vertices=k + 2,
                   reason=f"{k} eigenvectors need at least {k + 2} vertices.")
    reported = [0]

    def solves(done: int, total: int) -> None:
        reported[0] = done
        progress("geodesics", done, total)

    if progress is not None:
        progress("geodesics", 0, mesh.n_vertices)
    D = np.array(mesh.geodesic_matrix(geodesic, progress=None if progress is None else solves))
    if progress is not None and reported[0] < mesh.n_vertices:  # "dijkstra" solves all rows at once
        progress("geodesics", mesh.n_vertices, mesh.n_vertices)
    with _stage(progress, "eigenvectors"):
        return top_eigenpairs(gaussian_affinity(D, overwrite=True), k, random_state=random_state)


def spectrum_figure(vertices, faces, path, *, n_eigenvectors: int = 6, geodesic: str = DEFAULT_GEODESIC,
                    scale: bool = True, random_state: int | None = 0, elev: float = 30.0,
                    azim: float = -60.0, up: str = "z", dpi: int = 100, progress=None) -> np.ndarray:
    """Eigenvectors and spectral embedding of a mesh, written as a PNG.

    The first panel is the mesh coloured by part; the second is the 3-D
    spectral embedding drawn as a mesh (each vertex moved to
    ``(u_2, u_3, u_4)``, scaled by ``sqrt(lambda)`` when ``scale``; same
    faces and colours; the paper's Figure 2). The following panels show
    eigenvectors ``u_1 .. u_n`` of the Gaussian affinity matrix (blue
    negative, red positive, white 0) with their eigenvalues (Figure 6); the
    first 8 eigenvalues are listed under the grid.

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
    path : str or path-like
        The PNG file.
    n_eigenvectors : int
        Eigenvectors drawn (>= 1).
    geodesic : str
        Geodesic solver.
    scale : bool
        Scale the embedding by sqrt(eigenvalue), as the matcher does.
    random_state : int or None
        Seed of the eigensolver's start vector.
    elev, azim, up, dpi
        Camera and resolution (see :func:`meshcorr.viz.render.render_panels`).
    progress : callable or bool, optional
        ``progress(stage, done, total)`` as the long work advances, or True
        for a progress bar (:class:`meshcorr.runtime.progress.TqdmProgress`): the
        stages "geodesics" (``done`` of ``n`` single-source solves: the
        ``n x n`` geodesic matrix, minutes on meshes of several thousand
        vertices), "eigenvectors" and "drawing" (``0`` then ``1`` of ``1``).
        Nothing is printed; the picture is the same with or without it.

    Returns
    -------
    eigenvalues : (max(n_eigenvectors, 8),) float
        Descending.
    """
    n_eigenvectors = check_int("n_eigenvectors", n_eigenvectors, minimum=1, maximum=30)
    progress = as_progress(progress)
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64)
    k = max(n_eigenvectors, 8)
    values, vectors = affinity_eigenpairs(vertices, faces, k, geodesic=geodesic,
                                          random_state=random_state, progress=progress)
    colors = mesh_coloring("parts", vertices, faces)
    embedding = vectors[:, 1:4]
    if scale:
        embedding = embedding * np.sqrt(np.clip(values[1:4], 0.0, None))
    panels = [Panel(vertices, faces, colors, f"mesh ({len(vertices)} vertices)"),
              Panel(embedding, faces, colors, "spectral embedding (u2, u3, u4)")]
    for j in range(n_eigenvectors):
        u = vectors[:, j]
        bound = float(np.abs(u).max()) or 1.0
        panels.append(Panel(vertices, faces, scalar_colors(u, "coolwarm", vmin=-bound, vmax=bound),
                            f"u{j + 1}, \N{GREEK SMALL LETTER LAMDA} = {values[j]:.4g}"))
    listed = ", ".join(f"{v:.4g}" for v in values[:8])
    with _stage(progress, "drawing"):
        render_panels(panels, path, ncols=4, elev=elev, azim=azim, up=up, dpi=dpi, panel_size=(3.2, 2.8),
                      footer=f"eigenvalues \N{GREEK SMALL LETTER LAMDA}1..8: {listed}")
    return values
