"""Choosing among candidate maps: the left/right mirror, extremities, the whole-map choice.

- :mod:`~meshcorr.choice.symmetry`: the first round: TPS-ICP of each
  near-tied eigenvector configuration, scored
  (:class:`~meshcorr.choice.symmetry.ConfigurationCandidate`), and the rule
  that picks one;
- :mod:`~meshcorr.choice.whole_map`, :mod:`~meshcorr.choice.selection`: the
  second round: whole maps from the spectral map, matched extremities and
  landmarks (:class:`~meshcorr.choice.selection.MapCandidate`), refined and
  scored alike;
- :mod:`~meshcorr.choice.extremities`, :mod:`~meshcorr.choice.oriented_start`:
  where those starts come from;
- :mod:`~meshcorr.choice.curvature`: the curvature term of the scores;
- :mod:`~meshcorr.choice.repair`: the repair of a partly mirrored map;
- :mod:`~meshcorr.choice.part_tips`, :mod:`~meshcorr.choice.part_candidates`:
  the partial mode's tips and candidates.
"""
