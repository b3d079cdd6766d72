"""A correspondence inside a notebook: both meshes side by side, linked by colour.

The target is coloured (by part, by coordinates, or by given colours) and
each source vertex takes the colour of its image, as in the paper's
figures; the two meshes are interactive plotly ``Mesh3d`` views (each
rotates on its own; both start from the same camera). plotly is an optional dependency
(``pip install meshcorr[notebook]``): a figure displays itself in Jupyter,
VS Code and Colab, and :meth:`plotly.graph_objects.Figure.write_html`
saves it as a page; it needs no display or GPU (headless machines work).
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..core.mesh import Mesh, MeshLike, as_mesh

__all__ = ["show", "require_plotly"]


def require_plotly():
    """The plotly graph-objects module, or a :class:`ParameterError` saying how to install it."""
    try:
        import plotly.graph_objects as go
    except ImportError as exc:
        raise ParameterError("Notebook views need plotly: pip install 'meshcorr[notebook]'.") from exc
    return go


def _mesh3d(go, mesh: Mesh, colors: np.ndarray, name: str, scene: str):
    """A plotly ``Mesh3d`` trace of a mesh, or a ``Scatter3d`` of dots for a point cloud."""
    v, f = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    hex_colors = [f"rgb({r},{g},{b})" for r, g, b in np.asarray(colors, dtype=int)]
    if mesh.is_cloud:
        return go.Scatter3d(x=v[:, 0], y=v[:, 1], z=v[:, 2], mode="markers", name=name, scene=scene,
                            marker=dict(size=2.5, color=hex_colors), hoverinfo="name")
    return go.Mesh3d(x=v[:, 0], y=v[:, 1], z=v[:, 2], i=f[:, 0], j=f[:, 1], k=f[:, 2],
                     vertexcolor=hex_colors, name=name, scene=scene, flatshading=False,
                     lighting=dict(ambient=0.55, diffuse=0.6, specular=0.1), hoverinfo="name")


def show(source: MeshLike, target: MeshLike, mapping, *, coloring: str = "parts", colors=None,
         height: int = 420, titles: tuple[str, str] = ("source (through the map)", "target")):
    """Source and target side by side, the source coloured through the map.

    Parameters
    ----------
    source, target : path, trimesh.Trimesh, Mesh, (vertices, faces) or (n, 3) points
    mapping : (n_source,) int or Correspondence
        Target vertex of each source vertex (-1 = unmapped, drawn grey), in
        the numbering of these meshes.
    coloring : {"parts", "xyz"}
        The target's colouring (:func:`meshcorr.maps.colors.mesh_coloring`).
    colors : (n_target, 3) uint8, optional
        Target colours to use instead.
    height : int
        Figure height in pixels.
    titles : (str, str)

    Returns
    -------
    figure : plotly.graph_objects.Figure
        Two ``Mesh3d`` traces (source, target; a point cloud: a ``Scatter3d``
        of dots) in two 3-D scenes; displays itself in a notebook.

    Raises
    ------
    ParameterError
        Without plotly, or a map that does not fit the meshes.
    """
    from ..maps.transfer import check_map, pull_back
    from ..maps.colors import UNMAPPED_COLOR, mesh_coloring

    go = require_plotly()
    src = source if isinstance(source, Mesh) else as_mesh(source, name="source")
    tgt = target if isinstance(target, Mesh) else as_mesh(target, name="target")
    if hasattr(mapping, "local_map"):
        mapping = mapping.local_map()
    mapping = check_map(mapping, src.n_vertices, tgt.n_vertices)
    if colors is None:
        colors = mesh_coloring(coloring, tgt.vertices, tgt.faces)
    colors = np.asarray(colors)
    if colors.shape != (tgt.n_vertices, 3):
        raise ParameterError(f"colors must be one RGB row per target vertex, ({tgt.n_vertices}, 3); "
                             f"got shape {colors.shape}.")
    pulled = pull_back(colors, mapping, fill=UNMAPPED_COLOR)
    from plotly.subplots import make_subplots

    fig = make_subplots(rows=1, cols=2, specs=[[{"type": "scene"}, {"type": "scene"}]],
                        subplot_titles=list(titles), horizontal_spacing=0.02)
    fig.add_trace(_mesh3d(go, src, pulled, "source", "scene"), row=1, col=1)
    fig.add_trace(_mesh3d(go, tgt, colors, "target", "scene2"), row=1, col=2)
    axes = dict(visible=False)
    scene = dict(xaxis=axes, yaxis=axes, zaxis=axes, aspectmode="data")
    fig.update_layout(scene=scene, scene2=scene, height=height, margin=dict(l=0, r=0, t=30, b=0),
                      showlegend=False)
    return fig
