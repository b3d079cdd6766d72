"""The steps of a pair, each a function on arrays and meshes, in the order the pipeline runs them.

- :mod:`~meshcorr.stages.reorder`: eigenvector reordering and sign
  correction (step 4);
- :mod:`~meshcorr.stages.tps`, :mod:`~meshcorr.stages.icp`: thin-plate
  splines and TPS-ICP in the spectral domain (step 5);
- :mod:`~meshcorr.stages.anchors`: anchors and proximity-aided matching
  (step 6);
- :mod:`~meshcorr.stages.refine`: ZoomOut refinement;
- :mod:`~meshcorr.stages.shells`: the smooth-shell alignment;
- :mod:`~meshcorr.stages.bijection`: the one-to-one map (step 7);
- :mod:`~meshcorr.stages.landmarks`: the user's landmarks (checks, maps and
  descriptors from them);
- the partial mode's steps (:mod:`~meshcorr.stages.part_checks` and the
  ``part_*`` modules).

A stage imports the layers below (runtime, io, core, spectral) and other
stages, never the choice among maps or anything above.
"""
