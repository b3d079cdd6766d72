"""One shape: the mesh object, its checks and the geometry computed on it alone.

- :mod:`~meshcorr.core.mesh`: the immutable :class:`~meshcorr.core.mesh.Mesh`
  (a triangle mesh or a point cloud) and :func:`~meshcorr.core.mesh.as_mesh`;
- :mod:`~meshcorr.core.store`: the per-shape store of derived quantities;
- :mod:`~meshcorr.core.validate`, :mod:`~meshcorr.core.pointcloud`: what
  makes an input usable, with a message naming the problem and the fix;
- :mod:`~meshcorr.core.laplacian`, :mod:`~meshcorr.core.geodesics`: the
  Laplace-Beltrami operator and geodesic distances;
- :mod:`~meshcorr.core.sampling`: farthest-point sampling;
- :mod:`~meshcorr.core.normals`, :mod:`~meshcorr.core.orientation`,
  :mod:`~meshcorr.core.boundary`, :mod:`~meshcorr.core.holes`: normals,
  outward orientation, boundary loops, hole filling;
- :mod:`~meshcorr.core.map_orientation`: the orientation a vertex map keeps
  (the one module that looks at two shapes: it needs only their geometry).
"""
