"""meshcorr.spectral.spectrum: the dense spectrum of a small tube, its rows and its timings."""

import numpy as np
import pytest

import meshcorr.datasets as datasets
from meshcorr.core.mesh import as_mesh
from meshcorr.runtime.timing import StageTimer
from meshcorr.spectral.spectrum import dense_rows, dense_spectrum


def test_dense_rows_are_scaled_rows():
    D = np.array([[0.0, 2.0], [2.0, 0.0]])
    rows = dense_rows(D, 4.0)
    np.testing.assert_array_equal(rows(1), [0.5, 0.0])


def test_dense_spectrum_of_a_tube():
    shape = datasets.tube(n_along=16, n_around=10)
    mesh = as_mesh((shape.vertices, shape.faces))
    timer = StageTimer()
    spectrum = dense_spectrum(mesh, k=6, geodesic="heat", scale=True, random_state=0, timer=timer)
    assert set(timer.timings) == {"geodesics", "embedding"}
    assert spectrum.mode == "dense" and spectrum.rows == {}
    assert spectrum.embedding.shape == (mesh.n_vertices, 5)
    assert np.all(np.diff(spectrum.eigenvalues) <= 0) and spectrum.eigenvalues[-1] > 0
    D = mesh.geodesic_matrix("heat")
    assert spectrum.max_geodesic == pytest.approx(D.max())
    row = spectrum.geodesics_from(3)
    assert row[3] == pytest.approx(0.0, abs=1e-9) and row.max() <= 1.0 + 1e-12
    # the tube's long axis is x: the largest distance joins its two ends, about its length plus the caps
    assert spectrum.max_geodesic > np.ptp(mesh.vertices[:, 0])
    again = dense_spectrum(mesh, k=6, geodesic="heat", scale=True, random_state=0, timer=StageTimer())
    np.testing.assert_array_equal(spectrum.embedding, again.embedding)
