"""Collections of shapes: many maps on Dask (``batch``) and maps made consistent through a hub (``consistency``).

``meshcorr.collection.batch`` is the module; :func:`meshcorr.batch` the
function. Its steps: the pair lists (``pairs``), the options and keys
(``options``), the Dask cluster (``cluster``), the workers' tasks (``tasks``)
and the records and summary files (``summary``). The names of the former
``meshcorr.collection`` module are looked up in ``batch`` on first use, or
where they moved (``all_pairs``, ``map_name``: ``pairs``, with a warning).
"""


from .._moved import forwarding

__getattr__ = forwarding(__name__, "batch")
