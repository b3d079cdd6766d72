"""Progress of the pictures (`meshcorr show`, `meshcorr embed`): their geodesic solves and eigen-solves
take minutes on large meshes, and ran without a line on the terminal.

The figure functions take ``progress(stage, done, total)`` (and ``correspondence_figure`` a geodesic
``cache``); the picture is the same with or without them; the commands pass the command line's progress
lines as ``evaluate`` does (none with -q).
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from meshcorr import datasets  # noqa: E402
from meshcorr.cli import main  # noqa: E402
from meshcorr.evaluation.metrics import GeodesicCache  # noqa: E402
from meshcorr.io import write_map, write_mesh  # noqa: E402
from meshcorr.viz.figures import correspondence_figure, spectrum_figure  # noqa: E402

#: Small pictures: the tests are about the calls, not the drawing.
DPI = 30


def _read_png(path) -> np.ndarray:
    from matplotlib.image import imread

    return imread(str(path))


class Recorder:
    """A progress callback keeping every call."""

    def __init__(self) -> None:
        self.calls: list[tuple[str, int, int]] = []

    def __call__(self, stage: str, done: int, total: int) -> None:
        self.calls.append((stage, done, total))

    def stages(self) -> list[str]:
        """The stages in the order they ran, each once."""
        names = [stage for stage, _, _ in self.calls]
        return [stage for k, stage in enumerate(names) if k == 0 or names[k - 1] != stage]

    def counts(self, stage: str) -> list[tuple[int, int]]:
        return [(done, total) for name, done, total in self.calls if name == stage]


def _check_increasing(counts: list[tuple[int, int]]) -> None:
    """One total; ``done`` runs from 0 to it, increasing at every call."""
    totals = {total for _, total in counts}
    assert len(totals) == 1, counts
    done = [d for d, _ in counts]
    assert done[0] == 0 and done[-1] == totals.pop(), counts
    assert all(b > a for a, b in zip(done, done[1:])), counts


@pytest.fixture(scope="module")
def tubes_and_maps(tmp_path_factory):
    """A straight tube, a bent and re-indexed copy, the true map and a wrong map (the truth rolled), as
    arrays and files."""
    folder = tmp_path_factory.mktemp("show_progress")
    source = datasets.tube(n_along=14, n_around=8, bend=0.0)
    bent = datasets.tube(n_along=14, n_around=8, bend=1.5)
    target, _ = datasets.rigid_copy(bent, rotation=np.eye(3), translation=np.zeros(3), random_state=0)
    truth = datasets.ground_truth(source, target)
    mapping = np.roll(truth, 9)
    mapping[:3] = -1  # unmapped vertices have no error
    paths = {name: folder / f"{name}.{ext}" for name, ext in
             (("source", "off"), ("target", "off"), ("map", "txt"), ("gt", "txt"))}
    write_mesh(paths["source"], source.vertices, source.faces)
    write_mesh(paths["target"], target.vertices, target.faces)
    write_map(paths["map"], mapping)
    write_map(paths["gt"], truth)
    return {"source": (source.vertices, source.faces), "target": (target.vertices, target.faces),
            "truth": truth, "mapping": mapping, "paths": {k: str(v) for k, v in paths.items()}}


@pytest.mark.parametrize("error", [False, True])
def test_correspondence_figure_reports_its_solves_and_draws_the_same_picture(tubes_and_maps, tmp_path, error):
    plain, reported = tmp_path / "plain.png", tmp_path / "reported.png"
    options = dict(truth=tubes_and_maps["truth"], error=error, dpi=DPI)
    info = correspondence_figure(tubes_and_maps["source"], tubes_and_maps["target"], tubes_and_maps["mapping"], plain, **options)
    progress = Recorder()
    assert correspondence_figure(tubes_and_maps["source"], tubes_and_maps["target"], tubes_and_maps["mapping"], reported,
                                 progress=progress, **options) == info
    assert info["mean_error"] > 0.05  # the map is wrong: there were solves to report
    assert np.array_equal(_read_png(plain), _read_png(reported))
    assert progress.stages() == ["geodesic errors", "drawing"]
    solves = progress.counts("geodesic errors")
    _check_increasing(solves)
    assert len(solves) > 10  # reported as the solves advance, not only at the end
    assert progress.counts("drawing") == [(0, 1), (1, 1)]


def test_without_truth_only_the_drawing_is_reported(tubes_and_maps, tmp_path):
    progress = Recorder()
    assert correspondence_figure(tubes_and_maps["source"], tubes_and_maps["target"], tubes_and_maps["mapping"], tmp_path / "a.png",
                                 dpi=DPI, progress=progress) == {}
    assert progress.calls == [("drawing", 0, 1), ("drawing", 1, 1)]


def test_a_cache_passed_in_keeps_the_reported_solves(tubes_and_maps, tmp_path):
    cache = GeodesicCache("heat")
    first, second = Recorder(), Recorder()
    options = dict(truth=tubes_and_maps["truth"], dpi=DPI, cache=cache)
    info = correspondence_figure(tubes_and_maps["source"], tubes_and_maps["target"], tubes_and_maps["mapping"], tmp_path / "a.png",
                                 progress=first, **options)
    solves = first.counts("geodesic errors")
    assert cache.n_solves == solves[-1][1] > 0  # the solves went into the given cache
    # Again onto the same target: every row is cached, nothing to solve or report but the drawing.
    assert correspondence_figure(tubes_and_maps["source"], tubes_and_maps["target"], tubes_and_maps["mapping"], tmp_path / "b.png",
                                 progress=second, **options) == info
    assert cache.n_solves == solves[-1][1]
    assert second.stages() == ["drawing"]
    assert np.array_equal(_read_png(tmp_path / "a.png"), _read_png(tmp_path / "b.png"))


@pytest.mark.parametrize("geodesic", ["heat", "dijkstra"])
def test_spectrum_figure_reports_geodesics_and_eigenvectors(tubes_and_maps, tmp_path, geodesic):
    vertices, faces = tubes_and_maps["source"]
    plain, reported = tmp_path / "plain.png", tmp_path / "reported.png"
    values = spectrum_figure(vertices, faces, plain, n_eigenvectors=1, geodesic=geodesic, dpi=DPI)
    progress = Recorder()
    again = spectrum_figure(vertices, faces, reported, n_eigenvectors=1, geodesic=geodesic, dpi=DPI,
                            progress=progress)
    assert np.array_equal(values, again)
    assert np.array_equal(_read_png(plain), _read_png(reported))
    assert progress.stages() == ["geodesics", "eigenvectors", "drawing"]
    solves = progress.counts("geodesics")
    _check_increasing(solves)
    assert solves[-1][1] == len(vertices)
    if geodesic == "heat":  # solved one source at a time ("dijkstra" solves all rows in one call)
        assert len(solves) > 10
    assert progress.counts("eigenvectors") == progress.counts("drawing") == [(0, 1), (1, 1)]


def test_show_and_embed_print_progress_lines_unless_quiet(tubes_and_maps, tmp_path, capsys):
    p = tubes_and_maps["paths"]
    show = ["show", p["source"], p["target"], p["map"], "--gt", p["gt"], "--dpi", str(DPI)]
    embed = ["embed", p["source"], "-n", "1", "--dpi", str(DPI)]
    # -v: every stage, each line naming what the run is on.
    assert main(["-v", *show, "-o", str(tmp_path / "v.png")]) == 0
    err = capsys.readouterr().err
    assert f"meshcorr: {p['map']} on {p['target']} [geodesic errors] 100%" in err
    assert f"meshcorr: {p['map']} on {p['target']} [drawing] done in" in err
    assert err.splitlines()[-1].startswith(f"meshcorr: wrote {tmp_path / 'v.png'}")
    assert main(["-v", *embed, "-o", str(tmp_path / "e.png")]) == 0
    err = capsys.readouterr().err
    for line in ("[geodesics] 100%", "[eigenvectors] done in", "[drawing] done in"):
        assert f"meshcorr: {p['source']} {line}" in err
    # -q: nothing at all; the pictures are the same.
    assert main(["-q", *show, "-o", str(tmp_path / "q.png")]) == 0
    assert main(["-q", *embed, "-o", str(tmp_path / "eq.png")]) == 0
    assert capsys.readouterr().err == ""
    assert np.array_equal(_read_png(tmp_path / "v.png"), _read_png(tmp_path / "q.png"))
    assert np.array_equal(_read_png(tmp_path / "e.png"), _read_png(tmp_path / "eq.png"))
