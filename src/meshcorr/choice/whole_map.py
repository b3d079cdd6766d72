"""The whole-map choice: the spectral map against maps started from extremities and landmarks.

The second round of the map choice (docs/method.md, "whole-map choice";
the first, among near-tied eigenvector configurations, is
:mod:`meshcorr.choice.symmetry`): candidate maps started from matched shape
extremities (:mod:`meshcorr.choice.extremities`) and from the user's
landmarks are refined like the spectral map and scored with it by the
whole-map energies (:mod:`meshcorr.choice.selection`); with the smooth shells
and a reliable orientation the candidates are judged as the pipeline will
return them (repaired, :mod:`meshcorr.choice.repair`, and shelled).
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..core.mesh import Mesh
from ..errors import LandmarkWarning
from ..runtime.threads import parallel_map
from ..runtime.timing import StageTimer
from ..stages.landmarks import landmark_map
from ..stages.refine import refine_map
from .extremities import match_extremities, spectrum_extremities
from .landmark_doubts import landmark_doubts
from .oriented_start import fit_oriented_map
from .repair import repair_candidates
from .confidence import Confidence, choice_confidence
from .sign_search import sign_search_starts
from .selection import energy as map_energy
from .selection import (MapCandidate, candidate_summaries, choose_map, distinct_candidates, distortion_sources,
                        eligible, score_candidates, shell_candidates)

__all__ = ["EXTREMITY_STARTS", "WholeMapChoice", "whole_map_choice"]

#: How a tip assignment becomes a dense map: "distances" (meshcorr.stages.landmarks) or "oriented"
#: (meshcorr.choice.oriented_start, when the orientation is reliable); the first is named
#: "extremities-<rank>", others get their name appended. benchmarks/selection_study.py runs both:
#: "oriented" alone was better on TOSCA and SHREC'07 humans and much worse on gorilla -> human
#: (benchmarks/RESULTS-robustness-trials.md), so the default stays "distances".
EXTREMITY_STARTS: tuple[str, ...] = ("distances",)


class WholeMapChoice(NamedTuple):
    """What :func:`whole_map_choice` returns: the chosen map, its alternative and every candidate's scores."""

    mapping: np.ndarray  # the chosen local map
    other: np.ndarray | None  # the least distorted map of the other orientation, else the spectral alternative
    summaries: list  # every candidate's scores (MapCandidate.to_dict, chosen, alternative)
    spectral_kept: bool = True  # the chosen map is the spectral map unchanged (no other candidate, no pin)
    shelled: bool = False  # the candidates were judged after meshcorr.stages.shells: the chosen map is final
    orientation: float | None = None  # the chosen map's orientation score, when it is that exact map's
    confidence: Confidence | None = None  # the margin to the best rival map (meshcorr.choice.confidence)
    landmark_doubts: dict | None = None  # landmark row -> why it looks wrong (meshcorr.choice.landmark_doubts)


def whole_map_choice(src: Mesh, tgt: Mesh, spectra, spectral_map: np.ndarray, spectral_other,
                      pairs: np.ndarray | None, *, extremities: bool, refine: bool, refine_k: int,
                      bijective: bool, reliable: bool, shells: bool, timer: StageTimer,
                      described: tuple[np.ndarray, np.ndarray] | None = None,
                      tip_starts: tuple[str, ...] = EXTREMITY_STARTS, random_state, fine=None,
                      sign_search: bool = False) -> WholeMapChoice:
    """Candidate maps from extremities and landmarks, scored with the spectral map; the winner.

    With ``shells`` on and a reliable orientation, the choice is made between
    the maps as the pipeline returns them: each partly mirrored candidate
    adds its repair (:func:`meshcorr.choice.repair.repair_candidates`), and every
    candidate that keeps the orientation is refined by the smooth shells
    (:func:`meshcorr.choice.selection.shell_candidates`) and scored again. A right
    map whose ZoomOut vertices are scattered locally scores as low as a
    mirrored one before the shells (TOSCA michael11 -> michael16: 0.59
    against 0.2-0.58) and above 0.9 after them.

    ``fine``: when ``src`` and ``tgt`` are coarse copies, the two
    :class:`~meshcorr.core.coarse.CoarseCopy` (the curvature disagreement is
    measured on the full meshes: :func:`meshcorr.choice.selection.score_candidates`).
    ``sign_search``: also start from the configurations of the first
    Laplace-Beltrami functions' signs (:mod:`meshcorr.choice.sign_search`).
    """
    with timer.stage("whole-map"):
        g1, g2 = spectra[0].geodesics_from, spectra[1].geodesics_from
        hows = tuple(dict.fromkeys(tip_starts)) if reliable else ("distances",)  # the first is unnamed
        starts: list[tuple[str, np.ndarray, dict]] = []
        if pairs is not None:
            starts.append(("landmarks", landmark_map(g1, g2, pairs), {}))
        if extremities:
            tips = [spectrum_extremities(mesh, spectrum, random_state=random_state)
                    for mesh, spectrum in zip((src, tgt), spectra)]
            for rank, (energy, assignment) in enumerate(match_extremities(*tips)):
                for how in hows:
                    start = (fit_oriented_map(src, tgt, g1, g2, assignment, basis_k=refine_k,
                                              random_state=random_state) if how == "oriented"
                             else landmark_map(g1, g2, assignment))
                    suffix = "" if how == hows[0] else f"-{how}"
                    starts.append((f"extremities-{rank}{suffix}", start, {"extremity_energy": energy}))
        if sign_search:
            starts += sign_search_starts(src, tgt, reliable=reliable, random_state=random_state)
        candidates = [MapCandidate("spectral", spectral_map)]
        if spectral_other is not None:  # unrefined: it is kept as the alternative, rarely chosen
            candidates.append(MapCandidate("spectral-alternative", spectral_other))
        def refined(start: tuple[str, np.ndarray, dict]) -> np.ndarray:
            # Only the landmarks' own map is held to them while refined: the others must show
            # by themselves whether they agree with the landmarks (meshcorr.choice.selection).
            origin, mapping, _ = start
            pins = pairs if origin == "landmarks" else None
            return refine_map(src, tgt, mapping, k=refine_k, bijective=bijective, random_state=random_state,
                              landmarks=pins)[0] if refine else mapping

        # Independent refinements, mostly BLAS and LAPACK: one thread per core (same maps as a loop).
        for (origin, _, extra), mapping in zip(starts, parallel_map(refined, starts)):
            candidates.append(MapCandidate(origin, mapping, extra=extra))
        score_candidates(candidates, src, tgt, g1, g2, reliable=reliable, landmarks=pairs, random_state=random_state,
                         fine=fine)
    copies: list[MapCandidate] = []  # near-copies of kept candidates: listed in the summaries only
    sources = distortion_sources(src.n_vertices, random_state)  # where maps are compared
    if shells and reliable:  # judge the maps as they will be returned (module docstrings of these steps)
        with timer.stage("shells"):
            scored = dict(reliable=reliable, landmarks=pairs, random_state=random_state, fine=fine)
            candidates, copies = distinct_candidates(candidates, g2, sources, reliable=reliable)  # repaired once
            repaired = repair_candidates(candidates, src, tgt, k=refine_k, random_state=random_state)
            score_candidates(repaired, src, tgt, g1, g2, **scored)
            candidates, more = distinct_candidates(candidates + repaired, g2, sources, reliable=reliable)  # shelled once
            copies += more
            final = shell_candidates(candidates, src, tgt, k=refine_k, landmarks=pairs, descriptors=described,
                                     random_state=random_state)
            score_candidates(final, src, tgt, g1, g2, **scored)
    chosen, alternative = choose_map(candidates, reliable=reliable)
    pool = eligible(candidates, reliable=reliable)  # the rivals: maps the rules would have let win
    confidence = choice_confidence(pool, chosen, {id(c): map_energy(c, reliable) for c in pool}, g1, g2, sources)
    doubts = None
    if pairs is not None:  # warned before the landmarks are pinned below
        doubts = landmark_doubts(candidates, chosen, pairs, g1, g2, reliable=reliable)
        if doubts:
            warn_landmark_doubts(doubts, pairs, src, tgt, fine)
    mapping = chosen.mapping.copy()
    if pairs is not None:
        mapping[pairs[:, 0]] = pairs[:, 1]
    other = alternative.mapping if alternative is not None else spectral_other
    summaries = candidate_summaries(candidates + copies, chosen, alternative, reliable=reliable)
    shelled = bool(chosen.extra.get("shells"))
    return WholeMapChoice(mapping, other, summaries, chosen.origin == "spectral" and pairs is None and not shelled,
                          shelled, chosen.orientation if pairs is None and np.isfinite(chosen.orientation) else None,
                          confidence, doubts)


def warn_landmark_doubts(doubts: dict, pairs: np.ndarray, src: Mesh, tgt: Mesh, fine=None) -> None:
    """A :class:`~meshcorr.errors.LandmarkWarning` naming each doubted pair by its input vertex numbers.

    On coarse copies (``fine``), a landmark is named by the vertex its
    coarse vertex was born from (next to the user's vertex). The warning is
    attributed to the first caller outside meshcorr (the user's line).
    """
    named = []
    for row, why in doubts.items():
        ends = []
        for vertex, mesh, copy in zip(pairs[row], (src, tgt), fine or (None, None)):
            ends.append(int(mesh.kept[vertex]) if copy is None else int(copy.fine.kept[copy.parent[vertex]]))
        named.append(f"{ends[0]} -> {ends[1]} ({why})")
    message = (f"{len(doubts)} of the {len(pairs)} landmark pairs look wrong (source vertex -> target vertex, "
               f"input numbering): {'; '.join(named)}. The map follows the landmarks: check these pairs, or "
               "leave them out.")
    package = str(Path(__file__).resolve().parents[1])  # meshcorr/
    frame, level = sys._getframe(1), 2  # stacklevel 2 is this function's caller
    while frame is not None and str(Path(frame.f_code.co_filename).resolve()).startswith(package):
        frame, level = frame.f_back, level + 1
    warnings.warn(message, LandmarkWarning, stacklevel=level)
