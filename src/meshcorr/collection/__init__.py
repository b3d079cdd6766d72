"""Collections of shapes: many maps on Dask (``batch``) and maps made consistent through a hub (``consistency``).

``meshcorr.collection.batch`` is the module; :func:`meshcorr.batch` the
function. The names of the former ``meshcorr.collection`` module
(``read_pairs``, ``all_pairs``, ...) are looked up in ``batch`` on first use.
"""


from .._moved import forwarding

__getattr__ = forwarding(__name__, "batch")
