"""A self-contained interactive HTML report of one correspondence (numpy only).

The page holds everything it needs: the meshes, their colours and the
viewer (``viewer.js``, a few hundred lines of plain JavaScript shared with
the landmark picker of :mod:`meshcorr.viz.pick`, and ``report_viewer.js``,
inlined), so it opens offline in any browser. The source and target are
drawn side by side in two 2-D canvases (orthographic projection, faces
sorted back to front, two-sided Lambert shading; a point cloud as dots) that share one rotation
and zoom: dragging either view turns both, the mouse wheel zooms both. The target is coloured by part and the
source through the map, as in :func:`meshcorr.viz.figures.correspondence_figure`
(Jain & Zhang 2006, Figures 7-8). Below the views: the stage timings, the
chosen eigenvector configuration and its runner-up, and, with ground truth,
the cumulative geodesic error curve (inline SVG).

A canvas draws ~20 000 triangles per frame interactively; meshes with more
faces keep every ``ceil(m / max_faces)``-th face in the report (the
views show holes then; the numbers are computed on the full meshes).

The page sets ``document.body.dataset.status`` to ``"ok"`` once both views
are drawn, or to ``"error"`` with the messages in ``<pre id="errors">``;
opened with ``#selftest`` in the address it also drags the first view and
sets ``data-linked="yes"`` when both views turned together.
"""

from __future__ import annotations

import html
import json
from importlib import resources

import numpy as np

from ..runtime.checks import check_int
from ..io import atomic_write
from ..maps.transfer import check_map, pull_back
from ..maps.colors import UNMAPPED_COLOR, mesh_coloring
from .render import camera_frame

__all__ = ["mesh_payload", "report_html", "viewer_script", "write_report"]

_STYLE = """
body { font-family: system-ui, sans-serif; margin: 1.2em; color: #222; }
h1 { font-size: 1.3em; } h2 { font-size: 1.05em; margin-top: 1.4em; }
.views { display: flex; gap: 12px; flex-wrap: wrap; }
.views figure { margin: 0; } figcaption { font-size: 0.9em; text-align: center; }
canvas { border: 1px solid #ccc; cursor: grab; touch-action: none; }
table { border-collapse: collapse; font-size: 0.9em; }
td, th { border: 1px solid #ddd; padding: 2px 8px; text-align: right; }
th { background: #f0f0f0; } td.l, th.l { text-align: left; }
#errors { display: none; color: #a00; background: #fee; padding: 0.5em; }
.note { font-size: 0.85em; color: #555; }
"""


def viewer_script(page: str) -> str:
    """The shared viewer (``viewer.js``) followed by one page's script (``report_viewer.js``,
    ``pick_page.js``), as the text of one inline ``<script>``.

    Both pages draw with the same code; "</" is escaped so that no text ends the element early.
    """
    folder = resources.files(__package__)
    text = "\n".join(folder.joinpath(name).read_text(encoding="utf-8") for name in ("viewer.js", page))
    return text.replace("</", "<\\/")


def mesh_payload(vertices, faces, colors, max_faces: int) -> tuple[dict, int]:
    """Flat, rounded arrays for the viewer; every ``step``-th face when there are too many."""
    faces = np.asarray(faces, dtype=np.int64)
    step = max(1, -(-len(faces) // max_faces))
    vertices = np.asarray(vertices, dtype=np.float64)
    span = float(np.ptp(vertices, axis=0).max()) or 1.0
    digits = max(0, int(np.ceil(-np.log10(span))) + 4)  # ~1e-4 of the size
    payload = {"vertices": np.round(vertices, digits).ravel().tolist(),
               "faces": faces[::step].ravel().tolist(),
               "colors": np.asarray(colors, dtype=np.int64).ravel().tolist()}
    return payload, step


def _table(rows, header) -> str:
    head = "".join(f"<th{' class=l' if i == 0 else ''}>{html.escape(str(h))}</th>"
                   for i, h in enumerate(header))
    body = "".join("<tr>" + "".join(f"<td{' class=l' if i == 0 else ''}>{html.escape(str(c))}</td>"
                                    for i, c in enumerate(row)) + "</tr>" for row in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def _configuration_rows(summary: dict) -> list[list]:
    rows = []
    for label, key in (("chosen", "configuration"), ("runner-up", "runner_up")):
        config = summary.get(key)
        if config:
            signs = " ".join("+" if s > 0 else "-" for s in config["signs"])
            rows.append([label, " ".join(str(p + 1) for p in config["perm"]), signs,
                         f"{config['cost']:.6g}"])
    return rows


def _curve_svg(thresholds, fractions, width: int = 420, height: int = 260) -> str:
    """Cumulative error curve as an inline SVG polyline with labelled axes."""
    left, bottom, right, top = 46, 36, 22, 10  # room for the last tick label
    w, h = width - left - right, height - top - bottom
    xmax = float(thresholds[-1]) or 1.0
    points = " ".join(f"{left + w * t / xmax:.1f},{top + h * (1 - f):.1f}"
                      for t, f in zip(thresholds, fractions))
    ticks = []
    for t in np.linspace(0.0, xmax, 6):
        x = left + w * t / xmax
        ticks.append(f'<line x1="{x:.1f}" y1="{top + h}" x2="{x:.1f}" y2="{top + h + 4}" stroke="#444"/>'
                     f'<text x="{x:.1f}" y="{top + h + 16}" font-size="11" text-anchor="middle">{t:.2f}</text>')
    for f in np.linspace(0.0, 1.0, 6):
        y = top + h * (1 - f)
        ticks.append(f'<line x1="{left - 4}" y1="{y:.1f}" x2="{left + w}" y2="{y:.1f}" stroke="#e4e4e4"/>'
                     f'<text x="{left - 6}" y="{y + 4:.1f}" font-size="11" text-anchor="end">{100 * f:.0f}%</text>')
    return (f'<svg id="error-curve" width="{width}" height="{height}" xmlns="http://www.w3.org/2000/svg">'
            + "".join(ticks)
            + f'<rect x="{left}" y="{top}" width="{w}" height="{h}" fill="none" stroke="#444"/>'
            + f'<polyline points="{points}" fill="none" stroke="#1f77b4" stroke-width="2"/>'
            + f'<text x="{left + w / 2}" y="{height - 4}" font-size="12" text-anchor="middle">'
              "geodesic error / sqrt(area)</text></svg>")


def report_html(source, target, mapping, summary: dict, *, errors=None, coloring: str = "parts",
                title: str = "meshcorr correspondence", elev: float = 30.0, azim: float = -60.0,
                up: str = "z", max_faces: int = 20000) -> str:
    """The report page as a string.

    Parameters
    ----------
    source, target : ((n1, 3) float, (m1, 3) int), ((n2, 3) float, (m2, 3) int)
        Vertices and faces of the two meshes.
    mapping : (n1,) int
        Target vertex of each source vertex, -1 where unmapped.
    summary : dict
        :meth:`meshcorr.maps.result.Correspondence.summary` (``timings``,
        ``configuration``, ``runner_up``, ``params`` and counts are shown).
    errors : (p,) float, optional
        Normalised geodesic errors against ground truth (NaN: unmapped);
        adds the cumulative error curve (:func:`meshcorr.evaluation.metrics.cumulative_curve`).
    coloring : {"parts", "xyz"}
        Colouring of the target; the source gets it through the map.
    title : str
    elev, azim, up
        Initial camera (see :func:`meshcorr.viz.render.camera_frame`).
    max_faces : int
        Faces per mesh sent to the viewer (more are thinned).

    Returns
    -------
    page : str
        A complete HTML document.
    """
    from ..evaluation.metrics import cumulative_curve

    max_faces = check_int("max_faces", max_faces, minimum=1)
    (V1, F1), (V2, F2) = source, target
    mapping = check_map(mapping, len(V1), len(V2))
    target_colors = mesh_coloring(coloring, V2, F2)
    source_colors = pull_back(target_colors, mapping, fill=UNMAPPED_COLOR)
    src, step1 = mesh_payload(V1, F1, source_colors, max_faces)
    tgt, step2 = mesh_payload(V2, F2, target_colors, max_faces)
    data = {"source": src, "target": tgt,
            "camera": camera_frame(elev, azim, up).ravel().round(12).tolist()}
    # "</" inside a script element would end it early.
    data_json = json.dumps(data, separators=(",", ":")).replace("</", "<\\/")
    viewer = viewer_script("report_viewer.js")

    parts = [f"<h1>{html.escape(title)}</h1>",
             '<pre id="errors"></pre>',
             '<p class="note">Drag either view to turn both. The target is coloured by '
             f"{html.escape(coloring)}; each source vertex takes the colour of its matched target "
             'vertex (grey: unmapped). <button id="reset">reset view</button></p>',
             '<div class="views">'
             f'<figure><canvas id="view-source" width="560" height="460"></canvas>'
             f"<figcaption>source: {len(V1)} vertices, {int((mapping >= 0).sum())} mapped</figcaption></figure>"
             f'<figure><canvas id="view-target" width="560" height="460"></canvas>'
             f"<figcaption>target: {len(V2)} vertices</figcaption></figure></div>"]
    if step1 > 1 or step2 > 1:
        parts.append(f'<p class="note">Large meshes: the views show every {max(step1, step2)}-th '
                     "face only.</p>")
    if errors is not None:
        errors = np.asarray(errors, dtype=np.float64)
        thresholds, fractions = cumulative_curve(errors)
        finite = errors[np.isfinite(errors)]
        mean = f"{finite.mean():.4f}" if finite.size else "n/a"
        parts += ["<h2>Error against ground truth</h2>",
                  f"<p>{errors.size} points, mean geodesic error / sqrt(area) {mean}; "
                  f"{100 * fractions[np.searchsorted(thresholds, 0.05)]:.1f} % within 0.05, "
                  f"{100 * fractions[-1]:.1f} % within {thresholds[-1]:.2f}.</p>",
                  _curve_svg(thresholds, fractions)]
    timings = summary.get("timings") or {}
    if timings:
        total = sum(timings.values()) or 1.0
        rows = [[stage, f"{t:.3f}", f"{100 * t / total:.0f} %"] for stage, t in timings.items()]
        rows.append(["total", f"{sum(timings.values()):.3f}", "100 %"])
        parts += ["<h2>Stage timings</h2>", _table(rows, ["stage", "seconds", "share"])]
    config_rows = _configuration_rows(summary)
    if config_rows:
        parts += ["<h2>Eigenvector configuration</h2>",
                  '<p class="note">Source eigenvector c is matched with target eigenvector '
                  "perm[c], times sign[c] (1-based, excluding the constant first one); cost: mean "
                  "nearest-neighbour distance between the embeddings.</p>",
                  _table(config_rows, ["", "perm", "signs", "cost"])]
        chosen, runner_up = summary.get("configuration"), summary.get("runner_up")
        if chosen and runner_up and chosen["cost"] > runner_up["cost"]:
            rule = html.escape(str((summary.get("params") or {}).get("symmetry", "")))
            parts.append('<p class="note">The chosen configuration is not the cheapest: the '
                         f"symmetry rule{' (' + rule + ')' if rule else ''} picked it among "
                         "near-tied configurations (often a map and its left/right mirror image; "
                         "'auto' keeps the orientation-preserving one).</p>")
        if "n_configurations" in summary:
            parts.append(f'<p class="note">{summary["n_configurations"]} configurations ranked.</p>')
    params = summary.get("params") or {}
    if params:
        parts += ["<h2>Parameters</h2>",
                  _table([[k, json.dumps(v)] for k, v in params.items()], ["parameter", "value"])]
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{html.escape(title)}</title><style>{_STYLE}</style></head>\n<body>\n"
            + "\n".join(parts)
            + f'\n<script type="application/json" id="report-data">{data_json}</script>\n'
            + f"<script>\n{viewer}\n</script>\n</body></html>\n")


def write_report(path, source, target, mapping, summary: dict, **options) -> None:
    """Write :func:`report_html` to ``path`` atomically (UTF-8).

    Parameters
    ----------
    path : str or path-like
    source, target, mapping, summary, **options
        As for :func:`report_html`.
    """
    page = report_html(source, target, mapping, summary, **options)
    atomic_write(path, lambda file: file.write(page.encode("utf-8")))
