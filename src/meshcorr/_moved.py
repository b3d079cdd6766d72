"""The import paths of the flat layout, kept working with a warning that names the new one.

meshcorr kept its 58 modules side by side (``meshcorr.refine``,
``meshcorr.landmark_map``, ...); they now live in subpackages by layer
(``docs/architecture.md``). ``import meshcorr.refine`` and
``from meshcorr.refine import zoomout`` still work: a finder on
``sys.meta_path`` answers the old name with the module at its new place (the
same module object, so patching either name patches both) and emits a
:class:`DeprecationWarning` naming the new path. A name that moved on to
another module (:data:`MOVED_NAMES`, e.g. ``meshcorr.refine.laplace_basis``,
now in :mod:`meshcorr.spectral.basis`) is answered from there with a
warning that names its new home. The public modules that ``meshcorr`` itself lists
(``meshcorr.datasets``, ``meshcorr.fmap``, ...) keep their short names
without a warning.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings

#: Old module (under meshcorr) -> its place now.
MOVED: dict[str, str] = {
    "_params": "runtime.checks", "_threads": "runtime.threads", "_interrupt": "runtime.interrupt",
    "timing": "runtime.timing", "memory": "runtime.memory", "off": "io.off",
    "mesh": "core.mesh", "validate": "core.validate", "pointcloud": "core.pointcloud",
    "laplacian": "core.laplacian", "geodesics": "core.geodesics", "landmarks": "core.sampling",
    "normals": "core.normals", "boundary": "core.boundary", "holes": "core.holes",
    "embedding": "spectral.embedding", "nystrom": "spectral.nystrom", "spectrum": "spectral.spectrum",
    "modes": "spectral.modes",
    "reorder": "stages.reorder", "tps": "stages.tps", "icp": "stages.icp", "anchors": "stages.anchors",
    "refine": "stages.refine", "shells": "stages.shells", "bijection": "stages.bijection",
    "landmark_map": "stages.landmarks",
    "symmetry": "choice.symmetry", "selection": "choice.selection", "extremities": "choice.extremities",
    "orientation": "core.orientation", "curvature": "choice.curvature", "repair": "choice.repair",
    "oriented_start": "choice.oriented_start",
    "prepared": "shapes.prepared", "cache": "shapes.cache",
    "partial": "pipeline.partial", "settings": "pipeline.settings", "matcher": "pipeline.matcher",
    "methods": "pipeline.methods",
    "result": "maps.result", "texture": "maps.texture",
    "benchmark": "evaluation.benchmark", "ground_truth": "evaluation.ground_truth", "cuts": "evaluation.cuts",
    "consistency": "collection.consistency", "plots": "viz.plots",
    # modules that moved between subpackages
    "viz.colors": "maps.colors",
}

#: Names that left their flat-layout module: old module -> {name: "new.module:new_name"}.
MOVED_NAMES: dict[str, dict[str, str]] = {
    "refine": {**{name: f"spectral.basis:{name}" for name in ("laplace_basis", "pair_bases", "orthogonal_fit",
                                                              "BasisPrefetch", "prefetch_bases")},
               **{name: f"spectral.nearest:{name}" for name in ("nearest_vertices", "PRUNE_ABOVE",
                                                                "SCREEN_ABOVE")}},
    "orientation": {name: f"core.map_orientation:{name}" for name in ("orientation_score", "orientation_scores",
                                                                     "regional_orientation",
                                                                     "consistent_vertices")},
    "prepared": {"prepare": "pipeline.prepare:prepare", "SHAPE_SETTINGS": "pipeline.settings:SHAPE_SETTINGS",
                 "shape_settings": "pipeline.settings:shape_settings", "REFINE_K": "pipeline.settings:REFINE_K"},
    "pipeline": {"embedding_spread": "stages.anchors:embedding_spread",
                 "ANCHOR_SCALES": "stages.anchors:ANCHOR_SCALES"},
    "partial": {**{name: f"stages.part_checks:{name}" for name in (
        "PARTIAL_MODES", "check_partial_options", "partiality_suspicion", "part_evidence", "geodesic_rows",
        "geodesic_diameter", "check_part_not_larger", "check_roles")},
        **{name: f"stages.part_region:{name}" for name in ("matched_region", "part_region", "invert_part_map",
                                                           "mean_edge_length")},
        "partial_zoomout": "stages.partial_zoomout:partial_zoomout",
        "interior_vertices": "stages.part_cut:interior_vertices",
        "geodesic_refine": "stages.part_landmarks:geodesic_refine",
        "landmark_map": "stages.part_landmarks:part_landmark_map",
        "fitted_distortion": "stages.part_distortion:fitted_distortion",
        "part_extremities": "choice.part_tips:part_extremities",
        "match_part_tips": "choice.part_tips:match_part_tips"},
    "symmetry": {"Candidate": "choice.symmetry:ConfigurationCandidate"},
    "ground_truth": {"read_index_lines": "io.indices:read_index_lines", "index_fields": "io.indices:index_fields"},
    "collection": {"read_pairs": "collection.pairs:read_pair_list", "connect": "collection.cluster:connect",
                   "FIELDS": "collection.summary:FIELDS",
                   **{name: f"collection.pairs:{name}" for name in ("all_pairs", "template_pairs", "map_name")}},
}

#: Public modules of ``meshcorr`` (its ``__all__``) -> their place; these short names stay, silently.
PUBLIC_MODULES: dict[str, str] = {
    "datasets": "evaluation.datasets", "evaluation": "evaluation", "fmap": "spectral.fmap",
    "precise": "maps.precise", "progress": "runtime.progress", "transfer": "maps.transfer", "viz": "viz",
}


def new_name(old: str) -> str | None:
    """``meshcorr.<new place>`` of a flat-layout module name ``meshcorr.<old>``, else None."""
    parts = old.split(".")
    if len(parts) < 2 or parts[0] != "meshcorr":
        return None
    short = ".".join(parts[1:])
    place = MOVED.get(short) or PUBLIC_MODULES.get(short)
    return None if place in (None, short) else f"meshcorr.{place}"  # a package in its own place needs no alias


def _warn(old: str, new: str) -> None:
    if old.partition(".")[2] not in PUBLIC_MODULES:
        warnings.warn(f"{old} moved to {new}; import {new} instead (the old path will be removed).",
                      DeprecationWarning, stacklevel=3)


def moved_name(old_module: str, name: str):
    """The value of a name that left flat-layout module ``old_module`` (with the warning), else AttributeError."""
    place = MOVED_NAMES.get(old_module, {}).get(name)
    if place is None:
        raise AttributeError(name)
    module, _, attribute = place.partition(":")
    warnings.warn(f"meshcorr.{old_module}.{name} moved to meshcorr.{module}.{attribute}; import it from there "
                  "(the old path will be removed).", DeprecationWarning, stacklevel=3)
    return getattr(importlib.import_module(f"meshcorr.{module}"), attribute)


def _getattr_of_moved_names(old_module: str, new_module: str):
    """A module ``__getattr__`` answering the names that left ``old_module`` (:data:`MOVED_NAMES`)."""
    def __getattr__(name: str):
        try:
            return moved_name(old_module, name)
        except AttributeError:
            raise AttributeError(f"module {new_module!r} has no attribute {name!r}") from None

    return __getattr__


class _Alias(importlib.abc.Loader):
    """Loads an old module name as the module at its new place (the same object)."""

    def __init__(self, new: str) -> None:
        self.new = new

    def create_module(self, spec):
        _warn(spec.name, self.new)
        module = importlib.import_module(self.new)
        old = spec.name.partition(".")[2]
        if old in MOVED_NAMES and "__getattr__" not in vars(module):
            # ``from meshcorr.refine import laplace_basis``: the name is looked up at its new home
            module.__getattr__ = _getattr_of_moved_names(old, module.__name__)
        self.spec = module.__spec__  # the import system sets the alias's spec on the module; put it back
        return module

    def exec_module(self, module) -> None:  # already executed under its new name
        module.__spec__ = self.spec


class _OldPaths(importlib.abc.MetaPathFinder):
    """Finds ``meshcorr.<old>`` for the modules of :data:`MOVED` and :data:`PUBLIC_MODULES`."""

    def find_spec(self, fullname, path=None, target=None):
        new = new_name(fullname)
        if new is None:
            return None
        return importlib.util.spec_from_loader(fullname, _Alias(new))


def moved_attribute(name: str):
    """``meshcorr.<name>`` for an old module name (imports it with the warning), else None."""
    if f"meshcorr.{name}" not in sys.modules and new_name(f"meshcorr.{name}") is None:
        return None
    return importlib.import_module(f"meshcorr.{name}")


def install() -> None:
    """Put the finder of old paths on ``sys.meta_path`` once."""
    if not any(isinstance(finder, _OldPaths) for finder in sys.meta_path):
        sys.meta_path.append(_OldPaths())


def forwarding(package: str, module: str):
    """A module ``__getattr__`` for ``package`` that looks names up in ``package.module`` (imported on first use).

    A subpackage that took the place of a flat-layout module of the same
    name (``meshcorr.pipeline``, ``meshcorr.evaluation``,
    ``meshcorr.collection``) keeps that module's names this way.
    """
    def __getattr__(name: str):
        if name.startswith("__"):
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        # A submodule not imported yet comes first: ``meshcorr.collection.batch`` is the module, not the
        # function of that name inside it.
        if importlib.util.find_spec(f"{package}.{name}") is not None:
            return importlib.import_module(f"{package}.{name}")
        target = importlib.import_module(f"{package}.{module}")
        if hasattr(target, name):
            return getattr(target, name)
        try:  # a name of the flat-layout module that went elsewhere
            return moved_name(package.partition(".")[2], name)
        except AttributeError:
            raise AttributeError(f"module {package!r} has no attribute {name!r}") from None

    return __getattr__
