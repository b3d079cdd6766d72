"""meshcorr.core.normals: a point cloud's normals point outwards on a sphere, and an open cloud is flagged."""

import numpy as np

from meshcorr.core.normals import estimate_normals

from .meshes import sphere


def test_sphere_normals_are_the_radial_directions_outwards():
    points, _ = sphere(3)
    areas = np.full(len(points), 4 * np.pi / len(points))
    estimate = estimate_normals(points, areas)
    np.testing.assert_allclose(np.linalg.norm(estimate.normals, axis=1), 1.0, atol=1e-12)
    cosine = np.sum(estimate.normals * points, axis=1)
    assert cosine.min() > 0.98
    assert estimate.reliable and estimate.reason == "" and estimate.disagreement == 0.0
    assert not estimate.normals.flags.writeable


def test_an_open_hemisphere_is_not_reliable():
    points, _ = sphere(3)
    points = points[points[:, 2] > 0.1]
    areas = np.full(len(points), 2 * np.pi / len(points))
    estimate = estimate_normals(points, areas)
    assert not estimate.reliable
    assert "open" in estimate.reason
    # still consistent: all on one side
    cosine = np.sum(estimate.normals * points, axis=1)
    assert (cosine > 0.9).all() or (cosine < -0.9).all()
