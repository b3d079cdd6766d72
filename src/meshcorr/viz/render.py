"""Headless static pictures of coloured meshes (PNG) with matplotlib's Agg back end.

Each mesh is drawn by projecting it orthographically, sorting its faces back
to front (painter's algorithm) and filling them as 2-D polygons with a
Lambert-shaded face colour (the mean of its vertices' colours). This needs
no display, no GPU and no OpenGL, only ``pip install meshcorr[plot]``
(matplotlib); measured ~0.1-0.3 s per mesh of a few thousand faces. A
point cloud (no faces) is drawn as dots sorted back to front, darker with
depth. It does not use ``mplot3d``, whose per-axes 3-D machinery is slower and whose
aspect handling distorts meshes; a 2-D ``PolyCollection`` in an equal-aspect
axes is all a fixed view needs.

Camera convention (the same for every panel): the view direction is given
by an elevation and an azimuth in degrees around an "up" axis, as in
matplotlib (``elev=30, azim=-60`` by default, ``up="z"``); each panel is
then fitted to its own mesh.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..runtime.checks import check_choice, check_float
from ..errors import ParameterError
from ..io import atomic_write
from ..maps.colors import COLORMAPS

__all__ = ["Panel", "camera_frame", "render_panels"]

_UP_AXES = ("x", "y", "z")


@dataclass
class Panel:
    """One mesh drawing in a picture.

    Attributes
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int
        ``m = 0`` for a point cloud, drawn as dots.
    colors : (n, 3) uint8
        Per-vertex RGB colour.
    title : str
    colorbar : dict, optional
        ``{"cmap": name in COLORMAPS, "vmin": float, "vmax": float,
        "label": str}``: draw a colour bar under the panel.
    """

    vertices: np.ndarray
    faces: np.ndarray
    colors: np.ndarray
    title: str = ""
    colorbar: dict | None = field(default=None)


def _require_matplotlib():
    from .plots import require_matplotlib

    require_matplotlib()  # a clear ParameterError when matplotlib is missing
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    return Figure, FigureCanvasAgg


def camera_frame(elev: float, azim: float, up: str = "z") -> np.ndarray:
    """Rows ``(right, up, towards the viewer)`` of the view, in world coordinates.

    Parameters
    ----------
    elev, azim : float
        Degrees. ``elev`` is the angle above the plane normal to ``up``;
        ``azim`` turns the viewer about ``up`` (matplotlib's convention
        for ``up="z"``).
    up : {"x", "y", "z"}
        The world axis drawn pointing up.

    Returns
    -------
    frame : (3, 3) float
        Orthonormal, right-handed; ``vertices @ frame.T`` gives screen
        ``x``, screen ``y`` and depth (larger is nearer).
    """
    check_choice("up", up, _UP_AXES)
    e, a = np.radians(elev), np.radians(azim)
    eye = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    right = np.array([-np.sin(a), np.cos(a), 0.0])
    frame = np.stack([right, np.cross(eye, right), eye])
    # Rename world axes so that the chosen one plays the role of z (cyclic: stays right-handed).
    shift = {"z": 0, "x": 1, "y": 2}[up]
    return np.roll(frame, shift, axis=1)


def _shaded_polygons(vertices, faces, colors, frame):
    """Projected triangles sorted far to near, with Lambert-shaded RGB colours in [0, 1]."""
    projected = vertices @ frame.T
    tri = projected[faces]  # (m, 3, 3)
    order = np.argsort(tri[:, :, 2].mean(axis=1), kind="stable")
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-300)
    light = np.array([-0.35, 0.45, 1.0])
    light /= np.linalg.norm(light)
    # Two-sided: open meshes and inconsistent orientation still read.
    shade = 0.35 + 0.65 * np.abs(normals @ light)
    face_rgb = colors[faces].astype(np.float64).mean(axis=1) / 255.0
    face_rgb = np.clip(face_rgb * shade[:, None], 0.0, 1.0)
    return tri[order, :, :2], face_rgb[order]


def _shaded_points(vertices, colors, frame):
    """Projected points sorted far to near, with depth-cued RGB colours in [0, 1] (a cloud has no normals)."""
    projected = vertices @ frame.T
    order = np.argsort(projected[:, 2], kind="stable")
    depth = projected[:, 2]
    span = float(np.ptp(depth)) or 1.0
    shade = 0.55 + 0.45 * (depth - depth.min()) / span  # nearer is brighter
    rgb = np.clip(colors.astype(np.float64) / 255.0 * shade[:, None], 0.0, 1.0)
    return projected[order, :2], rgb[order]


def _draw_panel(fig, ax, panel: Panel, frame: np.ndarray) -> None:
    from matplotlib.collections import PolyCollection

    vertices = np.asarray(panel.vertices, dtype=np.float64)
    faces = np.asarray(panel.faces, dtype=np.int64)
    colors = np.asarray(panel.colors)
    if colors.shape != (len(vertices), 3):
        raise ParameterError(
            f"Panel colours must have shape ({len(vertices)}, 3), one RGB per vertex. "
            f"Got {colors.shape} instead."
        )
    if faces.size == 0:  # a point cloud: dots, about as many pixels per point as the panel allows
        xy, rgb = _shaded_points(vertices, colors, frame)
        ax.scatter(xy[:, 0], xy[:, 1], c=rgb, s=float(np.clip(6000.0 / max(len(xy), 1), 0.5, 12.0)),
                   marker="o", linewidths=0)
    else:
        polygons, face_rgb = _shaded_polygons(vertices, faces, colors, frame)
        # Edges in the face colour hide the hairline seams anti-aliasing leaves between faces.
        ax.add_collection(PolyCollection(polygons, facecolors=face_rgb, edgecolors=face_rgb,
                                         linewidths=0.3, antialiased=True))
        xy = polygons.reshape(-1, 2)
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    pad = 0.04 * float(max(hi - lo)) + 1e-12
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.set_axis_off()
    if panel.title:
        ax.set_title(panel.title, fontsize=10)


def _draw_colorbar(fig, ax, bar: dict | None) -> None:
    """A horizontal colour bar under ``ax`` (added after the layout, which it would upset)."""
    if bar:
        from matplotlib.cm import ScalarMappable
        from matplotlib.colors import LinearSegmentedColormap, Normalize

        stops = np.asarray(COLORMAPS[bar["cmap"]], dtype=np.float64) / 255.0
        cmap = LinearSegmentedColormap.from_list(bar["cmap"], stops)
        mappable = ScalarMappable(norm=Normalize(bar["vmin"], bar["vmax"]), cmap=cmap)
        cb = fig.colorbar(mappable, ax=ax, orientation="horizontal", fraction=0.05, pad=0.02,
                          shrink=0.8)
        cb.set_label(bar.get("label", ""), fontsize=8)
        cb.ax.tick_params(labelsize=7)


def render_panels(panels: list[Panel], path, *, ncols: int = 2, elev: float = 30.0,
                  azim: float = -60.0, up: str = "z", panel_size: tuple[float, float] = (4.0, 3.4),
                  dpi: int = 100, title: str | None = None, footer: str | None = None) -> None:
    """Draw meshes in a grid and write the picture as a PNG, atomically.

    Parameters
    ----------
    panels : list of Panel
        Filled row by row.
    path : str or path-like
        The PNG file.
    ncols : int
        Panels per row.
    elev, azim : float
        View direction in degrees, the same for every panel (see
        :func:`camera_frame`).
    up : {"x", "y", "z"}
        World axis drawn pointing up.
    panel_size : (float, float)
        Inches per panel; with ``dpi`` sets the picture size.
    dpi : int
    title, footer : str, optional
        Text above and below the grid.

    Raises
    ------
    ParameterError
        If matplotlib is missing, a view parameter is invalid, or the
        folder of ``path`` does not exist.
    """
    elev = check_float("elev", elev, minimum=-90.0, maximum=90.0)
    azim = check_float("azim", azim)
    if not panels:
        raise ParameterError("render_panels needs at least one panel.")
    Figure, FigureCanvasAgg = _require_matplotlib()
    frame = camera_frame(elev, azim, up)
    ncols = max(1, min(ncols, len(panels)))
    nrows = -(-len(panels) // ncols)
    width, height = panel_size
    extra = (0.35 if title else 0.0) + (0.35 if footer else 0.0)
    # Constrained layout makes room for titles, colour bars and the footer.
    fig = Figure(figsize=(width * ncols, height * nrows + extra), dpi=dpi, facecolor="white",
                 layout="constrained")
    FigureCanvasAgg(fig)
    axes = []
    for number, panel in enumerate(panels):
        axes.append(fig.add_subplot(nrows, ncols, number + 1))
        _draw_panel(fig, axes[-1], panel, frame)
    if title:
        fig.suptitle(title, fontsize=11)
    if footer:
        fig.supxlabel(footer, fontsize=8, family="monospace")
    for ax, panel in zip(axes, panels):
        _draw_colorbar(fig, ax, panel.colorbar)
    atomic_write(path, lambda file: fig.savefig(file, format="png", dpi=dpi, facecolor="white"))
