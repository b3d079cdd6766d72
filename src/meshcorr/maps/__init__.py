"""What a map becomes: the result object, precise maps, attribute and texture transfer.

- :mod:`~meshcorr.maps.result`: :class:`~meshcorr.maps.result.Correspondence`,
  the result of :func:`meshcorr.match` (its ``show()``, ``evaluate()``,
  ``inverse()`` import the layers above on use);
- :mod:`~meshcorr.maps.precise`: maps to points on triangles (``meshcorr.precise``);
- :mod:`~meshcorr.maps.transfer`, :mod:`~meshcorr.maps.colors`: values and
  colours carried through a map (``meshcorr.transfer``);
- :mod:`~meshcorr.maps.texture`: texture coordinates carried through a map.
"""
