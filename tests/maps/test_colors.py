"""meshcorr.maps.colors: colour maps, coordinate colours and part colours with known values."""

import numpy as np
import pytest

import meshcorr.datasets as datasets
from meshcorr.errors import ParameterError
from meshcorr.maps.colors import (COLORMAPS, PALETTE, UNMAPPED_COLOR, coordinate_colors, mesh_coloring,
                                 part_colors, scalar_colors)


def test_scalar_colors_ends_nan_and_clipping():
    stops = np.asarray(COLORMAPS["viridis"])
    colors = scalar_colors([0.0, 1.0, np.nan, 5.0], vmin=0.0, vmax=1.0)
    assert colors.dtype == np.uint8 and colors.shape == (4, 3)
    np.testing.assert_array_equal(colors[0], np.round(stops[0]))
    np.testing.assert_array_equal(colors[1], np.round(stops[-1]))
    np.testing.assert_array_equal(colors[2], UNMAPPED_COLOR)
    np.testing.assert_array_equal(colors[3], colors[1])  # clipped
    # default range: the finite minimum and maximum
    np.testing.assert_array_equal(scalar_colors([2.0, 4.0]), scalar_colors([0.0, 1.0], vmin=0, vmax=1))


def test_scalar_colors_interpolates_linearly_between_stops():
    stops = np.asarray(COLORMAPS["coolwarm"], dtype=float)
    x = np.linspace(0, 1, len(stops))
    t = (x[0] + x[1]) / 2
    colors = scalar_colors([t], "coolwarm", vmin=0, vmax=1)
    np.testing.assert_array_equal(colors[0], np.round((stops[0] + stops[1]) / 2))


def test_scalar_colors_constant_and_unknown_map():
    np.testing.assert_array_equal(scalar_colors([3.0, 3.0]), np.round([COLORMAPS["viridis"][0]] * 2))
    with pytest.raises(ParameterError, match="The 'cmap' parameter must be one of"):
        scalar_colors([1.0], "jet")


def test_coordinate_colors_span_without_black():
    vertices = np.array([[0, 0, 0], [1, 2, 0], [0.5, 1, 0]])
    colors = coordinate_colors(vertices)
    np.testing.assert_array_equal(colors, [[38, 38, 38], [255, 255, 38], [147, 147, 38]])


def test_part_colors_give_tips_their_own_colour():
    shape = datasets.tube()
    colors = part_colors(shape.vertices, shape.faces, n_parts=2)
    # The two seeds are the tube's ends: the vertices of least and largest x get the two first colours.
    ends = np.argmin(shape.vertices[:, 0]), np.argmax(shape.vertices[:, 0])
    got = {tuple(colors[i]) for i in ends}
    assert got == {tuple(PALETTE[0]), tuple(PALETTE[1])}
    assert colors.shape == (shape.n_vertices, 3) and colors.dtype == np.uint8


def test_mesh_coloring_by_name():
    shape = datasets.tube(n_along=10, n_around=8)
    np.testing.assert_array_equal(mesh_coloring("xyz", shape.vertices, shape.faces),
                                  coordinate_colors(shape.vertices))
    np.testing.assert_array_equal(mesh_coloring("parts", shape.vertices, shape.faces),
                                  part_colors(shape.vertices, shape.faces))
    with pytest.raises(ParameterError, match="The 'coloring' parameter must be one of 'parts', 'xyz'"):
        mesh_coloring("rainbow", shape.vertices, shape.faces)
