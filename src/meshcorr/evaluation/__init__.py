"""Evaluation: error metrics, ground truth, the benchmark runner, synthetic shapes with known maps, cuts.

``metrics`` (geodesic errors, curves, map quality), ``ground_truth`` (truth
files), ``benchmark`` (the runner of ``meshcorr bench``), ``datasets``
(generated shapes) and ``cuts`` (parts made from whole shapes).
``meshcorr.evaluation.geodesic_errors`` and the other names of the former
``meshcorr.evaluation`` module are looked up in ``metrics`` on first use.
"""


from .._moved import forwarding

__getattr__ = forwarding(__name__, "metrics")
