"""Figures for evaluation results, written as small PNG files.

matplotlib is optional (``pip install meshcorr[plot]``) and imported only
when a figure is drawn, with the Agg back end (no display needed).
"""

from __future__ import annotations

import io
from typing import Mapping, Sequence

import numpy as np

from ..errors import ParameterError
from ..io import atomic_write

__all__ = ["plot_cumulative_curves", "plot_lines", "require_matplotlib"]


def require_matplotlib():
    """Return ``matplotlib.pyplot`` (Agg back end) or raise a ParameterError naming the fix."""
    try:
        import matplotlib
    except ImportError as exc:
        raise ParameterError("Figures need matplotlib: install it with `pip install meshcorr[plot]` "
                             "(or pip install matplotlib).") from exc
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path, dpi: int) -> None:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi, bbox_inches="tight")
    payload = buffer.getvalue()
    atomic_write(path, lambda file: file.write(payload))


def plot_lines(path, series: Mapping[str, tuple[Sequence[float], Sequence[float]]], *,
               xlabel: str, ylabel: str, title: str = "", styles: Mapping[str, str] | None = None,
               ylim: tuple[float, float] | None = None, markers: bool = False,
               colors: Mapping[str, str] | None = None, dpi: int = 90) -> None:
    """Draw one line per series and save the figure as a PNG (atomically).

    Parameters
    ----------
    path : str or os.PathLike
        The PNG file to write.
    series : mapping label -> (x (t,) float, y (t,) float)
    xlabel, ylabel, title : str
    styles : mapping label -> matplotlib line style, optional
    colors : mapping label -> matplotlib colour, optional
        E.g. one colour per method for its solid and dashed variants.
    ylim : (float, float), optional
    markers : bool
        Mark the data points.
    dpi : int
        Resolution; the default keeps a 6 x 4 inch figure under ~60 KB.
    """
    if not series:
        raise ParameterError("Nothing to plot: no series were given.")
    plt = require_matplotlib()
    fig, ax = plt.subplots(figsize=(6, 4))
    try:
        for label, (x, y) in series.items():
            ax.plot(np.asarray(x), np.asarray(y), (styles or {}).get(label, "-"), label=label,
                    color=(colors or {}).get(label), marker="o" if markers else None, markersize=3)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        if title:
            ax.set_title(title, fontsize=10)
        if ylim is not None:
            ax.set_ylim(*ylim)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        _save(fig, path, dpi)
    finally:
        plt.close(fig)


def plot_cumulative_curves(path, curves: Mapping[str, tuple[np.ndarray, np.ndarray]], *,
                           title: str = "", styles: Mapping[str, str] | None = None,
                           colors: Mapping[str, str] | None = None) -> None:
    """Cumulative geodesic-error curves (Princeton protocol) as a PNG.

    Parameters
    ----------
    path : str or os.PathLike
    curves : mapping label -> (thresholds (t,) float, fractions (t,) float)
        E.g. from :func:`meshcorr.evaluation.metrics.cumulative_curve`.
    title : str
    styles : mapping label -> line style, optional
    colors : mapping label -> colour, optional
    """
    plot_lines(path, curves, xlabel="geodesic error / sqrt(area)", ylabel="fraction of points",
               title=title, styles=styles, colors=colors, ylim=(0.0, 1.0))
